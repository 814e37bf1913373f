//! The emergency-stop loop a board reads on an input of its own, whatever else is connected.
//!
//! A normally-closed contact (the stop button, or a jumper plug on its connector where no
//! button is fitted) holds the board's input closed; pressed, broken or not wired at all, the
//! loop reads open. On a board that has the input ([`crate::RigConfig::emergency_stop_input`]):
//!
//! - `Arm` is refused while the loop reads open, and until it has read closed once since reset
//!   ([`EmergencyStopError`]): a stop pressed, broken or unwired at power-up leaves the drive
//!   off, with a message that names the loop;
//! - nothing of the bed apparatus can be switched on while the loop reads open;
//! - the loop opening after it has read closed latches [`crate::FaultCode::EmergencyStop`]
//!   (drive and bed off, latched until `ClearFault` with the loop closed again).
//!
//! A loop that has never read closed latches nothing: with nothing wired the board is Idle and
//! safe, and says why it cannot arm. Boards without the input (the simulated rigs, QEMU) are
//! unaffected; their stop, if any, comes with the bed apparatus's inputs
//! ([`crate::bed::BedInputs::emergency_stop`]).

use core::fmt;

/// What `Status` reports of the loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EmergencyStopStatus {
    /// The board reads an emergency-stop loop of its own.
    pub fitted: bool,
    /// The loop reads open now (pressed, broken or not wired); false when not fitted.
    pub open: bool,
    /// The loop has read closed at least once since reset.
    pub closed_since_reset: bool,
}

/// Why `Arm` (or a bed command that switches something on) was refused by the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EmergencyStopError {
    /// The loop has not read closed since reset (no stop wired, or pressed since power-up).
    NeverClosed,
    /// The loop reads open now.
    Open,
}

impl fmt::Display for EmergencyStopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NeverClosed => {
                "the emergency-stop loop has not read closed since reset: wire the stop's \
                 normally-closed contact (or a jumper plug on its connector) and release it"
            }
            Self::Open => {
                "the emergency-stop loop is open (stop pressed, a wire broken or its connector \
                 out): release the stop or reconnect it"
            }
        })
    }
}

/// The loop's state, as the board last read it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EmergencyStopLoop {
    status: EmergencyStopStatus,
}

impl EmergencyStopLoop {
    /// A loop on a board that has the input (`fitted`), not read yet: open until it reads
    /// closed.
    pub const fn new(fitted: bool) -> Self {
        Self {
            status: EmergencyStopStatus {
                fitted,
                open: fitted,
                closed_since_reset: false,
            },
        }
    }

    /// This tick's reading (ignored on a board without the input).
    pub fn read(&mut self, open: bool) {
        if !self.status.fitted {
            return;
        }
        self.status.open = open;
        self.status.closed_since_reset |= !open;
    }

    /// What `Status` reports.
    pub fn status(&self) -> EmergencyStopStatus {
        self.status
    }

    /// The loop stops the rig now: it reads open after having read closed since reset.
    pub fn tripped(&self) -> bool {
        self.status.fitted && self.status.open && self.status.closed_since_reset
    }

    /// Whether `Arm`, or switching part of the bed on, may proceed.
    pub fn check(&self) -> Result<(), EmergencyStopError> {
        let s = self.status;
        if !s.fitted {
            Ok(())
        } else if !s.closed_since_reset {
            Err(EmergencyStopError::NeverClosed)
        } else if s.open {
            Err(EmergencyStopError::Open)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_board_without_the_input_never_refuses() {
        let mut l = EmergencyStopLoop::new(false);
        assert_eq!(l.check(), Ok(()));
        l.read(true);
        assert_eq!(l.check(), Ok(()));
        assert!(!l.tripped());
        assert_eq!(l.status(), EmergencyStopStatus::default());
    }

    #[test]
    fn open_from_power_up_refuses_without_tripping_and_trips_once_it_was_closed() {
        let mut l = EmergencyStopLoop::new(true);
        assert_eq!(l.check(), Err(EmergencyStopError::NeverClosed), "unread");
        l.read(true);
        assert_eq!(l.check(), Err(EmergencyStopError::NeverClosed));
        assert!(!l.tripped(), "never closed: Idle, not a fault");
        l.read(false);
        assert_eq!(l.check(), Ok(()));
        assert!(!l.tripped());
        l.read(true);
        assert_eq!(l.check(), Err(EmergencyStopError::Open));
        assert!(l.tripped());
        assert_eq!(
            l.status(),
            EmergencyStopStatus {
                fitted: true,
                open: true,
                closed_since_reset: true
            }
        );
    }
}
