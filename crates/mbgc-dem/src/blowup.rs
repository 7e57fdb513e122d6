//! Why a run was stopped: the checks that turn a blown-up run into an error instead of numbers,
//! and the failure of a thread of the team.

use super::vec3::V3;

/// Why a run was stopped. Every variant carries the step at which the check fired (checks run
/// every 50 steps and after the last), and particles are named by their stable id.
#[derive(Debug, Clone, PartialEq)]
pub enum BlowUp {
    /// A position or velocity became NaN or infinite: the integration diverged (usually a time
    /// step too large for the stiffness, or an overlap so deep the force exploded).
    NotFinite {
        /// Step at which the check found it.
        step: u64,
        /// Id of the first offending particle.
        particle: u32,
    },
    /// A particle left the scene's domain box along a non-periodic axis: it escaped the walls
    /// (tunnelled through a wall at too large a step, or was ejected by a spurious force). Along
    /// a periodic axis a particle outside the box is merely waiting to be wrapped in.
    LeftDomain {
        /// Step at which the check found it.
        step: u64,
        /// Id of the particle.
        particle: u32,
        /// Its position, m.
        position: V3,
    },
    /// Kinetic energy (translational plus rotational) exceeded 1.5 times the energy the scene
    /// started with: the integration creates energy. Checked only for closed scenes (no moving
    /// walls or moving driven particles, no cohesion, no gravity along a periodic axis), which
    /// cannot gain energy physically. Driven particles' own kinetic energy is not counted.
    EnergyGrowth {
        /// Step at which the check found it.
        step: u64,
        /// Kinetic energy at that step, J.
        kinetic: f64,
        /// The scene's initial kinetic, Hertz elastic and potential energy, J
        /// ([`crate::Simulation::energy_budget`]).
        budget: f64,
    },
    /// A particle moved faster than the scene's speed limit
    /// ([`crate::Simulation::speed_limit`], raised by ten times the fastest driven particle),
    /// ten times anything free fall, moving walls and the initial velocities can produce. Driven
    /// particles themselves are not checked.
    TooFast {
        /// Step at which the check found it.
        step: u64,
        /// Id of the particle.
        particle: u32,
        /// Its speed, m/s.
        speed: f64,
    },
    /// A thread of the team panicked; the others left their barriers and the run was abandoned
    /// mid-step, so the simulation's state is not to be trusted.
    WorkerPanic {
        /// The step in progress when the thread failed.
        step: u64,
        /// Index of the thread in the team (0 is the calling thread).
        thread: usize,
        /// The panic message.
        message: String,
    },
}

impl std::fmt::Display for BlowUp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BlowUp::NotFinite { step, particle } => {
                write!(
                    f,
                    "step {step}: particle {particle} has a non-finite position or velocity"
                )
            }
            BlowUp::LeftDomain {
                step,
                particle,
                position,
            } => {
                write!(
                    f,
                    "step {step}: particle {particle} left the domain at {position:?}"
                )
            }
            BlowUp::EnergyGrowth {
                step,
                kinetic,
                budget,
            } => write!(
                f,
                "step {step}: kinetic energy {kinetic:.3e} J exceeds all the energy the scene \
                 started with ({budget:.3e} J: kinetic, elastic and potential down to the domain \
                 floor); the integration is creating energy (time step too large?)"
            ),
            BlowUp::TooFast {
                step,
                particle,
                speed,
            } => write!(
                f,
                "step {step}: particle {particle} moves at {speed:.3e} m/s, beyond any speed the \
                 scene can produce (energy is not conserved: time step too large?)"
            ),
            BlowUp::WorkerPanic {
                step,
                thread,
                message,
            } => write!(
                f,
                "step {step}: thread {thread} of the team panicked ({message}); the run was \
                 abandoned"
            ),
        }
    }
}
