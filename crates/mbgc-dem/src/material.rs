//! Materials and the per-pair constants of the contact law.
//!
//! Particles and walls each carry a material index. Everything the contact law needs that does not
//! depend on the overlap is computed once per pair of materials, as LIGGGHTS does: effective
//! moduli, the damping factor from the restitution coefficient, friction coefficients and the
//! parameters of optional effects.

use crate::error::{Error, Result};

/// The elastic solid a particle or a wall is made of (the bulk material a user measures is
/// `mbgc::material::Material`).
#[derive(Debug, Clone, PartialEq)]
pub struct Solid {
    /// Label used in error messages (`interaction glass-steel: ...`); not interpreted.
    pub name: String,
    /// Young's modulus Y, Pa; positive and finite. DEM calibrations often soften it (seed 004
    /// samples 5e6..5e8 Pa) since the bulk response barely depends on it while the Rayleigh time
    /// step grows as Y^(-1/2).
    pub youngs_modulus: f64,
    /// Poisson ratio nu, dimensionless, in (-1, 0.5] (the thermodynamic bounds of an isotropic
    /// solid); enters Y*, G* and the Rayleigh time.
    pub poisson: f64,
}

/// What two materials do when they touch.
#[derive(Debug, Clone, PartialEq)]
pub struct Interaction {
    /// Coefficient of restitution e, dimensionless, in [0.05, 1]: the ratio of normal separation
    /// to approach speed of a binary Hertz impact, from which the damping factor beta follows
    /// (LIGGGHTS rejects e <= 0.05, where beta tends to -1 and the dashpot overdamps).
    pub restitution: f64,
    /// Coulomb sliding friction coefficient mu, dimensionless, >= 0: the tangential force is
    /// capped at mu |F_n|.
    pub friction: f64,
    /// Rolling friction coefficient mu_r, dimensionless, >= 0: the rolling torque (EPSD2 or CDT)
    /// is capped at mu_r R* |F_n|.
    pub rolling_friction: f64,
    /// Cohesion energy density k_c, J/m^3, >= 0: simplified JKR pulls with k_c times the area of
    /// the contact circle; 0 for none.
    pub cohesion_energy_density: f64,
    /// Phenomenological damping constant gamma_n of the power-law damped normal models
    /// (Tsuji, Kuwabara-Kono, free exponent), in N s/m^(1+alpha), >= 0; unused by Hertz.
    pub damping_gamma_n: f64,
    /// Exponent alpha of the power-law dashpot gamma_n d^alpha, dimensionless, >= 0 (1/4 Tsuji,
    /// 1/2 Kuwabara-Kono).
    pub damping_alpha: f64,
    /// Constant tangential spring stiffness k_t, N/m (the Cundall-Strack spring of seed 003);
    /// 0 (default) for Mindlin's k_t = 8 G* sqrt(R* d).
    pub tangential_stiffness: f64,
    /// Cap spring plus dashpot at mu max(F_n, 0) instead of LIGGGHTS' cap on the spring alone
    /// (the `strict-coulomb` effect).
    pub strict_coulomb: bool,
}

impl Default for Interaction {
    /// e = 0.5, mu = 0.5, everything optional switched off (no rolling resistance, cohesion,
    /// power-law dashpot or constant tangential stiffness).
    fn default() -> Self {
        Interaction {
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.0,
            cohesion_energy_density: 0.0,
            damping_gamma_n: 0.0,
            damping_alpha: 0.0,
            tangential_stiffness: 0.0,
            strict_coulomb: false,
        }
    }
}

