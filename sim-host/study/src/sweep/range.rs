//! Parameter ranges written `A:B:STEP` (inclusive of both ends) or a single value `A`.
//!
//! The values are computed as `A + i * STEP` (never by accumulating `STEP`), and rounded to
//! the number of decimals written in the spec, so `0.57:0.62:0.01` gives exactly the six
//! values `0.57, 0.58, ..., 0.62` (as f64 parses them) and the last one is never lost or
//! duplicated by floating-point error.

use core::fmt;
use core::str::FromStr;

/// Relative slack (in units of `STEP`) with which the end point `B` still counts as reached.
const END_SLACK_STEPS: f64 = 1e-9;
/// Most values one range may expand to (a typo like `1:1000000:0.0001` is refused, not run).
pub const MAX_RANGE_VALUES: usize = 1_000_000;

/// An inclusive range of f64 values, as written on the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct ValueRange {
    /// What the user wrote, e.g. `"5:20:0.5"` (kept for messages and metadata).
    pub spec: String,
    /// The expanded values, ascending.
    pub values: Vec<f64>,
}

/// Why a range spec was refused. The message names the spec and what is allowed.
#[derive(Clone, Debug, PartialEq)]
pub enum RangeError {
    /// Not `A`, nor `A:B:STEP`.
    Shape { spec: String },
    /// A part that is not a finite number.
    Number { spec: String, part: String },
    /// `STEP <= 0`.
    Step { spec: String, step: f64 },
    /// `B < A`.
    Reversed { spec: String, start: f64, end: f64 },
    /// More than [`MAX_RANGE_VALUES`] values.
    TooMany { spec: String, count: f64 },
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Shape { spec } => write!(
                f,
                "`{spec}` is not a range: write a single value `A` or `A:B:STEP` (inclusive of both ends)"
            ),
            Self::Number { spec, part } => {
                write!(f, "`{part}` in range `{spec}` is not a finite number")
            }
            Self::Step { spec, step } => write!(
                f,
                "range `{spec}` has step {step}: the step must be positive (write A:B:STEP with STEP > 0)"
            ),
            Self::Reversed { spec, start, end } => write!(
                f,
                "range `{spec}` ends ({end}) below its start ({start}): write A:B:STEP with A <= B"
            ),
            Self::TooMany { spec, count } => write!(
                f,
                "range `{spec}` expands to {count:.0} values; at most {MAX_RANGE_VALUES} are allowed"
            ),
        }
    }
}

impl std::error::Error for RangeError {}

fn parse_part(spec: &str, part: &str) -> Result<f64, RangeError> {
    let part = part.trim();
    match part.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(RangeError::Number {
            spec: spec.to_string(),
            part: part.to_string(),
        }),
    }
}

/// Digits after the decimal point as written (`"0.570"` -> 3), or `None` for exponent notation.
fn written_decimals(part: &str) -> Option<usize> {
    let part = part.trim();
    if part.contains(['e', 'E']) {
        return None;
    }
    Some(part.split_once('.').map_or(0, |(_, frac)| frac.len()))
}

/// Round `value` to `decimals` decimal places through the decimal representation (exact
/// for the values a user can type).
fn round_decimals(value: f64, decimals: usize) -> f64 {
    format!("{value:.decimals$}").parse().unwrap_or(value)
}

impl ValueRange {
    /// Parse `A` or `A:B:STEP`. See the module docs for the rules.
    pub fn parse(spec: &str) -> Result<Self, RangeError> {
        let parts: Vec<&str> = spec.split(':').collect();
        let values = match parts.as_slice() {
            [single] => vec![parse_part(spec, single)?],
            [a, b, step] => {
                let start = parse_part(spec, a)?;
                let end = parse_part(spec, b)?;
                let step_v = parse_part(spec, step)?;
                if step_v <= 0.0 {
                    return Err(RangeError::Step {
                        spec: spec.to_string(),
                        step: step_v,
                    });
                }
                if end < start {
                    return Err(RangeError::Reversed {
                        spec: spec.to_string(),
                        start,
                        end,
                    });
                }
                let steps = ((end - start) / step_v + END_SLACK_STEPS).floor();
                if steps >= MAX_RANGE_VALUES as f64 {
                    return Err(RangeError::TooMany {
                        spec: spec.to_string(),
                        count: steps + 1.0,
                    });
                }
                let decimals = [a, b, step]
                    .iter()
                    .map(|p| written_decimals(p))
                    .try_fold(0usize, |acc, d| d.map(|d| acc.max(d)));
                // `steps` is a non-negative integer below MAX_RANGE_VALUES here.
                let count = steps as usize + 1;
                (0..count)
                    .map(|i| {
                        let v = start + i as f64 * step_v;
                        match decimals {
                            Some(d) => round_decimals(v, d),
                            None => v,
                        }
                    })
                    .collect()
            }
            _ => {
                return Err(RangeError::Shape {
                    spec: spec.to_string(),
                });
            }
        };
        Ok(Self {
            spec: spec.to_string(),
            values,
        })
    }

