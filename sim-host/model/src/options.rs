//! Integration options of a run (tolerances, step limits, what to record) and their check.

use crate::error::SimError;

/// Integration options.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    /// Relative tolerance of the Dormand-Prince 5(4) step control.
    pub rtol: f64,
    /// Absolute tolerance (m, m/s, N), applied to every state component.
    pub atol: f64,
    /// Record a time series (the `series` of a jump's outcome).
    pub record_series: bool,
    /// Spacing of the recorded series, s (dense output; events are added as extra rows).
    pub series_interval_s: f64,
    /// Largest step, s.
    pub max_step_s: f64,
    /// Give up after this many steps.
    pub max_steps: u64,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: 1e-11,
            record_series: false,
            series_interval_s: 5e-4,
            max_step_s: 0.01,
            max_steps: 2_000_000,
        }
    }
}

/// Check integration options: tolerances positive and finite.
pub fn check_options(opts: &SimOptions) -> Result<(), SimError> {
    let bad = |field, value: f64, allowed: &str| SimError::InvalidInput {
        field,
        value: value.to_string(),
        allowed: allowed.into(),
    };
    if !(opts.rtol.is_finite() && opts.rtol > 0.0 && opts.rtol < 1.0) {
        return Err(bad("rtol", opts.rtol, "0 < rtol < 1"));
    }
    if !(opts.atol.is_finite() && opts.atol > 0.0) {
        return Err(bad("atol", opts.atol, "atol > 0"));
    }
    if !(opts.max_step_s.is_finite() && opts.max_step_s > 0.0) {
        return Err(bad("max_step_s", opts.max_step_s, "max_step_s > 0"));
    }
    if opts.record_series && !(opts.series_interval_s.is_finite() && opts.series_interval_s > 0.0) {
        return Err(bad(
            "series_interval_s",
            opts.series_interval_s,
            "series_interval_s > 0",
        ));
    }
    Ok(())
}
