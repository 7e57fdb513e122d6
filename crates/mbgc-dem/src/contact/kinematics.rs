//! What the effects of the contact law work from: the contact's geometry and kinematics, and the
//! history it carries from step to step.

use crate::vec3::*;

/// Per-contact state carried from step to step (and across neighbour-list rebuilds).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct History {
    /// Tangential spring displacement xi, m, kept in the contact plane; oriented from j's view
    /// of i, so swapping i and j flips its sign.
    pub shear: V3,
    /// Stored rolling resistance torque M, N m (EPSD2; unused by the other rolling effects).
    pub rolling: V3,
}

impl History {
    /// Whether both parts are exactly zero: a separated pair, whose entry the force loop may
    /// skip and a rebuild need not carry.
    pub fn is_zero(&self) -> bool {
        self.shear == [0.0; 3] && self.rolling == [0.0; 3]
    }
}

/// Geometry and kinematics of one touching contact between particle i and a partner j (another
/// particle or a wall).
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// Unit normal pointing from j to i.
    pub n: V3,
    /// Overlap delta > 0, m.
    pub overlap: f64,
    /// Effective radius R* = r_i r_j / (r_i + r_j), m (r_i against a wall).
    pub r_eff: f64,
    /// Effective mass m* = m_i m_j / (m_i + m_j), kg (m_i against a wall).
    pub m_eff: f64,
    /// sqrt(R* delta), shared by the Hertz and Mindlin stiffnesses.
    pub sqrt_rd: f64,
    /// sqrt(sqrt(R* delta) m*), shared by the normal and tangential dashpots.
    pub damp_root: f64,
    /// Normal relative velocity (v_i - v_j).n, m/s: negative while approaching.
    pub v_n: f64,
    /// Tangential relative velocity of the contact points, m/s:
    /// v_t - (c_i w_i + c_j w_j) x n, as LIGGGHTS.
    pub v_t: V3,
    /// Relative angular velocity w_i - w_j with its twisting part removed, rad/s.
    pub w_roll: V3,
    /// Lever arm c_i = r_i - delta/2 from the centre of i to the contact point, m.
    pub lever_i: f64,
    /// Lever arm c_j = r_j - delta/2 from the centre of j to the contact point, m (0 for a wall).
    pub lever_j: f64,
    /// Area of the contact circle, m^2, used by cohesion (0 when no effect needs it).
    pub area: f64,
}

impl Contact {
    /// Builds the contact from the state of both bodies. `lever_i`/`lever_j` are the distances
    /// from the centres to the contact point; `area` is the overlap circle area.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn new(
        n: V3,
        overlap: f64,
        r_eff: f64,
        m_eff: f64,
        v_rel: V3,
        w_i: V3,
        w_j: V3,
        lever_i: f64,
        lever_j: f64,
        area: f64,
    ) -> Self {
        let v_n = dot(v_rel, n);
        let v_t0 = sub(v_rel, scale(n, v_n));
        let w_sum = add(scale(w_i, lever_i), scale(w_j, lever_j));
        let v_t = sub(v_t0, cross(w_sum, n));
        let w_rel = sub(w_i, w_j);
        let w_roll = sub(w_rel, scale(n, dot(w_rel, n)));
        let sqrt_rd = (r_eff * overlap).sqrt();
        Contact {
            n,
            overlap,
            r_eff,
            m_eff,
            sqrt_rd,
            damp_root: (sqrt_rd * m_eff).sqrt(),
            v_n,
            v_t,
            w_roll,
            lever_i,
            lever_j,
            area,
        }
    }
}
