//! The simulator's error type: what was wrong, where, what is allowed.

use crate::params::ParamsError;
use core::fmt;

/// Why a simulation could not run or could not finish.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// A bad parameter set (see [`ParamsError`]).
    Params(ParamsError),
    /// A bad jump request or option: `field` had `value`; `allowed` says what is allowed.
    InvalidInput {
        /// The field, e.g. `freq_hz`.
        field: &'static str,
        /// The value given, as text.
        value: String,
        /// What is allowed.
        allowed: String,
    },
    /// The integrator could not keep the error below tolerance at time `t_s`.
    StepSizeTooSmall {
        /// Simulated time, s.
        t_s: f64,
        /// Step size reached, s.
        step_s: f64,
    },
    /// More than `limit` steps (a runaway run) at time `t_s`.
    TooManySteps {
        /// Simulated time, s.
        t_s: f64,
        /// The step limit of [`crate::SimOptions`].
        limit: u64,
    },
    /// More than `limit` mode switches at one instant `t_s` (an inconsistent hybrid state).
    ModeSwitchLoop {
        /// Simulated time, s.
        t_s: f64,
        /// Largest number of switches at one instant.
        limit: u32,
    },
    /// The state became NaN or infinite at time `t_s`.
    NonFinite {
        /// Simulated time, s.
        t_s: f64,
    },
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Params(e) => write!(f, "{e}"),
            Self::InvalidInput {
                field,
                value,
                allowed,
            } => {
                write!(f, "invalid {field} = {value} (allowed: {allowed})")
            }
            Self::StepSizeTooSmall { t_s, step_s } => write!(
                f,
                "integration failed at t = {t_s} s: step size {step_s:e} s too small for the tolerance \
                 (allowed: a looser --rtol, or parameters without a singularity)"
            ),
            Self::TooManySteps { t_s, limit } => write!(
                f,
                "integration stopped at t = {t_s} s after {limit} steps (allowed: at most SimOptions::max_steps)"
            ),
            Self::ModeSwitchLoop { t_s, limit } => write!(
                f,
                "more than {limit} ground-mode switches at t = {t_s} s (allowed: a consistent hybrid state)"
            ),
            Self::NonFinite { t_s } => {
                write!(
                    f,
                    "state became NaN or infinite at t = {t_s} s (allowed: finite parameters)"
                )
            }
        }
    }
}

impl std::error::Error for SimError {}

impl From<ParamsError> for SimError {
    fn from(e: ParamsError) -> Self {
        Self::Params(e)
    }
}
