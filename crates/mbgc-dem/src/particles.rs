//! Particles in structure-of-arrays form.
//!
//! Every per-particle quantity is its own array, indexed by the particle's current position in
//! memory. The neighbour list reorders the arrays by cell at each rebuild, so a particle's index
//! changes during a run; [`Particles::id`] is the stable name.
//!
//! A particle can be *driven* ([`Particles::drive`]): its motion is prescribed by the caller, not
//! by forces. Its inverse mass and inverse inertia are zero, so the integrator's kicks leave its
//! velocity and angular velocity as the caller set them, while the drift still moves it by its
//! velocity. Its mass stays real: a contact with a driven particle uses the effective mass
//! m_i m_j / (m_i + m_j), as LIGGGHTS does for particles under `fix freeze` or `fix move`. Glued
//! layers of driven particles make rough floors (velocity zero) and rough lids (velocity set by
//! the caller between runs).

use super::vec3::V3;
use crate::error::{Error, Result};

/// Spheres: positions, velocities, forces and constant properties, one array per quantity.
///
/// All arrays have the same length. Add particles through [`Particles::add`], which keeps the
/// mass and inverse inertia consistent with radius and density; velocities may be set directly.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Centre positions, m.
    pub x: Vec<V3>,
    /// Translational velocities, m/s.
    pub v: Vec<V3>,
    /// Angular velocities, rad/s.
    pub w: Vec<V3>,
    /// Total forces of the last force evaluation, N: gravity plus contacts for free particles,
    /// contacts only for driven ones (so the sum over a lid of driven particles is the force the
    /// material exerts on the lid, with nothing to subtract).
    pub f: Vec<V3>,
    /// Total torques about the centres of the last force evaluation, N m.
    pub t: Vec<V3>,
    /// Radii, m (> 0). Read them; they are set by [`Particles::add`] only: the neighbour
    /// list's cutoff and the near list's effective radii are made from them and kept.
    pub r: Vec<f64>,
    /// Masses, kg: density times sphere volume. Set by [`Particles::add`] only, as the radii
    /// (the near list keeps the pairs' effective masses).
    pub m: Vec<f64>,
    /// Inverse masses, 1/kg, kept so the integrator multiplies instead of dividing; zero for a
    /// driven particle (set through [`Particles::drive`] and [`Particles::release`], which keep
    /// it consistent with `driven`).
    pub inv_m: Vec<f64>,
    /// Inverse moments of inertia, 1/(kg m^2): 1 / (0.4 m r^2), a solid sphere; zero for a driven
    /// particle.
    pub inv_i: Vec<f64>,
    /// Material index into [`crate::Materials`].
    pub material: Vec<u16>,
    /// Stable identifier: the insertion order, unchanged by the spatial sorting.
    pub id: Vec<u32>,
    /// Whether the particle's motion is prescribed ([`Particles::drive`]); read it, change it
    /// only through `drive` and `release`.
    pub driven: Vec<bool>,
}

