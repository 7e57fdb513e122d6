//! Parameter sensitivity matrices from the contact law (seed 000's S, Eq. 1): rows are contact
//! states or design points, columns the parameters, entries the scaled sensitivities
//! p_k d f / d p_k of the contact force (translational equation of motion) or torque
//! (rotational one). Scaling by the parameter's value makes columns of different units
//! comparable, as seed 000 does before taking norms.

use super::contact_derivatives::{evaluate, Properties, State, PARAMETERS};

/// Which equation of motion a matrix belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Equation {
    /// m dv/dt = sum F: the contact force.
    Translational,
    /// I dw/dt = sum tau: the contact torque.
    Rotational,
}

impl Equation {
    /// Both equations, translational first.
    pub const BOTH: [Equation; 2] = [Equation::Translational, Equation::Rotational];

    /// Name in tables and on the command line (`translational`, `rotational`).
    pub fn name(self) -> &'static str {
        match self {
            Equation::Translational => "translational",
            Equation::Rotational => "rotational",
        }
    }
}

/// How a derivative enters the matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scaling {
    /// p d f / d p: the change of f per relative change of p (dimensionless in p), comparable
    /// across parameters of different units.
    Relative,
    /// d f / d p as it stands: its size depends on p's unit (a modulus in Pa gives tiny
    /// derivatives), so columns compare only for parameters of one unit.
    Absolute,
}

impl Scaling {
    /// Name in tables and on the command line (`relative`, `absolute`).
    pub fn name(self) -> &'static str {
        match self {
            Scaling::Relative => "relative",
            Scaling::Absolute => "absolute",
        }
    }

    /// Parses [`Self::name`]'s output; `None` for anything else.
    pub fn parse(s: &str) -> Option<Scaling> {
        match s {
            "relative" => Some(Scaling::Relative),
            "absolute" => Some(Scaling::Absolute),
            _ => None,
        }
    }
}

/// Levels of the contact state; every combination is one row.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Levels of the normal approach speed, m/s.
    pub v_n: Vec<f64>,
    /// Levels of the tangential slip speed, m/s.
    pub v_t: Vec<f64>,
    /// Levels of the relative rotation rate, rad/s.
    pub omega: Vec<f64>,
    /// Overlaps delta_n = delta_t as fractions of the particle diameter.
    pub overlap_fraction: Vec<f64>,
}

impl Grid {
    /// Seed 000's Level 3 levels: v_n, v_t = 1e-4, 0.01, 1 m/s; w = 0.01, 1, 100 rad/s;
    /// delta = 0.1, 1, 10 % of the diameter: 3^4 = 81 states.
    pub fn seed000() -> Grid {
        Grid {
            v_n: vec![1e-4, 0.01, 1.0],
            v_t: vec![1e-4, 0.01, 1.0],
            omega: vec![0.01, 1.0, 100.0],
            overlap_fraction: vec![0.001, 0.01, 0.1],
        }
    }

    /// The middle state (the geometric centre of seed 000's levels), used for Level 2.
    pub fn centre(&self, diameter: f64) -> State {
        let mid = |v: &[f64]| v[v.len() / 2];
        let d = mid(&self.overlap_fraction) * diameter;
        State {
            v_n: mid(&self.v_n),
            v_t: mid(&self.v_t),
            omega: mid(&self.omega),
            delta_n: d,
            delta_t: d,
        }
    }

    /// Every combination of the levels, for particles of `diameter` (m), in row order: v_n slowest,
    /// then v_t, omega and the overlap fastest.
    pub fn states(&self, diameter: f64) -> Vec<State> {
        let mut out = Vec::new();
        for &v_n in &self.v_n {
            for &v_t in &self.v_t {
                for &omega in &self.omega {
                    for &f in &self.overlap_fraction {
                        out.push(State {
                            v_n,
                            v_t,
                            omega,
                            delta_n: f * diameter,
                            delta_t: f * diameter,
                        });
                    }
                }
            }
        }
        out
    }
}

/// Sensitivities at one state, in [`PARAMETERS`] order.
pub fn row(p: &Properties, s: &State, eq: Equation, scaling: Scaling) -> [f64; 4] {
    let r = evaluate(p, s);
    let d = match eq {
        Equation::Translational => r.d_force,
        Equation::Rotational => r.d_torque,
    };
    let v = p.values();
    match scaling {
        Scaling::Relative => std::array::from_fn(|k| v[k] * d[k]),
        Scaling::Absolute => d,
    }
}

/// Scaled sensitivities p_k d f / d p_k at one state, in [`PARAMETERS`] order.
pub fn scaled_row(p: &Properties, s: &State, eq: Equation) -> [f64; 4] {
    row(p, s, eq, Scaling::Relative)
}

/// The matrix over the grid's states at one parameter point: `[state][parameter]`.
pub fn over_grid(p: &Properties, grid: &Grid, eq: Equation, scaling: Scaling) -> Vec<[f64; 4]> {
    grid.states(2.0 * p.radius)
        .iter()
        .map(|s| row(p, s, eq, scaling))
        .collect()
}

/// The matrix over design points at one state: `[point][parameter]` (seed 000's Level 2, where
/// the state is fixed and the parameters vary with the design).
pub fn over_design(points: &[Properties], s: &State, eq: Equation) -> Vec<[f64; 4]> {
    points.iter().map(|p| scaled_row(p, s, eq)).collect()
}

/// Index of a parameter in [`PARAMETERS`].
pub fn parameter_index(name: &str) -> Option<usize> {
    PARAMETERS.iter().position(|p| *p == name)
}