    /// A spec (`A` or `A:B:STEP`) that [`ValueRange::parse`] expands to exactly `values`, if
    /// there is one: how a list of values is written on a command line again (a Slurm task's
    /// sweep). `None` for no values, or values that are no such range.
    pub fn written_for(values: &[f64]) -> Option<String> {
        match values {
            [] => None,
            [v] => Some(format!("{v}")),
            [first, .., last] => {
                let step = (last - first) / (values.len() - 1) as f64;
                // The step as written with 0, 1, 2 ... decimals (each `{}` above is the shortest
                // text that reads back as the same f64): the first that gives `values` back.
                (0..=17).find_map(|d| {
                    let spec = format!("{first}:{last}:{step:.d$}");
                    (Self::parse(&spec).ok()?.values == values).then_some(spec)
                })
            }
        }
    }

    /// A range holding one value.
    pub fn single(value: f64) -> Self {
        Self {
            spec: format!("{value}"),
            values: vec![value],
        }
    }

    /// Smallest value.
    pub fn min(&self) -> f64 {
        self.values.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Largest value.
    pub fn max(&self) -> f64 {
        self.values
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

impl FromStr for ValueRange {
    type Err = RangeError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse(s)
    }
}

impl fmt::Display for ValueRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spec)
    }
}

/// Parse a range and check each of its values with `check` (the message names the range).
pub fn parse_range_checked(
    s: &str,
    check: fn(f64) -> Result<f64, String>,
) -> Result<ValueRange, String> {
    let r = ValueRange::parse(s).map_err(|e| e.to_string())?;
    for &v in &r.values {
        check(v).map_err(|e| format!("range `{s}`: {e}"))?;
    }
    Ok(r)
}

/// Value parser: a frequency range `A:B:STEP` in Hz, every value checked
/// ([`sandjumper_output::parse::check_freq`]).
pub fn parse_freq_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, sandjumper_output::parse::check_freq)
}

/// Value parser: a delay range `A:B:STEP` in s, every value checked
/// ([`sandjumper_output::parse::check_tau`]).
pub fn parse_tau_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, sandjumper_output::parse::check_tau)
}

