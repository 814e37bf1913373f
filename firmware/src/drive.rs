//! The drive's analog force command: the STA-1104's servo drive takes a +-10 V force (current)
//! command; the board's 12-bit DAC (0..3.3 V) feeds it through an offset-and-gain stage that
//! maps 0 V -> -10 V, 1.65 V -> 0 V and 3.3 V -> +10 V.
//!
//! | DAC code | DAC output | drive input | force command |
//! |---|---|---|---|
//! | 1 | ~0 V | -10 V | -300 N (the drive's peak force) |
//! | 2048 ([`ZERO_FORCE_CODE`]) | 1.65 V | 0 V | 0 N |
//! | 4095 | 3.3 V | +10 V | +300 N |
//!
//! Scale: 300 N / 2047 = 0.147 N per code. Code 0 is never written, so the command
//! is symmetric about the mid-point. These are the nominal codes; the rig's own (measured at
//! bring-up, sent with `SetDriveCalibration`) are the core's `DriveCalibration`, which turns
//! every force command into a code. The fault handlers write the nominal zero code after
//! dropping the enable line (the drive ignores its input then).
//!
//! Motor current sense: the drive's current monitor (+-10 V for +-[`CURRENT_FULL_SCALE_A`]) is
//! divided into 0..3.3 V with the same mid-point convention, read by a 12-bit ADC.

/// DAC code for zero force: the mid-point of the 12-bit range (1.65 V).
pub const ZERO_FORCE_CODE: u16 = sandjumper_core::drive_calibration::NOMINAL_ZERO_CODE;
/// Codes either side of the mid-point that reach full scale.
pub const HALF_RANGE_CODES: u16 = sandjumper_core::drive_calibration::NOMINAL_HALF_RANGE_CODES;
/// Current-sense ADC code for 0 A: the mid-point of the 12-bit range (1.65 V).
pub const ZERO_CURRENT_CODE: u16 = 2048;
/// Motor current at full scale of the current monitor, A.
pub const CURRENT_FULL_SCALE_A: f32 = 10.0;

/// Motor current from a 12-bit current-sense ADC code, A (2048 = 0 A).
pub fn current_from_code(code: u16) -> f32 {
    (f32::from(code & 0x0FFF) - f32::from(ZERO_CURRENT_CODE)) * CURRENT_FULL_SCALE_A
        / f32::from(HALF_RANGE_CODES)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn current_sense_mid_point_is_zero_amps() {
        assert_eq!(current_from_code(2048), 0.0);
        assert!((current_from_code(4095) - CURRENT_FULL_SCALE_A).abs() < 1e-6);
    }
}
