//! The contact force and torque of mbgc's default law (Hertz with LIGGGHTS' restitution
//! dashpot, Mindlin's history spring with Coulomb cap, EPSD2 rolling resistance) between two
//! equal spheres in a given contact state, and their analytic derivatives with respect to the
//! four parameters seed 000 studies: Young's modulus E, restitution e, sliding friction mu_s and
//! rolling friction mu_r. This is seed 000's Eqs. (21)-(24), written for the law mbgc runs.
//!
//! The state is seed 000's Level 3 input: approach speed v_n, tangential slip speed v_t,
//! relative rotation rate w, overlap delta_n and tangential spring displacement delta_t (the
//! paper sets delta_t = delta_n). EPSD2's rolling spring needs the accumulated rolling rotation,
//! which the paper's inputs do not give; it is taken as delta_t / R* (the rotation that rolls the
//! contact point over delta_t). EPSD2 has no rolling dashpot, so w enters no term: its levels
//! only repeat rows.
//!
//! Translational response: the magnitude of the contact force on a particle,
//! |F| = sqrt(F_n^2 + F_t^2). Rotational response: the magnitude of the contact torque, with the
//! tangential force's torque c F_t (lever arm c = r - delta/2) and the rolling torque M taken to
//! act about the same axis in the same sense, |tau| = c F_t + M.

use std::f64::consts::PI;

use mbgc_dem::contact::hertz::SQRT_5_6;

/// The parameters differentiated, in the order of every derivative array.
pub const PARAMETERS: [&str; 4] = ["E_p", "e_pp", "mu_pp", "mu_r_pp"];

/// Particle properties and the four parameters.
#[derive(Debug, Clone, Copy)]
pub struct Properties {
    /// Particle Young's modulus E, Pa (> 0).
    pub youngs_modulus: f64,
    /// Poisson ratio nu of the particles, in (-1, 0.5).
    pub poisson: f64,
    /// Particle-particle coefficient of restitution e, in (0, 1]; sets the dashpot through beta(e).
    pub restitution: f64,
    /// Sliding friction coefficient mu_s (>= 0): the Coulomb cap of the tangential force.
    pub mu_s: f64,
    /// Rolling friction coefficient mu_r (>= 0): the cap mu_r R* F_n of the EPSD2 torque.
    pub mu_r: f64,
    /// Particle radius, m.
    pub radius: f64,
    /// Particle density, kg/m^3.
    pub density: f64,
}

/// Names of the properties a table or the command line gives: the four [`PARAMETERS`] and
/// `nu_p`, `rho_p`, `d50` (mm).
pub const PROPERTY_NAMES: [&str; 7] = ["E_p", "nu_p", "e_pp", "mu_pp", "mu_r_pp", "rho_p", "d50"];

impl Properties {
    /// From named values (`d50` in mm); the error names the missing one and `source`.
    pub fn from_named(
        get: impl Fn(&str) -> Option<f64>,
        source: &str,
    ) -> crate::error::Result<Properties> {
        let v = |n: &str| {
            get(n).ok_or_else(|| {
                crate::error::Error::invalid(format!(
                    "{source}: no value of {n}; the contact-law sensitivities need {} (a column \
                     or --set {n}=...)",
                    PROPERTY_NAMES.join(", ")
                ))
            })
        };
        let p = Properties {
            youngs_modulus: v("E_p")?,
            poisson: v("nu_p")?,
            restitution: v("e_pp")?,
            mu_s: v("mu_pp")?,
            mu_r: v("mu_r_pp")?,
            radius: 0.5e-3 * v("d50")?,
            density: v("rho_p")?,
        };
        // nu = -1 makes the effective modulus E / (2 (1 - nu^2)) infinite.
        let ok = p.youngs_modulus > 0.0
            && p.poisson > -1.0
            && p.poisson < 0.5
            && p.restitution > 0.0
            && p.restitution <= 1.0
            && p.mu_s >= 0.0
            && p.mu_r >= 0.0
            && p.radius > 0.0
            && p.density > 0.0;
        if !ok {
            return Err(crate::error::Error::invalid(format!(
                "{source}: properties out of range ({p:?}); expected E_p > 0, -1 < nu_p < 0.5, \
                 0 < e_pp <= 1, mu_pp, mu_r_pp >= 0, d50 > 0, rho_p > 0"
            )));
        }
        Ok(p)
    }