/// Value parser: a packing-fraction range `A:B:STEP`, every value checked
/// ([`sandjumper_output::parse::check_phi`]).
pub fn parse_phi_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, sandjumper_output::parse::check_phi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn values_are_written_as_the_range_that_gives_them_back() {
        for spec in [
            "0.57:0.62:0.01",
            "8:14:2",
            "10",
            "0.1",
            "1e-3",
            "0:0.3:0.05",
            "5:20:0.5",
        ] {
            let values = ValueRange::parse(spec).unwrap().values;
            let written = ValueRange::written_for(&values).unwrap();
            assert_eq!(
                ValueRange::parse(&written).unwrap().values,
                values,
                "{spec} -> {written}"
            );
        }
        assert_eq!(ValueRange::written_for(&[0.57, 0.6, 0.61]), None);
        assert_eq!(ValueRange::written_for(&[12.0, 10.0]), None);
        assert_eq!(ValueRange::written_for(&[]), None);
    }

    proptest! {
        #[test]
        fn any_typed_range_is_written_back_to_its_values(
            start in 0u32..2000, count in 1u32..40, step in 1u32..500, decimals in 0u32..4
        ) {
            let scale = 10f64.powi(decimals as i32);
            let d = decimals as usize;
            let (a, s) = (f64::from(start) / scale, f64::from(step) / scale);
            let b = a + f64::from(count - 1) * s;
            let spec = format!("{a:.d$}:{b:.d$}:{s:.d$}");
            let values = ValueRange::parse(&spec).unwrap().values;
            let written = ValueRange::written_for(&values).unwrap();
            prop_assert_eq!(ValueRange::parse(&written).unwrap().values, values);
        }
    }

    #[test]
    fn single_value_is_a_range_of_one() {
        assert_eq!(ValueRange::parse("12.5").unwrap().values, vec![12.5]);
    }

    #[test]
    fn packing_fractions_hit_both_ends_exactly() {
        let r = ValueRange::parse("0.57:0.62:0.01").unwrap();
        assert_eq!(r.values, vec![0.57, 0.58, 0.59, 0.6, 0.61, 0.62]);
    }

    #[test]
    fn tenth_steps_do_not_lose_the_end() {
        // 0.1 * 3 = 0.30000000000000004 > 0.3 in f64: the end must still be included.
        let r = ValueRange::parse("0:0.3:0.1").unwrap();
        assert_eq!(r.values, vec![0.0, 0.1, 0.2, 0.3]);
    }

    #[test]
    fn step_that_overshoots_stops_before_the_end() {
        let r = ValueRange::parse("1:2:0.4").unwrap();
        assert_eq!(r.values, vec![1.0, 1.4, 1.8]);
    }

    #[test]
    fn degenerate_range_is_one_value() {
        assert_eq!(ValueRange::parse("5:5:1").unwrap().values, vec![5.0]);
    }

    #[test]
    fn bad_specs_are_refused_with_a_reason() {
        assert!(matches!(
            ValueRange::parse("1:2:0"),
            Err(RangeError::Step { .. })
        ));
        assert!(matches!(
            ValueRange::parse("1:2:-1"),
            Err(RangeError::Step { .. })
        ));
        assert!(matches!(
            ValueRange::parse("2:1:0.5"),
            Err(RangeError::Reversed { .. })
        ));
        assert!(matches!(
            ValueRange::parse("1:2"),
            Err(RangeError::Shape { .. })
        ));
        assert!(matches!(
            ValueRange::parse("1:x:1"),
            Err(RangeError::Number { .. })
        ));
        assert!(matches!(
            ValueRange::parse("nan"),
            Err(RangeError::Number { .. })
        ));
        assert!(matches!(
            ValueRange::parse("0:1e9:1e-3"),
            Err(RangeError::TooMany { .. })
        ));
        let msg = ValueRange::parse("1:2:0").unwrap_err().to_string();
        assert!(msg.contains("1:2:0") && msg.contains("positive"), "{msg}");
    }

    proptest! {
        /// For any integer-step decimal range the count is exact, the ends are both present,
        /// the values ascend with the written step, and nothing exceeds the end.
        #[test]
        fn decimal_ranges_are_exact(start_c in -5000i64..5000, n in 0usize..200, step_c in 1i64..500) {
            let start = start_c as f64 / 100.0;
            let step = step_c as f64 / 100.0;
            let end = (start_c + n as i64 * step_c) as f64 / 100.0;
            let spec = format!("{start:.2}:{end:.2}:{step:.2}");
            let r = ValueRange::parse(&spec).unwrap();
            prop_assert_eq!(r.values.len(), n + 1);
            prop_assert_eq!(r.values[0], start);
            prop_assert_eq!(*r.values.last().unwrap(), end);
            for w in r.values.windows(2) {
                prop_assert!((w[1] - w[0] - step).abs() < 1e-9);
            }
        }

        /// Arbitrary float ranges: never past the end (beyond slack), never more than one step
        /// short of it, strictly ascending.
        #[test]
        fn float_ranges_cover_the_interval(start in -1e3f64..1e3, len in 0f64..1e3, step in 1e-2f64..1e2) {
            let end = start + len;
            let spec = format!("{start:e}:{end:e}:{step:e}");
            let r = ValueRange::parse(&spec).unwrap();
            let last = *r.values.last().unwrap();
            prop_assert!(last <= end + step * 1e-6);
            prop_assert!(end - last < step * (1.0 + 1e-9));
            for w in r.values.windows(2) {
                prop_assert!(w[1] > w[0]);
            }
        }
    }
}
