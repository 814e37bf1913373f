//! Number parsers that say what is allowed: each returns the value or one message naming the
//! input and the allowed range (the command line uses them as value parsers; campaign files
//! and the DEM's option strings use them too).

use sandjumper_core::trajectory::{MAX_FREQ_HZ, MAX_TAU_S, MIN_FREQ_HZ};

/// A finite number.
pub fn parse_number(s: &str) -> Result<f64, String> {
    number_within(s, |_| true).ok_or_else(|| format!("`{s}` is not a finite number"))
}

/// `s` as a finite number for which `allowed` holds, or `None`: the one test behind the value
/// parsers of the commands' bounded numbers, each of which words its own refusal.
pub fn number_within(s: &str, allowed: impl Fn(f64) -> bool) -> Option<f64> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|&v| v.is_finite() && allowed(v))
}

/// Parse a strictly positive number (a scale, a rate, a length).
pub fn parse_positive(s: &str) -> Result<f64, String> {
    parse_number(s).and_then(|v| {
        if v > 0.0 {
            Ok(v)
        } else {
            Err(format!("`{s}` not allowed (allowed: > 0)"))
        }
    })
}

/// Parse a strictly positive number that is `what` (named in the error: "`0` is not a frame
/// rate in frames/s: a finite number > 0").
pub fn parse_positive_as(s: &str, what: &str) -> Result<f64, String> {
    parse_number(s)
        .ok()
        .filter(|&v| v > 0.0)
        .ok_or_else(|| format!("`{s}` is not {what}: a finite number > 0"))
}

/// Check a forcing frequency: positive, within the trajectory's supported band.
pub fn check_freq(f: f64) -> Result<f64, String> {
    if f <= 0.0 {
        return Err(format!(
            "frequency {f} Hz is not positive (allowed: {MIN_FREQ_HZ}..={MAX_FREQ_HZ} Hz)"
        ));
    }
    if !(MIN_FREQ_HZ..=MAX_FREQ_HZ).contains(&f) {
        return Err(format!(
            "frequency {f} Hz out of range (allowed: {MIN_FREQ_HZ}..={MAX_FREQ_HZ} Hz)"
        ));
    }
    Ok(f)
}

/// Check a delay: non-negative, at most the trajectory's longest delay.
pub fn check_tau(t: f64) -> Result<f64, String> {
    if t < 0.0 {
        return Err(format!(
            "delay tau {t} s is negative (allowed: 0..={MAX_TAU_S} s)"
        ));
    }
    if t > MAX_TAU_S {
        return Err(format!(
            "delay tau {t} s out of range (allowed: 0..={MAX_TAU_S} s)"
        ));
    }
    Ok(t)
}

/// Check a packing fraction: a fraction in (0, 1). Whether a preset exists is checked when
/// the parameters are resolved (a params file may supply the sand values).
pub fn check_phi(phi: f64) -> Result<f64, String> {
    if phi > 0.0 && phi < 1.0 {
        Ok(phi)
    } else {
        Err(format!(
            "packing fraction {phi} is not a fraction (allowed: 0 < phi < 1; presets 0.57..=0.62)"
        ))
    }
}

/// clap value parser: a forcing frequency in Hz ([`check_freq`]).
pub fn parse_freq(s: &str) -> Result<f64, String> {
    check_freq(parse_number(s)?)
}

/// clap value parser: a delay in s ([`check_tau`]).
pub fn parse_tau(s: &str) -> Result<f64, String> {
    check_tau(parse_number(s)?)
}

/// clap value parser: a packing fraction ([`check_phi`]).
pub fn parse_phi(s: &str) -> Result<f64, String> {
    check_phi(parse_number(s)?)
}

/// clap value parser: an integrator relative tolerance, 1e-14 <= rtol < 1.
pub fn parse_rtol(s: &str) -> Result<f64, String> {
    let r = parse_number(s)?;
    if (1e-14..1.0).contains(&r) {
        Ok(r)
    } else {
        Err(format!(
            "rtol {r} out of range (allowed: 1e-14 <= rtol < 1)"
        ))
    }
}

/// clap value parser: a gain-lowering factor (the position gain's multiplier during a delayed
/// stutter's delay), 0 < factor <= 1.
pub fn parse_gain_lowering(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!(
            "gain-lowering factor {v} out of range (allowed: 0 < factor <= 1; e.g. 0.05)"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::number_within;

    #[test]
    fn number_within_takes_finite_numbers_in_bounds_around_blanks() {
        let unit = |v: f64| (0.0..=1.0).contains(&v);
        assert_eq!(number_within(" 0.5\t", unit), Some(0.5));
        assert_eq!(number_within("0", unit), Some(0.0));
        assert_eq!(number_within("1", unit), Some(1.0));
        assert_eq!(number_within("1e0", unit), Some(1.0));
        for refused in [
            "1.0000001",
            "-0.1",
            "nan",
            "NaN",
            "inf",
            "-inf",
            "",
            "0.5 s",
            "x",
        ] {
            assert_eq!(number_within(refused, unit), None, "{refused:?}");
        }
        assert_eq!(number_within("inf", |_| true), None);
        assert_eq!(number_within("1e308", |_| true), Some(1e308));
    }
}
