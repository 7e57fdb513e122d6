//! Wall impact (seed 003): one sphere hits a flat wall at a given speed and angle, optionally
//! spinning; responses are the normal and tangential coefficients of restitution of its centre
//! velocity, `cnr = -v_n' / v_n` and `ctr = v_t' / v_t`. Each run costs a few milliseconds, so it
//! can be run inside a Bayesian sampler.

use std::time::Instant;

use super::{
    with_class_parameters, Diagnostics, Experiment, Outcome, ParamSet, RunOptions, E_RANGE,
    NU_RANGE, RHO_RANGE,
};
use crate::error::{Error, Result};
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::impact::{run_impact, Body, Impact};

/// Parameters: E_p, nu_p, rho_p, d50 (sphere diameter, mm), E_w, impact_speed (m/s),
/// impact_angle (degrees from the wall normal, 0-89), spin (rad/s, default 0), and the
/// particle-wall parameters of the model class's effects (`e_pw` for Hertz, `gamma_n_pw` for the
/// power-law dashpots, `mu_pw`, `k_t_pw` for the linear spring, `mu_r_pw` with rolling
/// resistance). The wall has modulus `E_w` and the particle's Poisson ratio.
#[derive(Debug, Clone, Copy, Default)]
pub struct WallImpact {
    /// The effects of the contact law between particle and wall.
    pub class: ModelClass,
}

/// The parameters the wall impact needs whatever the model class.
pub const OWN_PARAMETERS: [&str; 7] = [
    "E_p",
    "nu_p",
    "rho_p",
    "d50",
    "E_w",
    "impact_speed",
    "impact_angle",
];

impl WallImpact {
    fn impact(&self, p: &ParamSet) -> Result<Impact> {
        let d = p.require("d50", 1e-6, 1e4)? * 1e-3;
        let speed = p.require("impact_speed", 1e-6, 1e3)?;
        let angle = p.require("impact_angle", 0.0, 89.0)?.to_radians();
        let e_w = p.require("E_w", E_RANGE.0, E_RANGE.1)?;
        let nu = p.require("nu_p", NU_RANGE.0, NU_RANGE.1)?;
        Ok(Impact {
            body: Body {
                youngs_modulus: p.require("E_p", E_RANGE.0, E_RANGE.1)?,
                poisson: nu,
                density: p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?,
                radius: 0.5 * d,
            },
            partner: None,
            wall_youngs_modulus: Some(e_w),
            velocity: [speed * angle.sin(), 0.0, -speed * angle.cos()],
            spin: [0.0, p.optional("spin", 0.0, -1e6, 1e6)?, 0.0],
            partner_velocity: [0.0; 3],
            partner_spin: [0.0; 3],
            interaction: self.class.interaction(p, Pair::ParticleWall)?,
            class: self.class,
            steps_per_contact: 400.0,
        })
    }
}

/// Largest overlap, relative to the radius, at which Hertz contact still describes the impact;
/// beyond it (soft spheres at high speed) the numbers mean nothing.
pub const MAX_RELATIVE_OVERLAP: f64 = 0.1;

/// Refuses an impact whose outcome is not physical: no contact, an overlap far beyond Hertz's
/// small-strain range, or a sphere leaving with more kinetic energy than it came with (a
/// dissipative contact cannot add energy). The 0.1 % slack is far above velocity Verlet's error
/// at 400 steps per contact (it is symplectic, so the energy error does not accumulate once the
/// bodies part) and far below the gains of a broken run (tangential restitution 1.3-19.6).
fn physical(imp: &Impact, r: &mbgc_dem::impact::ImpactResult) -> Result<()> {
    let radius = imp.body.radius;
    if r.contact_time <= 0.0 {
        return Err(Error::invalid(
            "wall-impact: the sphere never touched the wall (no contact step); not a result",
        ));
    }
    if r.max_overlap > MAX_RELATIVE_OVERLAP * radius {
        return Err(Error::invalid(format!(
            "wall-impact: overlap {:.3e} m is {:.0} % of the radius, beyond the {:.0} % where \
             Hertz contact holds (too soft for this speed: raise E_p or lower impact_speed)",
            r.max_overlap,
            100.0 * r.max_overlap / radius,
            100.0 * MAX_RELATIVE_OVERLAP
        )));
    }
    let mass = imp.body.density * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    let inertia = 0.4 * mass * radius * radius;
    let energy = |v: &[f64; 3], w: &[f64; 3]| {
        let sq = |a: &[f64; 3]| a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        0.5 * mass * sq(v) + 0.5 * inertia * sq(w)
    };
    let (before, after) = (
        energy(&imp.velocity, &imp.spin),
        energy(&r.velocity, &r.spin),
    );
    if !(after.is_finite() && after <= before * (1.0 + 1e-3)) {
        return Err(Error::invalid(format!(
            "wall-impact: kinetic energy {after:.4e} J after the impact exceeds {before:.4e} J \
             before it: not physical (a time step too coarse for this stiffness and speed)"
        )));
    }
    Ok(())
}

