//! Single-contact impacts: a sphere against a rigid plane or against another sphere, run until the
//! contact opens. The verification tests of Chung & Ooi (2011) and the wall-impact experiment are
//! built on this.

use super::contact::ModelClass;
use super::material::{Interaction, Materials, Solid};
use super::particles::Particles;
use super::sim::{Scene, Simulation};
use super::timestep::rayleigh_time;
use super::vec3::*;
use super::walls::{Shape, Wall};
use crate::error::{Error, Result};

/// A sphere of an impact test.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Young's modulus, Pa (> 0).
    pub youngs_modulus: f64,
    /// Poisson ratio, dimensionless, in (-1, 0.5].
    pub poisson: f64,
    /// Density, kg/m^3 (> 0).
    pub density: f64,
    /// Radius, m (> 0).
    pub radius: f64,
}

/// A single-contact impact: a sphere against a plane or a second sphere, without gravity, the
/// set-up of the Chung & Ooi (2011) verification tests.
#[derive(Debug, Clone)]
pub struct Impact {
    /// The impacting sphere (particle id 0), which starts just touching the partner (a gap of
    /// 1e-9 r).
    pub body: Body,
    /// The partner: `None` for a rigid plane (z = 0, normal +z); a second sphere otherwise, placed
    /// on the +x side of the first and moving with `partner_velocity`.
    pub partner: Option<Body>,
    /// Young's modulus of the plane (`None`: rigid). The plane's Poisson ratio is the body's.
    pub wall_youngs_modulus: Option<f64>,
    /// Initial velocity of the body, m/s; must approach the partner (-z onto the plane, +x
    /// relative to the partner sphere).
    pub velocity: V3,
    /// Initial angular velocity of the body, rad/s.
    pub spin: V3,
    /// Initial velocity of the partner sphere, m/s (ignored for a plane).
    pub partner_velocity: V3,
    /// Initial angular velocity of the partner sphere, rad/s (ignored for a plane).
    pub partner_spin: V3,
    /// The contact's parameters (usually built by [`ModelClass::interaction`]).
    pub interaction: Interaction,
    /// The effects of the contact law.
    pub class: ModelClass,
    /// Time steps per Hertz contact duration (the elastic t_c of [`hertz_theory`] at the impact
    /// speed), > 0; the wall-impact experiment uses 400, the verification tests 1000. The run
    /// gives up after 20 contact durations.
    pub steps_per_contact: f64,
}

/// What an impact produced, measured step by step while the bodies overlapped.
#[derive(Debug, Clone, Default)]
pub struct ImpactResult {
    /// Largest contact force along the line of centres, N.
    pub max_normal_force: f64,
    /// Largest overlap, m.
    pub max_overlap: f64,
    /// Duration of the overlap, s (a whole number of steps).
    pub contact_time: f64,
    /// Velocity of the body after the contact opened, m/s.
    pub velocity: V3,
    /// Angular velocity of the body after the contact opened, rad/s.
    pub spin: V3,
    /// Velocity of the partner sphere after the contact opened, m/s (zero for a plane).
    pub partner_velocity: V3,
    /// Angular velocity of the partner sphere after the contact opened, rad/s (zero for a plane).
    pub partner_spin: V3,
    /// Steps taken until the contact opened.
    pub steps: u64,
}

/// Hertz elastic impact theory (Timoshenko & Goodier / Chung & Ooi 2011): maximum overlap
/// delta_max = (15 m* v^2 / (16 Y* sqrt(R*)))^(2/5) (m), maximum force
/// F_max = 4/3 Y* sqrt(R*) delta_max^(3/2) (N) and contact duration
/// t_c = 2.87 (m*^2 / (R* Y*^2 v))^(1/5) (s), returned in that order, for effective modulus
/// `y_eff` (Pa), radius `r_eff` (m), mass `m_eff` (kg) and relative normal speed `v` (m/s, > 0).
/// Against a rigid plane R* = r and m* = m.
///
/// ```
/// // Chung & Ooi (2011) test 1: two glass spheres (E = 48 GPa, nu = 0.2, rho = 2800 kg/m^3,
/// // R = 10 mm) head-on at +-10 m/s. Expected: delta_max 274 um, F_max 10.70 kN, t_c 40.3 us.
/// use std::f64::consts::PI;
/// let (e, nu, rho, r) = (48e9, 0.2, 2800.0, 0.01);
/// let y_eff = e / (2.0 * (1.0 - nu * nu)); // two equal solids
/// let m = rho * 4.0 / 3.0 * PI * r * r * r;
/// let (delta, force, t_c) = mbgc_dem::impact::hertz_theory(y_eff, r / 2.0, m / 2.0, 20.0);
/// assert!((delta - 274e-6).abs() < 1e-6, "{delta}");
/// assert!((force - 10.70e3).abs() < 10.0, "{force}");
/// assert!((t_c - 40.3e-6).abs() < 0.1e-6, "{t_c}");
/// ```
pub fn hertz_theory(y_eff: f64, r_eff: f64, m_eff: f64, v: f64) -> (f64, f64, f64) {
    let delta = (15.0 * m_eff * v * v / (16.0 * y_eff * r_eff.sqrt())).powf(0.4);
    let force = 4.0 / 3.0 * y_eff * r_eff.sqrt() * delta.powf(1.5);
    let t_c = 2.87 * (m_eff * m_eff / (r_eff * y_eff * y_eff * v)).powf(0.2);
    (delta, force, t_c)
}