/// The overlap-independent constants of the contact law for one pair of materials, computed once
/// by [`PairConstants::new`] (as LIGGGHTS' global properties) and looked up per contact by
/// [`Materials::pair`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PairConstants {
    /// Effective Young's modulus Y*, Pa: 1/Y* = (1 - nu_a^2)/Y_a + (1 - nu_b^2)/Y_b.
    pub y_eff: f64,
    /// Effective shear modulus G*, Pa: 1/G* = 2(2 - nu_a)(1 + nu_a)/Y_a + 2(2 - nu_b)(1 + nu_b)/Y_b
    /// (LIGGGHTS' form).
    pub g_eff: f64,
    /// Damping factor beta = ln e / sqrt(ln^2 e + pi^2), dimensionless, in (-1, 0]; 0 for an
    /// elastic contact (e = 1).
    pub beta: f64,
    /// Damping factor giving restitution e when the normal force is kept from turning
    /// attractive (`limit-force`); see [`beta_for_restitution_limited`].
    pub beta_limited: f64,
    /// sqrt(2 Y*), Pa^(1/2): the dashpots are -2 sqrt(5/6) beta sqrt(S m*) with
    /// S = 2 Y* sqrt(R* d) (normal) or 8 G* sqrt(R* d) (tangential), so the square root of the
    /// modulus part is taken once per pair.
    pub sqrt_2y: f64,
    /// sqrt(8 G*), Pa^(1/2): the tangential counterpart of [`PairConstants::sqrt_2y`].
    pub sqrt_8g: f64,
    /// Coulomb friction coefficient mu, dimensionless ([`Interaction::friction`]).
    pub friction: f64,
    /// Rolling friction coefficient mu_r, dimensionless ([`Interaction::rolling_friction`]).
    pub rolling_friction: f64,
    /// Cohesion energy density, J/m^3 ([`Interaction::cohesion_energy_density`]).
    pub cohesion_energy_density: f64,
    /// Power-law dashpot constant gamma_n, N s/m^(1+alpha) ([`Interaction::damping_gamma_n`]).
    pub damping_gamma_n: f64,
    /// Power-law dashpot exponent alpha, dimensionless ([`Interaction::damping_alpha`]).
    pub damping_alpha: f64,
    /// Constant tangential stiffness k_t, N/m: when > 0 it replaces Mindlin's
    /// 8 G* sqrt(R* d) in the tangential spring and the EPSD2 rolling stiffness; 0 for Mindlin's.
    pub k_t_fixed: f64,
    /// Whether spring plus dashpot are capped at mu max(F_n, 0)
    /// ([`Interaction::strict_coulomb`]).
    pub strict_coulomb: bool,
}

impl PairConstants {
    /// The constants of solids `a` and `b` touching with interaction `i`. The `limit-force`
    /// damping factor is left NaN until [`Materials::prepare_limit_force`] solves it.
    pub fn new(a: &Solid, b: &Solid, i: &Interaction) -> Self {
        let y_eff = 1.0
            / ((1.0 - a.poisson * a.poisson) / a.youngs_modulus
                + (1.0 - b.poisson * b.poisson) / b.youngs_modulus);
        let g_eff = 1.0
            / (2.0 * (2.0 - a.poisson) * (1.0 + a.poisson) / a.youngs_modulus
                + 2.0 * (2.0 - b.poisson) * (1.0 + b.poisson) / b.youngs_modulus);
        let ln_e = i.restitution.ln();
        let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI * std::f64::consts::PI).sqrt();
        PairConstants {
            y_eff,
            g_eff,
            beta,
            // Solved on demand (Materials::prepare_limit_force): it takes a few milliseconds.
            beta_limited: f64::NAN,
            sqrt_2y: (2.0 * y_eff).sqrt(),
            sqrt_8g: (8.0 * g_eff).sqrt(),
            friction: i.friction,
            rolling_friction: i.rolling_friction,
            cohesion_energy_density: i.cohesion_energy_density,
            damping_gamma_n: i.damping_gamma_n,
            damping_alpha: i.damping_alpha,
            k_t_fixed: i.tangential_stiffness,
            strict_coulomb: i.strict_coulomb,
        }
    }
}

/// All materials of a scene and the interaction of every pair.
#[derive(Debug, Clone, Default)]
pub struct Materials {
    /// The solids, indexed by the material index that particles and walls carry.
    pub materials: Vec<Solid>,
    interactions: Vec<Option<Interaction>>,
    table: Vec<PairConstants>,
}