impl Particles {
    /// No particles.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a sphere at rest at centre `x` (m) with `radius` (m) and `density` (kg/m^3), both
    /// positive and finite, made of `material`; returns its id. The material index is checked
    /// later, by [`crate::Simulation::new`].
    pub fn add(&mut self, x: V3, radius: f64, density: f64, material: u16) -> Result<u32> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::invalid(format!(
                "particle radius must be positive, found {radius}"
            )));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(Error::invalid(format!(
                "particle density must be positive, found {density}"
            )));
        }
        if !x.iter().all(|c| c.is_finite()) {
            return Err(Error::invalid(format!(
                "particle position must be finite, found {x:?}"
            )));
        }
        let m = density * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
        let id = self.x.len() as u32;
        self.x.push(x);
        self.v.push([0.0; 3]);
        self.w.push([0.0; 3]);
        self.f.push([0.0; 3]);
        self.t.push([0.0; 3]);
        self.r.push(radius);
        self.m.push(m);
        self.inv_m.push(1.0 / m);
        self.inv_i.push(1.0 / (0.4 * m * radius * radius));
        self.material.push(material);
        self.id.push(id);
        self.driven.push(false);
        Ok(id)
    }

    /// Makes particle `i` (current index) driven: forces and torques no longer change its
    /// velocity `v[i]` and angular velocity `w[i]`, which keep whatever the caller sets, and it
    /// drifts by `v[i]` every step. Contact forces and torques on it are still accumulated in
    /// `f[i]` and `t[i]` (contacts only, without gravity). Contacts between two driven particles
    /// are skipped: a glued layer exerts no force on itself.
    ///
    /// In a [`crate::Simulation`], indices change at every neighbour-list rebuild: find the
    /// particle by id ([`Particles::index_of_ids`]) before each call.
    pub fn drive(&mut self, i: usize) {
        self.driven[i] = true;
        self.inv_m[i] = 0.0;
        self.inv_i[i] = 0.0;
    }

    /// Gives a driven particle back to the forces (the inverse of [`Particles::drive`]); it
    /// keeps its current velocity. Its force `f[i]` lacks gravity until the next step.
    pub fn release(&mut self, i: usize) {
        let (m, r) = (self.m[i], self.r[i]);
        self.driven[i] = false;
        self.inv_m[i] = 1.0 / m;
        self.inv_i[i] = 1.0 / (0.4 * m * r * r);
    }

    /// Number of driven particles.
    pub fn driven_count(&self) -> usize {
        self.driven.iter().filter(|&&d| d).count()
    }

    /// Density of particle `i` (current index), kg/m^3, recovered from its mass and radius.
    pub fn density(&self, i: usize) -> f64 {
        self.m[i] / (4.0 / 3.0 * std::f64::consts::PI * self.r[i].powi(3))
    }

    /// Reorders every array so that new index k holds old particle `order[k]`. The scratch
    /// buffers keep their capacity, so a reorder in the time-step loop does not allocate.
    pub fn permute(&mut self, order: &[u32], s: &mut PermuteScratch) {
        fn apply<T: Copy>(v: &mut Vec<T>, scratch: &mut Vec<T>, order: &[u32]) {
            scratch.clear();
            scratch.extend(order.iter().map(|&k| v[k as usize]));
            std::mem::swap(v, scratch);
        }
        apply(&mut self.x, &mut s.v3, order);
        apply(&mut self.v, &mut s.v3, order);
        apply(&mut self.w, &mut s.v3, order);
        apply(&mut self.f, &mut s.v3, order);
        apply(&mut self.t, &mut s.v3, order);
        apply(&mut self.r, &mut s.f, order);
        apply(&mut self.m, &mut s.f, order);
        apply(&mut self.inv_m, &mut s.f, order);
        apply(&mut self.inv_i, &mut s.f, order);
        apply(&mut self.material, &mut s.u16, order);
        apply(&mut self.id, &mut s.u32, order);
        apply(&mut self.driven, &mut s.flag, order);
    }

    /// Keeps the particles whose `keep` flag (one per particle, current order) is set, in order.
    /// Ids are not renumbered.
    pub fn retain(&mut self, keep: &[bool]) {
        fn apply<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
            let mut k = keep.iter();
            v.retain(|_| *k.next().expect("one flag per particle"));
        }
        apply(&mut self.x, keep);
        apply(&mut self.v, keep);
        apply(&mut self.w, keep);
        apply(&mut self.f, keep);
        apply(&mut self.t, keep);
        apply(&mut self.r, keep);
        apply(&mut self.m, keep);
        apply(&mut self.inv_m, keep);
        apply(&mut self.inv_i, keep);
        apply(&mut self.material, keep);
        apply(&mut self.id, keep);
        apply(&mut self.driven, keep);
    }

    /// Index of each particle id (inverse of `id`); ids of removed particles map to usize::MAX.
    pub fn index_of_ids(&self) -> Vec<usize> {
        let max_id = self.id.iter().copied().max().map_or(0, |m| m as usize + 1);
        let mut idx = vec![usize::MAX; max_id];
        for (k, &id) in self.id.iter().enumerate() {
            idx[id as usize] = k;
        }
        idx
    }

    /// Translational kinetic energy of the free particles, sum of m v^2 / 2, J. Driven
    /// particles are left out: their motion is prescribed, like a wall's, not part of the
    /// dynamics (a settling criterion must not see a moving lid).
    pub fn translational_energy(&self) -> f64 {
        self.v
            .iter()
            .zip(&self.m)
            .zip(&self.driven)
            .filter(|(_, &d)| !d)
            .map(|((v, m), _)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
            .sum()
    }

    /// Rotational kinetic energy, sum of I w^2 / 2 with I = 0.4 m r^2, J. With EPSD2 (no rolling
    /// dashpot) a resting packing keeps far more of it than of translational energy, so stop
    /// criteria should use [`Particles::translational_energy`].
    ///
    /// Driven particles are left out, as in [`Particles::translational_energy`].
    pub fn rotational_energy(&self) -> f64 {
        self.w
            .iter()
            .zip(&self.inv_i)
            .zip(&self.driven)
            .filter(|(_, &d)| !d)
            .map(|((w, ii), _)| 0.5 / ii * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]))
            .sum()
    }
}

/// Scratch buffers for [`Particles::permute`], kept between calls so that reordering allocates
/// nothing once warmed up.
#[derive(Debug, Default, Clone)]
pub struct PermuteScratch {
    v3: Vec<V3>,
    f: Vec<f64>,
    u16: Vec<u16>,
    u32: Vec<u32>,
    flag: Vec<bool>,
}
