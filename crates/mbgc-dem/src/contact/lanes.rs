//! The common contact law, four contacts at a time: Hertz with LIGGGHTS' restitution damping,
//! Mindlin's history spring with its Coulomb cap, EPSD2 rolling resistance, no cohesion and no
//! force limit (the campaigns' `hertz,mindlin,epsd2`).
//!
//! Why a second copy of that law: the scalar kernels ([`super::hertz`], [`super::mindlin`],
//! [`super::epsd2`] through [`super::Law`]) are written for one contact, and the processor then
//! spends most of a step on one contact's scalar arithmetic. Laid out as four lanes (one
//! `[f64; 4]` per quantity) the same arithmetic compiles to vector instructions. Every lane
//! performs the scalar law's operations in the scalar law's order, branches become selects of
//! both outcomes, and nothing is fused, so each lane's force, torques and history are the scalar
//! law's bit for bit (`tests` checks it on random contacts). Callers add the results in list
//! order, so a run's sums are the scalar path's too.

use super::hertz::SQRT_5_6;
use crate::material::PairConstants;

/// Contacts per batch.
pub const LANES: usize = 4;

type L = [f64; LANES];
type V = [L; 3];

/// One batch's inputs, lane by lane; the histories are updated in place.
#[derive(Debug, Clone, Copy, Default)]
pub struct Lanes {
    /// x_i - x_j (minimum image where periodic).
    pub d: V,
    /// |d|^2, already known to be below rsum^2.
    pub dist2: L,
    /// r_i + r_j.
    pub rsum: L,
    /// Radii.
    pub ri: L,
    /// Radius of j.
    pub rj: L,
    /// Effective radius r_i r_j / (r_i + r_j), computed so by the near build.
    pub r_eff: L,
    /// Effective mass m_i m_j / (m_i + m_j), likewise.
    pub m_eff: L,
    /// v_i - v_j.
    pub v_rel: V,
    /// Angular velocities.
    pub wi: V,
    /// Angular velocity of j.
    pub wj: V,
    /// Pair constants ([`crate::material::PairConstants`]).
    pub y_eff: L,
    /// Effective shear modulus.
    pub g_eff: L,
    /// Damping factor beta.
    pub beta: L,
    /// sqrt(2 Y*).
    pub sqrt_2y: L,
    /// sqrt(8 G*).
    pub sqrt_8g: L,
    /// Sliding friction.
    pub friction: L,
    /// Rolling friction.
    pub rolling_friction: L,
    /// Tangential spring (history), updated.
    pub shear: V,
    /// Rolling spring (history), updated.
    pub rolling: V,
}

impl Lanes {
    /// Lane `l` takes the pair constants `pc`.
    #[inline(always)]
    pub fn set_pair(&mut self, l: usize, pc: &PairConstants) {
        self.y_eff[l] = pc.y_eff;
        self.g_eff[l] = pc.g_eff;
        self.beta[l] = pc.beta;
        self.sqrt_2y[l] = pc.sqrt_2y;
        self.sqrt_8g[l] = pc.sqrt_8g;
        self.friction[l] = pc.friction;
        self.rolling_friction[l] = pc.rolling_friction;
    }

    /// Copies lane `from`'s inputs into lane `to`.
    pub fn copy_lane(&mut self, from: usize, to: usize) {
        for v in [
            &mut self.d,
            &mut self.v_rel,
            &mut self.wi,
            &mut self.wj,
            &mut self.shear,
            &mut self.rolling,
        ] {
            for q in v.iter_mut() {
                q[to] = q[from];
            }
        }
        for s in [
            &mut self.dist2,
            &mut self.rsum,
            &mut self.ri,
            &mut self.rj,
            &mut self.r_eff,
            &mut self.m_eff,
            &mut self.y_eff,
            &mut self.g_eff,
            &mut self.beta,
            &mut self.sqrt_2y,
            &mut self.sqrt_8g,
            &mut self.friction,
            &mut self.rolling_friction,
        ] {
            s[to] = s[from];
        }
    }
}