impl Materials {
    /// No materials yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a material and returns its index; refuses a modulus that is not positive and finite
    /// or a Poisson ratio outside (-1, 0.5]. Its interactions are undefined until set.
    pub fn add(&mut self, m: Solid) -> Result<u16> {
        if !(m.youngs_modulus.is_finite() && m.youngs_modulus > 0.0) {
            return Err(Error::invalid(format!(
                "material {}: Young's modulus must be positive and finite, found {}",
                m.name, m.youngs_modulus
            )));
        }
        if !(m.poisson > -1.0 && m.poisson < 0.5 + 1e-12) {
            return Err(Error::invalid(format!(
                "material {}: Poisson ratio must lie in (-1, 0.5], found {}",
                m.name, m.poisson
            )));
        }
        let n = self.materials.len();
        self.materials.push(m);
        let mut inter = vec![None; (n + 1) * (n + 1)];
        for a in 0..n {
            for b in 0..n {
                inter[a * (n + 1) + b] = self.interactions[a * n + b].clone();
            }
        }
        self.interactions = inter;
        self.table = vec![PairConstants::default(); (n + 1) * (n + 1)];
        self.rebuild();
        Ok(n as u16)
    }

    /// Sets the interaction of materials a and b (symmetric); refuses a restitution outside
    /// [0.05, 1] and a negative or non-finite friction, rolling friction, cohesion energy
    /// density, dashpot constant, exponent or tangential stiffness.
    pub fn set_interaction(&mut self, a: u16, b: u16, i: Interaction) -> Result<()> {
        let n = self.materials.len();
        let (a, b) = (a as usize, b as usize);
        if a >= n || b >= n {
            return Err(Error::invalid(format!("no material {} or {b}", a.max(b))));
        }
        let name = format!("{}-{}", self.materials[a].name, self.materials[b].name);
        check_range(&name, "restitution", i.restitution, 0.05, 1.0)?;
        check_range(&name, "friction", i.friction, 0.0, f64::MAX)?;
        check_range(&name, "rolling friction", i.rolling_friction, 0.0, f64::MAX)?;
        check_range(
            &name,
            "cohesion energy density",
            i.cohesion_energy_density,
            0.0,
            f64::MAX,
        )?;
        check_range(&name, "damping gamma_n", i.damping_gamma_n, 0.0, f64::MAX)?;
        check_range(&name, "damping exponent", i.damping_alpha, 0.0, f64::MAX)?;
        check_range(
            &name,
            "tangential stiffness",
            i.tangential_stiffness,
            0.0,
            f64::MAX,
        )?;
        self.interactions[a * n + b] = Some(i.clone());
        self.interactions[b * n + a] = Some(i);
        self.rebuild();
        Ok(())
    }

    fn rebuild(&mut self) {
        let n = self.materials.len();
        for a in 0..n {
            for b in 0..n {
                if let Some(i) = &self.interactions[a * n + b] {
                    self.table[a * n + b] =
                        PairConstants::new(&self.materials[a], &self.materials[b], i);
                }
            }
        }
    }

    /// Solves the damping factors used by `limit-force` for every defined pair (a bisection on an
    /// impact integration, a few milliseconds each; [`crate::Simulation::new`] calls it when the
    /// model class asks for `limit-force`).
    pub fn prepare_limit_force(&mut self) {
        let n = self.materials.len();
        for k in 0..n * n {
            if let Some(i) = &self.interactions[k] {
                if self.table[k].beta_limited.is_nan() {
                    self.table[k].beta_limited = beta_for_restitution_limited(i.restitution);
                }
            }
        }
    }

    /// Checks that every pair of materials in `pairs` has an interaction: a pair that can meet
    /// without one would have no contact law. Indices must be below [`Materials::count`].
    pub fn check_complete(&self, pairs: impl Iterator<Item = (u16, u16)>) -> Result<()> {
        let n = self.materials.len();
        for (a, b) in pairs {
            if self.interactions[a as usize * n + b as usize].is_none() {
                return Err(Error::invalid(format!(
                    "no interaction defined between materials {} and {}",
                    self.materials[a as usize].name, self.materials[b as usize].name
                )));
            }
        }
        Ok(())
    }