    /// The four parameters in [`PARAMETERS`] order.
    pub fn values(&self) -> [f64; 4] {
        [self.youngs_modulus, self.restitution, self.mu_s, self.mu_r]
    }

    /// A copy with parameter `k` (index into [`PARAMETERS`]; 3 or more: mu_r) set to `v`.
    pub fn with(&self, k: usize, v: f64) -> Properties {
        let mut p = *self;
        match k {
            0 => p.youngs_modulus = v,
            1 => p.restitution = v,
            2 => p.mu_s = v,
            _ => p.mu_r = v,
        }
        p
    }
}

/// One contact state (SI units; speeds and overlaps positive).
#[derive(Debug, Clone, Copy)]
pub struct State {
    /// Normal approach speed, m/s.
    pub v_n: f64,
    /// Tangential slip speed at the contact point, m/s.
    pub v_t: f64,
    /// Relative rotation rate, rad/s; EPSD2 has no rolling dashpot, so it enters no term.
    pub omega: f64,
    /// Normal overlap, m; positive and small against the radius.
    pub delta_n: f64,
    /// Tangential spring displacement, m (seed 000 sets it equal to delta_n).
    pub delta_t: f64,
}

/// Force and torque magnitudes and their derivatives by the [`PARAMETERS`].
#[derive(Debug, Clone, Copy)]
pub struct Response {
    /// Normal force, N: Hertz spring plus restitution dashpot.
    pub f_n: f64,
    /// Tangential force magnitude, N: Mindlin spring plus dashpot, or mu_s F_n when sliding.
    pub f_t: f64,
    /// EPSD2 rolling torque, N m.
    pub rolling: f64,
    /// Magnitude of the contact force, sqrt(F_n^2 + F_t^2), N.
    pub force: f64,
    /// Contact torque magnitude c F_t + M_r, N m, with lever arm c = r - delta_n / 2.
    pub torque: f64,
    /// Derivatives of `force` by E (N/Pa), e (N), mu_s (N) and mu_r (N), in [`PARAMETERS`] order.
    pub d_force: [f64; 4],
    /// Derivatives of `torque` by the four [`PARAMETERS`], in N m per unit of each.
    pub d_torque: [f64; 4],
    /// The Coulomb cap limits the tangential force (gross sliding).
    pub sliding: bool,
    /// The rolling torque sits at its cap mu_r R* F_n.
    pub rolling_at_cap: bool,
}

/// |beta(e)| = -ln e / sqrt(ln^2 e + pi^2) and its derivative by e.
fn damping_factor(e: f64) -> (f64, f64) {
    let l = e.ln();
    let q = l * l + PI * PI;
    let beta = -l / q.sqrt();
    // d beta / d e for beta = ln e / sqrt(q) is pi^2 / (e q^(3/2)); |beta| is its negative.
    (beta, -PI * PI / (e * q * q.sqrt()))
}

