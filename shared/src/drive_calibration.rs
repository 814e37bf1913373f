//! The drive's force command as DAC codes, calibrated on the rig.
//!
//! The rig's 12-bit DAC (0..V_ref) feeds the servo drive's +-10 V force input through an
//! offset-and-gain stage. Nominally code 2048 is 0 V at the drive and +-2047 codes are +-10 V
//! = +-300 N. On a real board neither holds exactly: the DAC's reference is the board's supply
//! (a Discovery board runs at about 3.0 V, not 3.3 V), the buffered output cannot reach its
//! rails, and the offset stage has its own error. "Zero force" at the nominal code can then be
//! tens of newtons. So the codes are measured on the rig with the drive disabled (the bring-up
//! procedure in `docs/bringup.md`) and sent with `SetDriveCalibration`; the core checks them,
//! uses them for every force command, and reports them in `Status`.

use core::fmt;

/// Nominal DAC code of zero force (the mid-point of 12 bits).
pub const NOMINAL_ZERO_CODE: u16 = 2048;
/// Nominal codes either side of zero that reach the drive's full scale.
pub const NOMINAL_HALF_RANGE_CODES: u16 = 2047;
/// The drive's force at full scale (+-10 V), N.
pub const FULL_SCALE_N: f32 = 300.0;
/// Largest allowed distance of a calibrated zero code from the nominal one, codes (10 % of the
/// range: ~0.33 V at the DAC; more means a wiring fault, not an offset).
pub const MAX_ZERO_OFFSET_CODES: u16 = 410;
/// Allowed gain relative to nominal: 0.8..=1.25.
pub const GAIN_RANGE: (f32, f32) = (0.8, 1.25);

/// DAC codes of the force command: the code of zero force and the codes per newton. (The
/// host's calibration file is this struct as TOML; an unknown key there is an error.)
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveCalibration {
    /// The DAC code at which the drive's input reads 0 V, codes.
    pub zero_code: u16,
    /// DAC codes per newton of force command (nominal 2047 / 300 N = 6.823).
    pub codes_per_newton: f32,
}

/// Why a calibration was refused.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalibrationError {
    /// The zero code is further than [`MAX_ZERO_OFFSET_CODES`] from 2048.
    ZeroCode { zero_code: u16 },
    /// The gain is outside [`GAIN_RANGE`] of nominal (or not finite).
    Gain { codes_per_newton: f32 },
    /// Full scale (+-300 N) does not fit in the DAC's codes 1..=4095 from this zero.
    FullScale {
        zero_code: u16,
        codes_per_newton: f32,
    },
}

impl fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroCode { zero_code } => write!(
                f,
                "zero code {zero_code} is more than {MAX_ZERO_OFFSET_CODES} codes from \
                 {NOMINAL_ZERO_CODE}: check the offset stage"
            ),
            Self::Gain { codes_per_newton } => write!(
                f,
                "{codes_per_newton} codes/N is outside {}..={} x the nominal {}",
                GAIN_RANGE.0,
                GAIN_RANGE.1,
                DriveCalibration::NOMINAL.codes_per_newton
            ),
            Self::FullScale {
                zero_code,
                codes_per_newton,
            } => write!(
                f,
                "+-{FULL_SCALE_N} N at {codes_per_newton} codes/N from zero code {zero_code} \
                 leaves the DAC's codes 1..=4095"
            ),
        }
    }
}

impl DriveCalibration {
    /// The nominal codes (a 3.3 V reference and an exact offset stage).
    pub const NOMINAL: Self = Self {
        zero_code: NOMINAL_ZERO_CODE,
        codes_per_newton: NOMINAL_HALF_RANGE_CODES as f32 / FULL_SCALE_N,
    };

