//! Latched fault codes: a small table with stable numbers (the README has it too).
//!
//! | code | name | meaning | cleared by |
//! |---|---|---|---|
//! | 1 | `StrokeLimit` | measured motor position `\|p\|` beyond the stroke limit while the drive is enabled | `ClearFault` |
//! | 2 | `TrackingError` | `\|p_cmd - p\|` beyond the configured bound while the drive is enabled | `ClearFault` |
//! | 3 | `EncoderFault` | encoder count moved more in one tick than physically possible | `ClearFault` |
//! | 4 | `CommandWatchdog` | host link silent longer than the watchdog while the drive is enabled | `ClearFault` |
//! | 5 | `DeadlineOverrun` | a control tick took longer than its budget, the glue flagged an overrun, or a tick was missed (`Rig::note_tick_start`) | `ClearFault` |
//! | 6 | `InvalidConfiguration` | a jump configuration failed validation, or a replay jump is armed after its table was re-uploaded | `ClearFault` |
//! | 7 | `LinkCorrupted` | too many consecutive corrupted frames on the host link | `ClearFault` |
//! | 8 | `LinkLost` | lockstep sensor frames stopped (`Rig::lockstep_silent_period`), or the link closed mid-run | `ClearFault` |
//! | 9 | `EmergencyStop` | the emergency-stop loop opened after reading closed, or the bed apparatus reported its stop (or its harness lost) | `ClearFault`, with the stop released |
//! | 10 | `BedWatchdog` | host link silent longer than the bed watchdog while the lift, the shaker or the blower is on, in any state | `ClearFault` |
//!
//! Any fault: force command exactly zero from the faulting tick on, drive disabled, state
//! `Faulted`; only the first fault is latched (later ones are counted, not reported over it).

use core::fmt;

/// A latched fault. The discriminants are the stable wire/README numbers: never renumber.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum FaultCode {
    /// Measured `|p|` beyond the stroke limit while the drive is enabled.
    StrokeLimit = 1,
    /// Tracking error `|p_cmd - p|` beyond the configured bound while the drive is enabled.
    TrackingError = 2,
    /// Encoder jumped more counts in one tick than physically possible.
    EncoderFault = 3,
    /// No host traffic for longer than the watchdog while the drive is enabled.
    CommandWatchdog = 4,
    /// A control tick exceeded its deadline.
    DeadlineOverrun = 5,
    /// A configuration failed validation, or a replay jump was armed after its table changed.
    InvalidConfiguration = 6,
    /// A burst of corrupted frames beyond the configured limit.
    LinkCorrupted = 7,
    /// Lockstep sensor frames stopped arriving (raised by the glue).
    LinkLost = 8,
    /// The emergency stop was pressed (its loop opened, or the bed apparatus reported it).
    EmergencyStop = 9,
    /// No host traffic for longer than the bed watchdog while a bed actuator was on.
    BedWatchdog = 10,
}

impl FaultCode {
    /// Every code, in table order.
    pub const ALL: [FaultCode; 10] = [
        Self::StrokeLimit,
        Self::TrackingError,
        Self::EncoderFault,
        Self::CommandWatchdog,
        Self::DeadlineOverrun,
        Self::InvalidConfiguration,
        Self::LinkCorrupted,
        Self::LinkLost,
        Self::EmergencyStop,
        Self::BedWatchdog,
    ];

    /// The stable number.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The code for a stable number, if it is one.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.code() == code)
    }

    /// Short snake_case name (logs, CLI output).
    pub fn name(self) -> &'static str {
        match self {
            Self::StrokeLimit => "stroke_limit",
            Self::TrackingError => "tracking_error",
            Self::EncoderFault => "encoder_fault",
            Self::CommandWatchdog => "command_watchdog",
            Self::DeadlineOverrun => "deadline_overrun",
            Self::InvalidConfiguration => "invalid_configuration",
            Self::LinkCorrupted => "link_corrupted",
            Self::LinkLost => "link_lost",
            Self::EmergencyStop => "emergency_stop",
            Self::BedWatchdog => "bed_watchdog",
        }
    }
}

impl fmt::Display for FaultCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "fault {} ({})", self.code(), self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_stable_and_round_trip() {
        let numbers: [u8; 10] = FaultCode::ALL.map(FaultCode::code);
        assert_eq!(numbers, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]);
        for f in FaultCode::ALL {
            assert_eq!(FaultCode::from_code(f.code()), Some(f));
        }
        assert_eq!(FaultCode::from_code(0), None);
        assert_eq!(FaultCode::from_code(11), None);
    }

    /// The names the logs, the host and the README's table use: snake_case, one per code, and
    /// the display that carries them. Found by `cargo mutants` (`name` replaced by a constant
    /// passed the core's tests).
    #[test]
    fn names_are_the_tables_and_the_display_carries_them() {
        extern crate std;
        use std::string::ToString;
        let names = FaultCode::ALL.map(FaultCode::name);
        assert_eq!(
            names,
            [
                "stroke_limit",
                "tracking_error",
                "encoder_fault",
                "command_watchdog",
                "deadline_overrun",
                "invalid_configuration",
                "link_corrupted",
                "link_lost",
                "emergency_stop",
                "bed_watchdog",
            ]
        );
        assert_eq!(
            FaultCode::TrackingError.to_string(),
            "fault 2 (tracking_error)"
        );
    }
}
