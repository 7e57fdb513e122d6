//! Particles in structure-of-arrays form.

use super::vec3::V3;
use crate::error::{Error, Result};

#[derive(Debug, Clone, Default)]
pub struct Particles {
    pub x: Vec<V3>,
    pub v: Vec<V3>,
    /// Angular velocity.
    pub w: Vec<V3>,
    pub f: Vec<V3>,
    /// Torque.
    pub t: Vec<V3>,
    pub r: Vec<f64>,
    pub m: Vec<f64>,
    pub inv_m: Vec<f64>,
    /// 1 / (0.4 m r^2).
    pub inv_i: Vec<f64>,
    pub material: Vec<u16>,
    /// Stable identifier: the insertion order, unchanged by the spatial sorting.
    pub id: Vec<u32>,
}

impl Particles {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a sphere at rest; returns its id.
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
        Ok(id)
    }

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
    }

    /// Keeps the particles whose `keep` flag is set, in order.
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

    pub fn translational_energy(&self) -> f64 {
        self.v
            .iter()
            .zip(&self.m)
            .map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
            .sum()
    }

    pub fn rotational_energy(&self) -> f64 {
        self.w
            .iter()
            .zip(&self.inv_i)
            .map(|(w, ii)| 0.5 / ii * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]))
            .sum()
    }
}

#[derive(Debug, Default)]
pub struct PermuteScratch {
    v3: Vec<V3>,
    f: Vec<f64>,
    u16: Vec<u16>,
    u32: Vec<u32>,
}