/// One batch's results.
#[derive(Debug, Clone, Copy, Default)]
pub struct LaneForces {
    /// Force on i (j gets the opposite).
    pub force: V,
    /// Torque on i.
    pub torque_i: V,
    /// Torque on j.
    pub torque_j: V,
}

#[inline(always)]
fn map(f: impl Fn(usize) -> f64) -> L {
    std::array::from_fn(f)
}

#[inline(always)]
fn vmap(f: impl Fn(usize, usize) -> f64) -> V {
    std::array::from_fn(|k| std::array::from_fn(|l| f(k, l)))
}

#[inline(always)]
fn dot(a: &V, b: &V) -> L {
    map(|l| a[0][l] * b[0][l] + a[1][l] * b[1][l] + a[2][l] * b[2][l])
}

#[inline(always)]
fn cross(a: &V, b: &V) -> V {
    [
        map(|l| a[1][l] * b[2][l] - a[2][l] * b[1][l]),
        map(|l| a[2][l] * b[0][l] - a[0][l] * b[2][l]),
        map(|l| a[0][l] * b[1][l] - a[1][l] * b[0][l]),
    ]
}

#[inline(always)]
fn pick(c: [bool; LANES], a: &V, b: &V) -> V {
    vmap(|k, l| if c[l] { a[k][l] } else { b[k][l] })
}

