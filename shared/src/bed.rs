//! The bed apparatus (the paper's automated bed preparation) and its interlocks.
//!
//! Outputs: the blower's flow command (0-10 V), the shaker motor (duty 0-1), the lift motor
//! that takes the jumper out of the bed (enable and direction). Inputs: the lift's up and
//! down limit switches, the emergency stop, the bed-height sensor (raw ADC code).
//!
//! Interlocks, owned here so the firmware and every simulated rig obey the same rules:
//! - no `Arm` (hence no jump) unless the lift is at its down limit and stopped, and the
//!   blower and the shaker are off;
//! - while a jump is armed or running, the lift cannot move and the blower and shaker cannot
//!   be switched on;
//! - the emergency stop or any latched fault turns blower, shaker and lift off and trips the
//!   apparatus (latched): it takes no command that switches anything on until the fault is
//!   cleared with the emergency stop released;
//! - the lift stops by itself at the limit switch it is moving toward.
//!
//! A board without the apparatus never reports its inputs ([`BedApparatus::present`] stays
//! false): the `Arm` interlock then does not apply, and its outputs stay off (every command
//! that would switch something on is refused, [`BedError::Absent`]).

use core::fmt;

/// The apparatus's inputs, read once per control tick by the glue.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BedInputs {
    /// Lift at its upper limit switch.
    pub lift_up_limit: bool,
    /// Lift at its lower limit switch (the jumper in the bed, ready to jump).
    pub lift_down_limit: bool,
    /// Emergency stop pressed.
    pub emergency_stop: bool,
    /// Bed-height sensor, raw ADC code (the host converts it; it may use the camera instead).
    pub height_raw: u16,
}

/// Which way the lift moves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LiftMove {
    /// Stopped.
    #[default]
    Stop,
    /// Up (out of the bed), until the upper limit.
    Up,
    /// Down (into the bed), until the lower limit.
    Down,
}

/// A bed command from the host.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BedCommand {
    /// Blower flow command, V (0: off; up to 10).
    Blower {
        /// V.
        volts: f32,
    },
    /// Shaker duty (0: off; up to 1).
    Shaker {
        /// 0-1.
        duty: f32,
    },
    /// Move or stop the lift.
    Lift(LiftMove),
}

impl BedCommand {
    /// Whether it switches something off (always allowed).
    pub fn is_off(&self) -> bool {
        match *self {
            Self::Blower { volts } => volts == 0.0,
            Self::Shaker { duty } => duty == 0.0,
            Self::Lift(m) => m == LiftMove::Stop,
        }
    }
}

/// The apparatus's outputs after a tick.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BedOutputs {
    /// Blower command, V.
    pub blower_v: f32,
    /// Shaker duty, 0-1.
    pub shaker_duty: f32,
    /// Lift motor enabled.
    pub lift_enable: bool,
    /// Lift direction (true: up); meaningful when enabled.
    pub lift_up: bool,
}

/// Why a bed command or `Arm` was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BedError {
    /// A jump is armed or running: the lift stays, blower and shaker stay off.
    JumpActive,
    /// Tripped by the emergency stop or a fault: clear the fault first.
    Tripped,
    /// The emergency stop is pressed.
    EmergencyStop,
    /// A value out of range (blower 0-10 V, shaker duty 0-1).
    OutOfRange,
    /// `Arm` refused: the lift is not at its down limit, or still moving.
    LiftNotDown,
    /// `Arm` refused: the blower is on.
    BlowerOn,
    /// `Arm` refused: the shaker is on.
    ShakerOn,
    /// The lift is already at the limit it was told to move to.
    LiftAtLimit,
    /// No apparatus has reported its inputs (its limit switches and emergency stop unread):
    /// nothing of it may be switched on.
    Absent,
}

impl fmt::Display for BedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::JumpActive => {
                "a jump is armed or running: the lift stays and blower and shaker stay off"
            }
            Self::Tripped => {
                "the bed apparatus tripped (emergency stop or fault): clear the fault first"
            }
            Self::EmergencyStop => "the emergency stop is pressed",
            Self::Absent => {
                "no bed apparatus is connected (its limit switches and emergency stop are not read): nothing of it can be switched on"
            }
            Self::OutOfRange => "out of range (blower 0 to 10 V, shaker duty 0 to 1)",
            Self::LiftNotDown => "the lift is not down at its limit switch (or still moving)",
            Self::BlowerOn => "the blower is on",
            Self::ShakerOn => "the shaker is on",
            Self::LiftAtLimit => "the lift is already at that limit",
        })
    }
}

/// Blower full scale, V.
pub const BLOWER_MAX_V: f32 = 10.0;

/// The apparatus's state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BedApparatus {
    present: bool,
    inputs: BedInputs,
    out: BedOutputs,
    lift: LiftMove,
    tripped: bool,
}

impl BedApparatus {
    /// An apparatus that has not reported yet (absent).
    pub const fn new() -> Self {
        Self {
            present: false,
            inputs: BedInputs {
                lift_up_limit: false,
                lift_down_limit: false,
                emergency_stop: false,
                height_raw: 0,
            },
            out: BedOutputs {
                blower_v: 0.0,
                shaker_duty: 0.0,
                lift_enable: false,
                lift_up: false,
            },
            lift: LiftMove::Stop,
            tripped: false,
        }
    }