    /// Number of materials.
    pub fn count(&self) -> usize {
        self.materials.len()
    }

    /// Whether every pair's tangential spring is Mindlin's, not strict and not of constant
    /// stiffness: the pairs the four-lane kernel computes (`crate::contact::lanes`).
    pub fn lanes_ready(&self) -> bool {
        self.table
            .iter()
            .all(|p| !p.strict_coulomb && p.k_t_fixed <= 0.0)
    }

    /// The contact-law constants of materials a and b (the kernel's lookup; zeros for a pair
    /// without an interaction). Panics if an index is out of range.
    #[inline(always)]
    pub fn pair(&self, a: u16, b: u16) -> &PairConstants {
        &self.table[a as usize * self.materials.len() + b as usize]
    }

    /// The interaction of materials a and b, if one was set.
    pub fn interaction(&self, a: u16, b: u16) -> Option<&Interaction> {
        self.interactions[a as usize * self.materials.len() + b as usize].as_ref()
    }
}

fn check_range(pair: &str, what: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "interaction {pair}: {what} must lie in [{lo}, {}], found {v}",
            if hi == f64::MAX {
                "inf".to_string()
            } else {
                hi.to_string()
            }
        )))
    }
}

/// Restitution of a Hertz impact with LIGGGHTS' damping for damping factor `beta`, with the
/// normal force clamped at zero (`limited`) or allowed to turn attractive near separation.
///
/// In units where the elastic force is X^(3/2), the impact obeys X'' = -X^(3/2) - z X^(1/4) X'
/// with z = -sqrt(5) beta, X(0) = 0, X'(0) = 1, whatever the material, size and speed; so the
/// restitution depends on beta alone and one integration tells it.
pub fn hertz_restitution(beta: f64, limited: bool) -> f64 {
    let z = -(5.0f64).sqrt() * beta;
    let acc = |x: f64, v: f64| -> f64 {
        let xp = x.max(0.0);
        -(xp * xp.sqrt()) - z * xp.sqrt().sqrt() * v
    };
    let h = 2e-4;
    let (mut x, mut v) = (0.0f64, 1.0f64);
    for _ in 0..200_000 {
        let (k1x, k1v) = (v, acc(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v));
        let xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if limited && vn < 0.0 && acc(xn, vn) >= 0.0 {
            // The force would turn attractive: the bodies part with this speed.
            return -vn;
        }
        if xn <= 0.0 && vn < 0.0 {
            // Interpolate the speed at X = 0.
            let f = x / (x - xn);
            return -(v + f * (vn - v));
        }
        x = xn;
        v = vn;
    }
    0.0
}

/// The damping factor that gives restitution `e` with the normal force clamped at zero, by
/// bisection on [`hertz_restitution`]. Clamping removes the attraction at the end of the contact,
/// so the same beta would give a larger restitution than LIGGGHTS' unclamped law.
pub fn beta_for_restitution_limited(e: f64) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (-1.0f64, 0.0f64); // restitution falls as beta goes down
    while hertz_restitution(lo, true) > e && lo > -1e3 {
        lo *= 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if hertz_restitution(mid, true) > e {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liggghts_damping_gives_the_input_restitution_and_the_limited_one_is_solved() {
        for e in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let ln_e = f64::ln(e);
            let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt();
            let free = hertz_restitution(beta, false);
            assert!(
                (free - e).abs() < 0.003,
                "e {e}: unclamped law gives {free}"
            );
            let clamped = hertz_restitution(beta, true);
            assert!(
                clamped > e + 1e-3,
                "clamping must raise the restitution: {clamped}"
            );
            let b = beta_for_restitution_limited(e);
            assert!((hertz_restitution(b, true) - e).abs() < 1e-6);
        }
    }
}