fn mass(b: &Body) -> f64 {
    b.density * 4.0 / 3.0 * std::f64::consts::PI * b.radius.powi(3)
}

/// Runs an impact to the end of contact, with time step t_c / `steps_per_contact`. Errors if the
/// bodies do not approach, a material or interaction is refused, or the contact has not opened
/// after 20 contact durations (a cohesive or overdamped pair that sticks).
pub fn run_impact(imp: &Impact) -> Result<ImpactResult> {
    let b = &imp.body;
    let mut materials = Materials::new();
    let m_body = materials.add(Solid {
        name: "body".into(),
        youngs_modulus: b.youngs_modulus,
        poisson: b.poisson,
    })?;
    // The plane: `wall_youngs_modulus` with the body's Poisson ratio, or rigid (a modulus so
    // large that Y* and G* are the body's alone).
    let m_other = match (&imp.partner, imp.wall_youngs_modulus) {
        (None, Some(e_w)) => materials.add(Solid {
            name: "wall".into(),
            youngs_modulus: e_w,
            poisson: b.poisson,
        })?,
        (None, None) => materials.add(Solid {
            name: "rigid".into(),
            youngs_modulus: 1e40,
            poisson: 0.0,
        })?,
        (Some(p), _) if *p == *b => m_body,
        (Some(p), _) => materials.add(Solid {
            name: "partner".into(),
            youngs_modulus: p.youngs_modulus,
            poisson: p.poisson,
        })?,
    };
    for (x, y) in [(m_body, m_body), (m_body, m_other), (m_other, m_other)] {
        materials.set_interaction(x, y, imp.interaction.clone())?;
    }
    let mut particles = Particles::new();
    let gap = 1e-9 * b.radius;
    let mut walls = Vec::new();
    let (y_eff, r_eff, m_eff, v_rel);
    match &imp.partner {
        None => {
            particles.add([0.0, 0.0, b.radius + gap], b.radius, b.density, m_body)?;
            walls.push(Wall::new(
                "plane",
                Shape::Plane {
                    point: [0.0; 3],
                    normal: [0.0, 0.0, 1.0],
                },
                m_other,
            )?);
            y_eff = materials.pair(m_body, m_other).y_eff;
            r_eff = b.radius;
            m_eff = mass(b);
            v_rel = -imp.velocity[2];
        }
        Some(p) => {
            particles.add([0.0; 3], b.radius, b.density, m_body)?;
            particles.add(
                [b.radius + p.radius + gap, 0.0, 0.0],
                p.radius,
                p.density,
                m_other,
            )?;
            y_eff = materials.pair(m_body, m_other).y_eff;
            r_eff = b.radius * p.radius / (b.radius + p.radius);
            m_eff = mass(b) * mass(p) / (mass(b) + mass(p));
            v_rel = imp.velocity[0] - imp.partner_velocity[0];
        }
    }
    if v_rel <= 0.0 {
        return Err(Error::invalid("the bodies must approach each other"));
    }
    particles.v[0] = imp.velocity;
    particles.w[0] = imp.spin;
    if imp.partner.is_some() {
        particles.v[1] = imp.partner_velocity;
        particles.w[1] = imp.partner_spin;
    }
    let (_, _, t_c) = hertz_theory(y_eff, r_eff, m_eff, v_rel);
    let dt = t_c / imp.steps_per_contact;
    let r_min = b
        .radius
        .min(imp.partner.as_ref().map_or(f64::INFINITY, |p| p.radius));
    let t_r = rayleigh_time(r_min, b.density, b.youngs_modulus, b.poisson);
    let size = 10.0 * (b.radius + imp.partner.as_ref().map_or(0.0, |p| p.radius)) + 1.0;
    let scene = Scene {
        particles,
        walls,
        materials,
        class: imp.class,
        gravity: [0.0; 3],
        dt,
        skin: 0.1 * r_min,
        domain: ([-size; 3], [size; 3]),
        max_dt_fraction: (dt / t_r).max(0.3),
        periodic: [false; 3],
    };
    let mut sim = Simulation::new(scene)?;
    let mut res = ImpactResult::default();
    let mut touched = false;
    let max_steps = (20.0 * imp.steps_per_contact) as u64;
    for _ in 0..max_steps {
        sim.advance();
        let p = &sim.particles;
        let i0 = p.id.iter().position(|&id| id == 0).expect("body");
        let overlap = match &imp.partner {
            None => p.r[i0] - p.x[i0][2],
            Some(_) => {
                let i1 = 1 - i0;
                p.r[i0] + p.r[i1] - norm(sub(p.x[i0], p.x[i1]))
            }
        };
        if overlap > 0.0 {
            touched = true;
            res.contact_time += dt;
            res.max_overlap = res.max_overlap.max(overlap);
            // The contact force along the line of centres: gravity is off, so it is the total.
            let f = p.f[i0];
            let fnorm = match &imp.partner {
                None => f[2],
                Some(_) => -f[0],
            };
            res.max_normal_force = res.max_normal_force.max(fnorm);
        } else if touched {
            res.velocity = p.v[i0];
            res.spin = p.w[i0];
            if imp.partner.is_some() {
                res.partner_velocity = p.v[1 - i0];
                res.partner_spin = p.w[1 - i0];
            }
            res.steps = sim.step;
            return Ok(res);
        }
    }
    Err(Error::invalid(format!(
        "the contact did not end within {max_steps} steps"
    )))
}
