//! The drive's analog force command: the STA-1104's servo drive takes a +-10 V force (current)
//! command; the board's 12-bit DAC (0..3.3 V) feeds it through an offset-and-gain stage that
//! maps 0 V -> -10 V, 1.65 V -> 0 V and 3.3 V -> +10 V.
//!
//! | DAC code | DAC output | drive input | force command |
//! |---|---|---|---|
//! | 1 | ~0 V | -10 V | -[`FULL_SCALE_N`] |
//! | 2048 ([`ZERO_FORCE_CODE`]) | 1.65 V | 0 V | 0 N |
//! | 4095 | 3.3 V | +10 V | +[`FULL_SCALE_N`] |
//!
//! Scale: [`FULL_SCALE_N`] / 2047 = 0.147 N per code. Code 0 is never written, so the command
//! is symmetric about the mid-point.
//!
//! Motor current sense: the drive's current monitor (+-10 V for +-[`CURRENT_FULL_SCALE_A`]) is
//! divided into 0..3.3 V with the same mid-point convention, read by a 12-bit ADC.

/// DAC code for zero force: the mid-point of the 12-bit range (1.65 V).
pub const ZERO_FORCE_CODE: u16 = 2048;
/// Codes either side of the mid-point that reach full scale.
pub const HALF_RANGE_CODES: u16 = 2047;
/// Force at full scale (+-10 V at the drive input), N: the drive's peak force `F_peak`
/// (MODEL.md section 1).
pub const FULL_SCALE_N: f32 = 300.0;
/// Current-sense ADC code for 0 A: the mid-point of the 12-bit range (1.65 V).
pub const ZERO_CURRENT_CODE: u16 = 2048;
/// Motor current at full scale of the current monitor, A.
pub const CURRENT_FULL_SCALE_A: f32 = 10.0;

/// The DAC code for a force command, N: rounded to the nearest code, saturated at full scale,
/// NaN -> zero force.
pub fn force_to_code(force_n: f32) -> u16 {
    if force_n.is_nan() {
        return ZERO_FORCE_CODE;
    }
    let half = f32::from(HALF_RANGE_CODES);
    let offset = (force_n / FULL_SCALE_N * half).clamp(-half, half);
    // Round half away from zero without libm: offset is within +-2047, so the cast is exact.
    let rounded = if offset >= 0.0 {
        (offset + 0.5) as i32
    } else {
        (offset - 0.5) as i32
    };
    (i32::from(ZERO_FORCE_CODE) + rounded) as u16
}

/// The force a DAC code commands, N (the inverse of [`force_to_code`], for the tests).
#[cfg(test)]
pub fn code_to_force(code: u16) -> f32 {
    (f32::from(code) - f32::from(ZERO_FORCE_CODE)) * FULL_SCALE_N / f32::from(HALF_RANGE_CODES)
}

/// Motor current from a 12-bit current-sense ADC code, A (2048 = 0 A).
pub fn current_from_code(code: u16) -> f32 {
    (f32::from(code & 0x0FFF) - f32::from(ZERO_CURRENT_CODE)) * CURRENT_FULL_SCALE_A
        / f32::from(HALF_RANGE_CODES)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_force_is_the_mid_point() {
        assert_eq!(force_to_code(0.0), 2048);
        assert_eq!(force_to_code(-0.0), 2048);
        assert_eq!(code_to_force(2048), 0.0);
        assert_eq!(force_to_code(f32::NAN), 2048);
    }

    #[test]
    fn full_scale_saturates_symmetrically() {
        assert_eq!(force_to_code(FULL_SCALE_N), 4095);
        assert_eq!(force_to_code(-FULL_SCALE_N), 1);
        assert_eq!(force_to_code(1e9), 4095);
        assert_eq!(force_to_code(-1e9), 1);
        assert_eq!(force_to_code(f32::INFINITY), 4095);
        assert_eq!(force_to_code(f32::NEG_INFINITY), 1);
    }

    #[test]
    fn round_trip_is_within_half_a_code() {
        let step = FULL_SCALE_N / f32::from(HALF_RANGE_CODES);
        let mut f = -FULL_SCALE_N;
        while f <= FULL_SCALE_N {
            let back = code_to_force(force_to_code(f));
            assert!((back - f).abs() <= step / 2.0 + 1e-4, "{f} N -> {back} N");
            f += 0.37;
        }
    }

    #[test]
    fn current_sense_mid_point_is_zero_amps() {
        assert_eq!(current_from_code(2048), 0.0);
        assert!((current_from_code(4095) - CURRENT_FULL_SCALE_A).abs() < 1e-6);
    }
}