/// The law and its derivatives at one state. Derivatives are one-sided at a cap's kink (the
/// capped branch is taken when the spring reaches the cap exactly).
pub fn evaluate(p: &Properties, s: &State) -> Response {
    let nu = p.poisson;
    let e_mod = p.youngs_modulus;
    // Two equal particles.
    let y_eff = e_mod / (2.0 * (1.0 - nu * nu));
    let g_eff = e_mod / (4.0 * (2.0 - nu) * (1.0 + nu));
    let r_eff = 0.5 * p.radius;
    let mass = p.density * 4.0 / 3.0 * PI * p.radius.powi(3);
    let m_eff = 0.5 * mass;
    let sqrt_rd = (r_eff * s.delta_n).sqrt();
    let (b, db_de) = damping_factor(p.restitution);

    // Normal: k_n d + gamma_n v_n, gamma_n = 2 sqrt(5/6) |beta| sqrt(2 Y* sqrt(R* d) m*).
    let elastic = 4.0 / 3.0 * y_eff * sqrt_rd * s.delta_n;
    let root_n = (2.0 * y_eff * sqrt_rd * m_eff).sqrt();
    let damp_n = 2.0 * SQRT_5_6 * b * root_n * s.v_n;
    let f_n = elastic + damp_n;
    // Elastic part is linear in E, the dashpot goes as sqrt(E).
    let dfn = [
        elastic / e_mod + 0.5 * damp_n / e_mod,
        2.0 * SQRT_5_6 * db_de * root_n * s.v_n,
        0.0,
        0.0,
    ];

    // Tangential: spring k_t d_t capped at mu_s F_n; below the cap the dashpot adds.
    let k_t = 8.0 * g_eff * sqrt_rd;
    let spring = k_t * s.delta_t;
    let cap = p.mu_s * f_n.abs();
    let sliding = spring >= cap;
    let (f_t, dft) = if sliding {
        (cap, [p.mu_s * dfn[0], p.mu_s * dfn[1], f_n.abs(), 0.0])
    } else {
        let root_t = (k_t * m_eff).sqrt();
        let damp_t = 2.0 * SQRT_5_6 * b * root_t * s.v_t;
        (
            spring + damp_t,
            [
                spring / e_mod + 0.5 * damp_t / e_mod,
                2.0 * SQRT_5_6 * db_de * root_t * s.v_t,
                0.0,
                0.0,
            ],
        )
    };

    // Rolling: EPSD2 spring k_r phi, k_r = k_t R*^2, phi = d_t / R*, capped at mu_r R* F_n.
    let spring_r = k_t * r_eff * s.delta_t;
    let cap_r = p.mu_r * r_eff * f_n.abs();
    let rolling_at_cap = spring_r >= cap_r;
    let (m_r, dm) = if rolling_at_cap {
        (
            cap_r,
            [
                p.mu_r * r_eff * dfn[0],
                p.mu_r * r_eff * dfn[1],
                0.0,
                r_eff * f_n.abs(),
            ],
        )
    } else {
        (spring_r, [spring_r / e_mod, 0.0, 0.0, 0.0])
    };

    let force = f_n.hypot(f_t);
    let lever = p.radius - 0.5 * s.delta_n;
    let torque = lever * f_t + m_r;
    let mut d_force = [0.0; 4];
    let mut d_torque = [0.0; 4];
    for k in 0..4 {
        d_force[k] = if force > 0.0 {
            (f_n * dfn[k] + f_t * dft[k]) / force
        } else {
            0.0
        };
        d_torque[k] = lever * dft[k] + dm[k];
    }
    Response {
        f_n,
        f_t,
        rolling: m_r,
        force,
        torque,
        d_force,
        d_torque,
        sliding,
        rolling_at_cap,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mbgc_dem::contact::{
        epsd2::Epsd2, hertz::Hertz, mindlin::HistorySpring, none::NoCohesion, Contact, ContactLaw,
        History, Law,
    };
    use mbgc_dem::material::{Interaction, PairConstants, Solid};
    use mbgc_dem::vec3::*;

    fn props() -> Properties {
        Properties {
            youngs_modulus: 2e7,
            poisson: 0.3,
            restitution: 0.45,
            mu_s: 0.25,
            mu_r: 0.25,
            radius: 1e-3,
            density: 2500.0,
        }
    }

    fn states() -> Vec<State> {
        let mut v = Vec::new();
        for vn in [1e-4, 0.01, 1.0] {
            for vt in [1e-4, 0.01, 1.0] {
                for d in [2e-6, 2e-5, 2e-4] {
                    for dt_ratio in [1.0, 0.05] {
                        v.push(State {
                            v_n: vn,
                            v_t: vt,
                            omega: 1.0,
                            delta_n: d,
                            delta_t: d * dt_ratio,
                        });
                    }
                }
            }
        }
        v
    }

    /// The force and torque agree with mbgc's own contact law evaluated on the same state.
    #[test]
    fn force_and_torque_are_the_engines() {
        for mu_s in [0.05, 0.5, 2.0] {
            for mu_r in [0.05, 0.45, 3.0] {
                let p = Properties {
                    mu_s,
                    mu_r,
                    ..props()
                };
                let mat = Solid {
                    name: "g".into(),
                    youngs_modulus: p.youngs_modulus,
                    poisson: p.poisson,
                };
                let inter = Interaction {
                    restitution: p.restitution,
                    friction: mu_s,
                    rolling_friction: mu_r,
                    ..Interaction::default()
                };
                let pc = PairConstants::new(&mat, &mat, &inter);
                let law = Law {
                    normal: Hertz,
                    tangential: HistorySpring,
                    rolling: Epsd2,
                    cohesion: NoCohesion,
                    limit_force: false,
                };
                let mass = p.density * 4.0 / 3.0 * PI * p.radius.powi(3);
                for s in states() {
                    let r_eff = 0.5 * p.radius;
                    let lever = p.radius - 0.5 * s.delta_n;
                    // n = +z from j to i; i approaches j (moves along -z) and slips along +x.
                    let c = Contact::new(
                        [0.0, 0.0, 1.0],
                        s.delta_n,
                        r_eff,
                        0.5 * mass,
                        [s.v_t, 0.0, -s.v_n],
                        [0.0; 3],
                        [0.0; 3],
                        lever,
                        lever,
                        0.0,
                    );
                    let k_t = 8.0 * pc.g_eff * (r_eff * s.delta_n).sqrt();
                    let mut h = History {
                        shear: [s.delta_t, 0.0, 0.0],
                        rolling: [0.0, k_t * r_eff * s.delta_t, 0.0],
                    };
                    // dt = 0: the springs keep the displacements given.
                    let out = law.force(&c, &pc, &mut h, 0.0);
                    let ft_engine = norm2(sub(out.force, scale([0.0, 0.0, 1.0], out.f_n))).sqrt();
                    let m_engine = norm2(h.rolling).sqrt();
                    let a = evaluate(&p, &s);
                    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * y.abs().max(1e-30);
                    assert!(close(a.f_n, out.f_n), "F_n {} vs {}", a.f_n, out.f_n);
                    assert!(
                        close(a.f_t, ft_engine),
                        "F_t {} vs {ft_engine} at {s:?}",
                        a.f_t
                    );
                    assert!(close(a.rolling, m_engine), "M {} vs {m_engine}", a.rolling);
                    let tq = norm2(cross(
                        [0.0, 0.0, 1.0],
                        sub(out.force, scale([0.0, 0.0, 1.0], out.f_n)),
                    ))
                    .sqrt()
                        * lever;
                    assert!(close(a.torque, tq + m_engine));
                }
            }
        }
    }

    /// The analytic derivatives agree with central differences away from the caps' kinks.
    #[test]
    fn derivatives_match_central_differences() {
        let p = props();
        let mut checked = 0;
        for s in states() {
            let base = evaluate(&p, &s);
            for (k, &v) in p.values().iter().enumerate() {
                let h = 1e-6 * v;
                let up = evaluate(&p.with(k, v + h), &s);
                let dn = evaluate(&p.with(k, v - h), &s);
                if up.sliding != dn.sliding || up.rolling_at_cap != dn.rolling_at_cap {
                    continue;
                }
                for (num, ana) in [
                    ((up.force - dn.force) / (2.0 * h), base.d_force[k]),
                    ((up.torque - dn.torque) / (2.0 * h), base.d_torque[k]),
                ] {
                    let scale = ana.abs().max(1e-12 * base.force.max(1e-30) / v);
                    assert!(
                        (num - ana).abs() <= 1e-5 * scale,
                        "k {k}: {num} vs {ana} at {s:?}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 300, "{checked}");
    }
}
