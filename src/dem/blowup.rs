//! Why a run was stopped: the checks that turn a blown-up run into an error instead of numbers,
//! and the failure of a thread of the team.

use super::vec3::V3;

/// Why a run was stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum BlowUp {
    NotFinite {
        step: u64,
        particle: u32,
    },
    LeftDomain {
        step: u64,
        particle: u32,
        position: V3,
    },
    EnergyGrowth {
        step: u64,
        kinetic: f64,
        budget: f64,
    },
    TooFast {
        step: u64,
        particle: u32,
        speed: f64,
    },
    /// A thread of the team panicked; the others left their barriers and the run was abandoned
    /// mid-step, so the simulation's state is not to be trusted.
    WorkerPanic {
        step: u64,
        thread: usize,
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