    /// Whether the board has reported the apparatus's inputs.
    pub fn present(&self) -> bool {
        self.present
    }

    /// The inputs last read.
    pub fn inputs(&self) -> BedInputs {
        self.inputs
    }

    /// The outputs now.
    pub fn outputs(&self) -> BedOutputs {
        self.out
    }

    /// Tripped (latched off).
    pub fn tripped(&self) -> bool {
        self.tripped
    }

    /// Any actuator is on: the lift moving, the shaker or the blower running.
    pub fn any_on(&self) -> bool {
        self.out.lift_enable || self.out.blower_v != 0.0 || self.out.shaker_duty != 0.0
    }

    /// The emergency stop is pressed (as last read).
    pub fn emergency_stop(&self) -> bool {
        self.inputs.emergency_stop
    }

    /// A host command; `jump_active`: the rig is Armed or Running.
    pub fn command(&mut self, cmd: &BedCommand, jump_active: bool) -> Result<(), BedError> {
        if !cmd.is_off() {
            if !self.present {
                return Err(BedError::Absent);
            }
            if self.inputs.emergency_stop {
                return Err(BedError::EmergencyStop);
            }
            if self.tripped {
                return Err(BedError::Tripped);
            }
            if jump_active {
                return Err(BedError::JumpActive);
            }
        }
        match *cmd {
            BedCommand::Blower { volts } => {
                if !(0.0..=BLOWER_MAX_V).contains(&volts) {
                    return Err(BedError::OutOfRange);
                }
                self.out.blower_v = volts;
            }
            BedCommand::Shaker { duty } => {
                if !(0.0..=1.0).contains(&duty) {
                    return Err(BedError::OutOfRange);
                }
                self.out.shaker_duty = duty;
            }
            BedCommand::Lift(m) => {
                let at_limit = match m {
                    LiftMove::Up => self.inputs.lift_up_limit,
                    LiftMove::Down => self.inputs.lift_down_limit,
                    LiftMove::Stop => false,
                };
                if at_limit {
                    return Err(BedError::LiftAtLimit);
                }
                self.lift = m;
                self.drive_lift();
            }
        }
        Ok(())
    }

    /// Whether `Arm` may proceed.
    pub fn arm_check(&self) -> Result<(), BedError> {
        if !self.present {
            return Ok(());
        }
        if self.inputs.emergency_stop {
            return Err(BedError::EmergencyStop);
        }
        if self.tripped {
            return Err(BedError::Tripped);
        }
        if !self.inputs.lift_down_limit || self.lift != LiftMove::Stop {
            return Err(BedError::LiftNotDown);
        }
        if self.out.blower_v != 0.0 {
            return Err(BedError::BlowerOn);
        }
        if self.out.shaker_duty != 0.0 {
            return Err(BedError::ShakerOn);
        }
        Ok(())
    }

    /// Store this tick's inputs (marks the apparatus present).
    pub fn read_inputs(&mut self, inputs: BedInputs) {
        self.present = true;
        self.inputs = inputs;
    }

    /// Once per tick after the rig's own checks: `fault_latched` is the rig's latched fault.
    /// Trips on the emergency stop or a fault, stops the lift at its limit, returns the
    /// outputs to apply.
    pub fn update(&mut self, fault_latched: bool) -> BedOutputs {
        if self.inputs.emergency_stop || fault_latched {
            self.trip();
        }
        let at_limit = match self.lift {
            LiftMove::Up => self.inputs.lift_up_limit,
            LiftMove::Down => self.inputs.lift_down_limit,
            LiftMove::Stop => false,
        };
        if at_limit {
            self.lift = LiftMove::Stop;
            self.drive_lift();
        }
        self.out
    }

    /// Everything off, latched.
    pub fn trip(&mut self) {
        self.tripped = true;
        self.lift = LiftMove::Stop;
        self.out = BedOutputs::default();
    }

    /// Clear the trip (with the rig's fault): refused while the emergency stop is pressed.
    pub fn clear(&mut self) -> Result<(), BedError> {
        if self.inputs.emergency_stop {
            return Err(BedError::EmergencyStop);
        }
        self.tripped = false;
        Ok(())
    }

    fn drive_lift(&mut self) {
        self.out.lift_enable = self.lift != LiftMove::Stop;
        self.out.lift_up = self.lift == LiftMove::Up;
    }
}

/// What `Status` reports about the apparatus.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BedStatus {
    /// The board has reported the apparatus.
    pub present: bool,
    /// Inputs last read.
    pub inputs: BedInputs,
    /// Outputs now.
    pub outputs: BedOutputs,
    /// Tripped (latched off).
    pub tripped: bool,
}

impl From<&BedApparatus> for BedStatus {
    fn from(b: &BedApparatus) -> Self {
        Self {
            present: b.present,
            inputs: b.inputs,
            outputs: b.out,
            tripped: b.tripped,
        }
    }
}

#[cfg(test)]
mod tests;