/// The forces of the batch's contacts, advancing their histories by `dt`.
#[inline(always)]
pub fn forces(a: &mut Lanes, dt: f64) -> LaneForces {
    // The pair loop's geometry.
    let dist = map(|l| a.dist2[l].sqrt());
    let inv = map(|l| 1.0 / dist[l]);
    let n = vmap(|k, l| a.d[k][l] * inv[l]);
    let overlap = map(|l| a.rsum[l] - dist[l]);
    let (r_eff, m_eff) = (a.r_eff, a.m_eff);
    let lever_i = map(|l| a.ri[l] - 0.5 * overlap[l]);
    let lever_j = map(|l| a.rj[l] - 0.5 * overlap[l]);
    // Contact::new.
    let v_n = dot(&a.v_rel, &n);
    let v_t0 = vmap(|k, l| a.v_rel[k][l] - n[k][l] * v_n[l]);
    let w_sum = vmap(|k, l| a.wi[k][l] * lever_i[l] + a.wj[k][l] * lever_j[l]);
    let wxn = cross(&w_sum, &n);
    let v_t = vmap(|k, l| v_t0[k][l] - wxn[k][l]);
    let w_rel = vmap(|k, l| a.wi[k][l] - a.wj[k][l]);
    let w_rel_n = dot(&w_rel, &n);
    let w_roll = vmap(|k, l| w_rel[k][l] - n[k][l] * w_rel_n[l]);
    let sqrt_rd = map(|l| (r_eff[l] * overlap[l]).sqrt());
    let damp_root = map(|l| (sqrt_rd[l] * m_eff[l]).sqrt());
    // Hertz.
    let k_n = map(|l| (4.0 / 3.0) * a.y_eff[l] * sqrt_rd[l]);
    let gamma_n = map(|l| -2.0 * SQRT_5_6 * a.beta[l] * a.sqrt_2y[l] * damp_root[l]);
    let f_normal = map(|l| k_n[l] * overlap[l] - gamma_n[l] * v_n[l]);
    // No cohesion: the scalar law subtracts its zero.
    let f_n = map(|l| f_normal[l] - 0.0);
    // Mindlin's history spring, not strict, stiffness from G*.
    let xi0 = vmap(|k, l| a.shear[k][l] + v_t[k][l] * dt);
    let xn = dot(&xi0, &n);
    let xi = vmap(|k, l| xi0[k][l] - n[k][l] * xn[l]);
    let k_t = map(|l| 8.0 * a.g_eff[l] * sqrt_rd[l]);
    let f_t0 = vmap(|k, l| xi[k][l] * -k_t[l]);
    let f_shear2 = dot(&f_t0, &f_t0);
    let f_friction = map(|l| a.friction[l] * f_normal[l].abs());
    let sliding: [bool; LANES] =
        std::array::from_fn(|l| f_shear2[l] > f_friction[l] * f_friction[l]);
    // sqrt(f_shear2) > 0 exactly when f_shear2 > 0 (NaN fails both).
    let capped: [bool; LANES] = std::array::from_fn(|l| sliding[l] && f_shear2[l] > 0.0);
    let gamma_t = map(|l| -2.0 * SQRT_5_6 * a.beta[l] * a.sqrt_8g[l] * damp_root[l]);
    let f_stick = vmap(|k, l| f_t0[k][l] - v_t[k][l] * gamma_t[l]);
    let mut f_t = pick(sliding, &f_t0, &f_stick);
    a.shear = xi;
    // The divider is the bottleneck of this kernel: the cap's square root and divisions only
    // for a batch where some contact slides (few in a bed at rest).
    if capped.iter().any(|&c| c) {
        let f_shear = map(|l| f_shear2[l].sqrt());
        let ratio = map(|l| f_friction[l] / f_shear[l]);
        let f_slide = vmap(|k, l| f_t0[k][l] * ratio[l]);
        let inv_k = map(|l| -1.0 / k_t[l]);
        let xi_slide = vmap(|k, l| f_slide[k][l] * inv_k[l]);
        f_t = pick(capped, &f_slide, &f_t);
        a.shear = pick(capped, &xi_slide, &xi);
    }
    // Torques of the tangential force.
    let nxf = cross(&n, &f_t);
    let torque_i0 = vmap(|k, l| nxf[k][l] * -lever_i[l]);
    let torque_j0 = vmap(|k, l| nxf[k][l] * -lever_j[l]);
    // EPSD2.
    let k_r = map(|l| k_t[l] * r_eff[l] * r_eff[l]);
    let k_r_dt = map(|l| k_r[l] * dt);
    let m0 = vmap(|k, l| a.rolling[k][l] + w_roll[k][l] * k_r_dt[l]);
    let cap = map(|l| a.rolling_friction[l] * r_eff[l] * f_normal[l].abs());
    let mag2 = dot(&m0, &m0);
    let over: [bool; LANES] = std::array::from_fn(|l| mag2[l] > cap[l] * cap[l]);
    let m = if over.iter().any(|&o| o) {
        let shrink = map(|l| cap[l] / mag2[l].sqrt());
        let m_cap = vmap(|k, l| m0[k][l] * shrink[l]);
        pick(over, &m_cap, &m0)
    } else {
        m0
    };
    a.rolling = m;
    LaneForces {
        force: vmap(|k, l| n[k][l] * f_n[l] + f_t[k][l]),
        torque_i: vmap(|k, l| torque_i0[k][l] - m[k][l]),
        torque_j: vmap(|k, l| torque_j0[k][l] + m[k][l]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{epsd2::Epsd2, Contact, ContactLaw, History, Law};
    use crate::contact::{hertz::Hertz, mindlin::HistorySpring, none::NoCohesion};
    use crate::material::{Interaction, PairConstants, Solid};
    use crate::vec3::*;
    use rand::{RngExt, SeedableRng};

    /// Random contacts, some sliding and some rolling past their caps, some stuck: each lane's
    /// force, torques and histories equal the scalar law's to the bit.
    #[test]
    fn four_lanes_are_the_scalar_law_bit_for_bit() {
        let law = Law::<Hertz, HistorySpring, Epsd2, NoCohesion>::default();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let dt = 1.3e-5;
        let (mut capped, mut stuck, mut rolled) = (0, 0, 0);
        for _ in 0..500 {
            let mut a = Lanes::default();
            let mut expected = Vec::new();
            for l in 0..LANES {
                let solid = Solid {
                    name: "s".into(),
                    youngs_modulus: 10f64.powf(rng.random_range(6.0..9.0)),
                    poisson: rng.random_range(0.1..0.45),
                };
                let i = Interaction {
                    restitution: rng.random_range(0.1..0.95),
                    friction: rng.random_range(0.0..1.0),
                    rolling_friction: rng.random_range(0.0..1.0),
                    ..Interaction::default()
                };
                let p = PairConstants::new(&solid, &solid, &i);
                let (ri, rj) = (rng.random_range(1e-3..1e-2), rng.random_range(1e-3..1e-2));
                let rsum = ri + rj;
                let mut unit = [0.0; 3];
                for u in &mut unit {
                    *u = rng.random_range(-1.0..1.0);
                }
                let dist = rsum * rng.random_range(0.97..0.99999);
                let d = scale(unit, dist / norm(unit));
                let vec = |rng: &mut rand_chacha::ChaCha8Rng, s: f64| -> V3 {
                    [
                        rng.random_range(-s..s),
                        rng.random_range(-s..s),
                        rng.random_range(-s..s),
                    ]
                };
                let (vi, vj) = (vec(&mut rng, 0.3), vec(&mut rng, 0.3));
                let (wi, wj) = (vec(&mut rng, 30.0), vec(&mut rng, 30.0));
                let (mi, mj) = (rng.random_range(1e-6..1e-2), rng.random_range(1e-6..1e-2));
                let mut h = History {
                    shear: vec(&mut rng, 1e-4),
                    rolling: vec(&mut rng, 1e-4),
                };
                // Load both from the same values the pair loop would.
                let dist2 = norm2(d);
                for k in 0..3 {
                    a.d[k][l] = d[k];
                    a.v_rel[k][l] = sub(vi, vj)[k];
                    a.wi[k][l] = wi[k];
                    a.wj[k][l] = wj[k];
                    a.shear[k][l] = h.shear[k];
                    a.rolling[k][l] = h.rolling[k];
                }
                a.dist2[l] = dist2;
                a.rsum[l] = rsum;
                (a.ri[l], a.rj[l]) = (ri, rj);
                // As the near build computes them.
                (a.r_eff[l], a.m_eff[l]) = (ri * rj / (ri + rj), mi * mj / (mi + mj));
                a.set_pair(l, &p);
                // The scalar path, as the pair loop runs it.
                let dist = dist2.sqrt();
                let inv = 1.0 / dist;
                let nrm = scale(d, inv);
                let overlap = rsum - dist;
                let c = Contact::new(
                    nrm,
                    overlap,
                    ri * rj / rsum,
                    mi * mj / (mi + mj),
                    sub(vi, vj),
                    wi,
                    wj,
                    ri - 0.5 * overlap,
                    rj - 0.5 * overlap,
                    0.0,
                );
                let before = h;
                let out = law.force(&c, &p, &mut h, dt);
                let k_t = 8.0 * p.g_eff * c.sqrt_rd;
                let xi = add(before.shear, scale(c.v_t, dt));
                let cap = p.friction * out.f_n.abs();
                if norm2(scale(xi, k_t)) > 1.0001 * cap * cap {
                    capped += 1;
                } else {
                    stuck += 1;
                }
                if norm2(h.rolling)
                    < 0.9999
                        * norm2(add(
                            before.rolling,
                            scale(c.w_roll, k_t * c.r_eff * c.r_eff * dt),
                        ))
                {
                    rolled += 1;
                }
                expected.push((out, h));
            }
            let got = forces(&mut a, dt);
            for (l, (out, h)) in expected.iter().enumerate() {
                for k in 0..3 {
                    assert_eq!(got.force[k][l].to_bits(), out.force[k].to_bits(), "force");
                    assert_eq!(
                        got.torque_i[k][l].to_bits(),
                        out.torque_i[k].to_bits(),
                        "t_i"
                    );
                    assert_eq!(
                        got.torque_j[k][l].to_bits(),
                        out.torque_j[k].to_bits(),
                        "t_j"
                    );
                    assert_eq!(a.shear[k][l].to_bits(), h.shear[k].to_bits(), "shear");
                    assert_eq!(a.rolling[k][l].to_bits(), h.rolling[k].to_bits(), "rolling");
                }
            }
        }
        // Both branches of both caps were exercised.
        assert!(
            capped > 100 && stuck > 100,
            "capped {capped}, stuck {stuck}"
        );
        assert!(rolled > 100, "rolled {rolled}");
    }
}