    /// Check the codes: zero near the mid-point, gain near nominal, full scale within range.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        if self.zero_code.abs_diff(NOMINAL_ZERO_CODE) > MAX_ZERO_OFFSET_CODES {
            return Err(CalibrationError::ZeroCode {
                zero_code: self.zero_code,
            });
        }
        let gain = self.codes_per_newton / Self::NOMINAL.codes_per_newton;
        if !(gain.is_finite() && gain >= GAIN_RANGE.0 && gain <= GAIN_RANGE.1) {
            return Err(CalibrationError::Gain {
                codes_per_newton: self.codes_per_newton,
            });
        }
        let half = self.codes_per_newton * FULL_SCALE_N;
        let zero = f32::from(self.zero_code);
        if zero - half < 1.0 || zero + half > 4095.0 {
            return Err(CalibrationError::FullScale {
                zero_code: self.zero_code,
                codes_per_newton: self.codes_per_newton,
            });
        }
        Ok(())
    }

    /// The DAC code for a force command, N: rounded to the nearest code, saturated at the
    /// drive's full scale, NaN -> zero force.
    pub fn force_to_code(&self, force_n: f32) -> u16 {
        if force_n.is_nan() {
            return self.zero_code;
        }
        let clamped = force_n.clamp(-FULL_SCALE_N, FULL_SCALE_N);
        let offset = clamped * self.codes_per_newton;
        // Round half away from zero without libm; |offset| < 4096, so the cast is exact.
        let rounded = if offset >= 0.0 {
            (offset + 0.5) as i32
        } else {
            (offset - 0.5) as i32
        };
        (i32::from(self.zero_code) + rounded).clamp(1, 4095) as u16
    }

    /// The force a DAC code commands, N (the inverse of [`Self::force_to_code`]).
    pub fn code_to_force(&self, code: u16) -> f32 {
        (f32::from(code) - f32::from(self.zero_code)) / self.codes_per_newton
    }
}

impl Default for DriveCalibration {
    fn default() -> Self {
        Self::NOMINAL
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn nominal_codes_match_the_wiring_table() {
        let c = DriveCalibration::NOMINAL;
        assert_eq!(c.validate(), Ok(()));
        assert_eq!(c.force_to_code(0.0), 2048);
        assert_eq!(c.force_to_code(f32::NAN), 2048);
        assert_eq!(c.force_to_code(FULL_SCALE_N), 4095);
        assert_eq!(c.force_to_code(-FULL_SCALE_N), 1);
        assert_eq!(c.force_to_code(1e9), 4095);
        assert_eq!(c.force_to_code(f32::NEG_INFINITY), 1);
    }

    #[test]
    fn a_discovery_board_at_3_0_v_gets_its_own_zero_and_gain() {
        // 1.65 V at the drive's zero is code 2253 with a 3.0 V reference; the gain is 10 %
        // higher in codes.
        let c = DriveCalibration {
            zero_code: 2253,
            codes_per_newton: DriveCalibration::NOMINAL.codes_per_newton * 1.1,
        };
        assert_eq!(
            c.validate(),
            Err(CalibrationError::FullScale {
                zero_code: 2253,
                codes_per_newton: c.codes_per_newton
            }),
            "at 3.0 V full scale does not fit: the offset stage must be referenced to VDDA"
        );
        let fits = DriveCalibration {
            zero_code: 2100,
            codes_per_newton: DriveCalibration::NOMINAL.codes_per_newton * 0.95,
        };
        assert_eq!(fits.validate(), Ok(()));
        assert_eq!(fits.force_to_code(0.0), 2100);
    }

    #[test]
    fn bad_calibrations_are_refused() {
        let nominal = DriveCalibration::NOMINAL;
        let bad = [
            DriveCalibration {
                zero_code: 2048 + 411,
                ..nominal
            },
            DriveCalibration {
                codes_per_newton: f32::NAN,
                ..nominal
            },
            DriveCalibration {
                codes_per_newton: nominal.codes_per_newton * 0.5,
                ..nominal
            },
            DriveCalibration {
                codes_per_newton: nominal.codes_per_newton * 1.2,
                ..nominal
            },
        ];
        for c in bad {
            assert!(c.validate().is_err(), "{c:?}");
        }
    }

    proptest! {
        /// Within full scale, a code commands its force to half a code.
        #[test]
        fn round_trip_within_half_a_code(
            f in -FULL_SCALE_N..FULL_SCALE_N,
            zero in 1900u16..2200,
            gain in 0.8f32..1.05,
        ) {
            let c = DriveCalibration {
                zero_code: zero,
                codes_per_newton: DriveCalibration::NOMINAL.codes_per_newton * gain,
            };
            prop_assume!(c.validate().is_ok());
            let back = c.code_to_force(c.force_to_code(f));
            prop_assert!((back - f).abs() <= 0.5 / c.codes_per_newton + 1e-3);
        }
    }
}
