//! Why the board last reset, and the policy that follows from it.
//!
//! Position zero is wherever the carriage sat at boot (the encoder counter starts at 0). After
//! a power-on reset the lab starts from a known place; after any other reset (the watchdog
//! firing mid-run, a software reset, the reset pin, a brown-out) the carriage may be anywhere
//! within its stroke, so the stroke limits may be shifted by up to the stroke itself. The core
//! refuses `Arm` after such a reset until the host acknowledges it (`AcknowledgeReset`, after
//! homing or checking the carriage's position by hand), and reports the cause in every
//! `Status`.

/// The cause of the last reset, as the board's reset-status flags report it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// Power applied (or the simulator starting): position zero is where the lab put it.
    PowerOn,
    /// The reset pin (NRST), e.g. a probe or the board's button.
    Pin,
    /// A watchdog (independent or window) fired.
    Watchdog,
    /// Software asked for it (`SYSRESETREQ`), e.g. after flashing.
    Software,
    /// The supply dropped below the brown-out level.
    BrownOut,
    /// A low-power mode's reset.
    LowPower,
    /// No flag set, or flags the board cannot tell apart.
    Unknown,
}

impl ResetCause {
    /// A reset after which position zero is trustworthy without an acknowledgement.
    pub fn is_power_on(self) -> bool {
        self == Self::PowerOn
    }
}