impl Experiment for WallImpact {
    fn name(&self) -> &'static str {
        "wall-impact"
    }

    fn parameters(&self) -> Vec<&'static str> {
        with_class_parameters(&OWN_PARAMETERS, &self.class, self.pairs())
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["spin"]
    }

    fn class(&self) -> Option<&ModelClass> {
        Some(&self.class)
    }

    fn pairs(&self) -> &'static [Pair] {
        &[Pair::ParticleWall]
    }

    fn responses(&self) -> Vec<&'static str> {
        vec!["cnr", "ctr"]
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        self.impact(p).map(|_| ())
    }

    fn run(&self, p: &ParamSet, _seed: u64, _opts: &RunOptions) -> Result<Outcome> {
        let t = Instant::now();
        let imp = self.impact(p)?;
        let r = run_impact(&imp)?;
        physical(&imp, &r)?;
        let (vt0, vn0) = (imp.velocity[0], -imp.velocity[2]);
        let cnr = r.velocity[2] / vn0;
        let ctr = if vt0.abs() > 0.0 {
            r.velocity[0] / vt0
        } else {
            f64::NAN
        };
        Ok(Outcome {
            responses: vec![("cnr".into(), cnr), ("ctr".into(), ctr)],
            diagnostics: Diagnostics {
                settled: true,
                steps: r.steps,
                particles: 1,
                wall_time_s: t.elapsed().as_secs_f64(),
                warnings: if vt0 == 0.0 {
                    vec!["normal impact: ctr undefined".into()]
                } else {
                    vec![]
                },
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hertz-Mindlin without rolling resistance: a sphere that does not roll on the wall.
    fn exp() -> WallImpact {
        WallImpact {
            class: ModelClass::parse("hertz,mindlin").unwrap(),
        }
    }

    fn params(angle: f64) -> ParamSet {
        ParamSet::from_pairs(&[
            ("E_p", 380e9),
            ("nu_p", 0.23),
            ("rho_p", 4000.0),
            ("d50", 5.0),
            ("E_w", 1e13),
            ("e_pw", 0.98),
            ("mu_pw", 0.092),
            ("impact_speed", 3.9),
            ("impact_angle", angle),
        ])
    }

    #[test]
    fn reproduces_the_chung_ooi_sliding_branch() {
        for angle in [45.0, 60.0, 75.0] {
            let o = exp()
                .run(&params(angle), 1, &RunOptions::default())
                .unwrap();
            let th = f64::to_radians(angle);
            let want = 1.0 - 0.092 * 1.98 / th.tan();
            let ctr = o.get("ctr").unwrap();
            assert!((ctr - want).abs() / want < 0.02, "{angle}: {ctr} vs {want}");
            assert!((o.get("cnr").unwrap() - 0.98).abs() < 0.01);
        }
    }

    #[test]
    fn the_wall_modulus_and_a_constant_tangential_spring_enter() {
        // A wall of the particle's own modulus halves Y*: contact time x 2^(2/5) (Hertz).
        let mut p = params(0.0);
        p.set("E_w", 380e9);
        let steel = exp().impact(&p).unwrap();
        let rigid = Impact {
            wall_youngs_modulus: None,
            ..steel.clone()
        };
        let (a, b) = (run_impact(&steel).unwrap(), run_impact(&rigid).unwrap());
        let ratio = a.contact_time / b.contact_time;
        assert!((ratio - 2f64.powf(0.4)).abs() < 0.01, "{ratio}");
        // A spring too soft to act within the impact leaves v_t alone; the sliding branch does
        // not depend on the spring.
        let spring = WallImpact {
            class: ModelClass::parse("hertz,linear-spring").unwrap(),
        };
        let mut p = params(20.0);
        p.set("k_t_pw", 1e3);
        let o = spring.run(&p, 1, &RunOptions::default()).unwrap();
        assert!((o.get("ctr").unwrap() - 1.0).abs() < 1e-3);
        let mut p = params(75.0);
        p.set("k_t_pw", 1e7);
        let o = spring.run(&p, 1, &RunOptions::default()).unwrap();
        let want = 1.0 - 0.092 * 1.98 / 75f64.to_radians().tan();
        assert!((o.get("ctr").unwrap() - want).abs() < 0.01 * want);
    }

    #[test]
    fn impossible_parameters_are_refused_naming_them() {
        let mut p = params(30.0);
        p.set("rho_p", -5.0);
        let e = exp().check(&p).unwrap_err().to_string();
        assert!(e.contains("rho_p"), "{e}");
        let mut p = params(30.0);
        p.set("impact_angle", 95.0);
        assert!(exp()
            .check(&p)
            .unwrap_err()
            .to_string()
            .contains("impact_angle"));
        let mut p = params(30.0);
        p.set("k_t_pw", -1.0);
        let spring = WallImpact {
            class: ModelClass::parse("hertz,linear-spring").unwrap(),
        };
        let e = spring.check(&p).unwrap_err().to_string();
        assert!(e.contains("k_t_pw"), "{e}");
        // A missing effect parameter is named with its effect.
        let e = WallImpact::default()
            .check(&params(30.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("mu_r_pw") && e.contains("epsd2"), "{e}");
    }

    #[test]
    fn non_physical_impacts_fail_instead_of_reporting_numbers() {
        // Soft spheres at hundreds of m/s used to report ctr of 1.3-19.6 as done.
        for speed in [100.0, 300.0, 1000.0] {
            let mut p = params(30.0);
            p.set("E_p", 5e6).set("E_w", 5e6).set("impact_speed", speed);
            let e = exp()
                .run(&p, 1, &RunOptions::default())
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("overlap") || e.contains("kinetic energy"),
                "{speed}: {e}"
            );
        }
        // The same sphere at a sensible speed is a result, and within the checks.
        let mut p = params(30.0);
        p.set("E_p", 5e6).set("E_w", 5e6).set("impact_speed", 0.5);
        let o = exp().run(&p, 1, &RunOptions::default()).unwrap();
        assert!((0.0..=1.0).contains(&o.get("cnr").unwrap()));
    }
}
