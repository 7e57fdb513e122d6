//! The interfaces of the contact law's effects, one trait per slot; their implementations are
//! in one file per effect (`hertz`, `power_damped`, `mindlin`, `epsd2`, `cdt`, `sjkr`, `none`).

use super::kinematics::Contact;
use crate::material::PairConstants;
use crate::vec3::V3;

/// A kernel of the normal slot: elasticity and damping along the line of centres.
pub trait NormalForce: Copy + Default + Send + Sync {
    /// Whether the four-lane kernel ([`super::lanes`]) implements this effect exactly.
    const LANES: bool = false;
    /// Normal force along n, N (positive pushes the bodies apart; negative near separation when
    /// the dashpot outweighs the spring, as LIGGGHTS allows).
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64;
}

/// A kernel of the tangential slot: friction in the contact plane.
pub trait Tangential: Copy + Default + Send + Sync {
    /// Whether the four-lane kernel ([`super::lanes`]) implements this effect exactly.
    const LANES: bool = false;
    /// Advances the history spring `xi` (m) by the tangential slip over `dt` (s) and returns the
    /// tangential force on i, N; `f_n` (N) is the normal load the Coulomb cap scales with.
    fn force(&self, c: &Contact, p: &PairConstants, f_n: f64, xi: &mut V3, dt: f64) -> V3;
}

/// A kernel of the rolling slot: a torque against the relative rolling rotation.
pub trait Rolling: Copy + Default + Send + Sync {
    /// Whether the four-lane kernel ([`super::lanes`]) implements this effect exactly.
    const LANES: bool = false;
    /// The rolling resistance torque M, N m: i receives -M and j +M (the contact law
    /// applies the signs); updates the stored torque `m` over `dt` (s). `f_n` (N) is the load
    /// the cap mu_r R* |F_n| scales with.
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3;
}

/// A kernel of the cohesion slot: an attraction between touching bodies.
pub trait Cohesion: Copy + Default + Send + Sync {
    /// Whether the effect needs the contact area (skipped at compile time when not).
    const ACTIVE: bool = true;
    /// Attractive force magnitude, N, >= 0 (subtracted from the normal force).
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64;
}
