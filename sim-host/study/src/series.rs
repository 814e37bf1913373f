//! One jump's time series as `trajectory.csv`.

use std::fmt;
use std::path::Path;

use sandjumper_model::record::SeriesRow;
use sandjumper_output::OutputError;

/// Header of `trajectory.csv` (SI units in the names).
pub const SERIES_HEADER: [&str; 9] = [
    "t_s", "x_m_m", "x_r_m", "x_f_m", "p_m", "f_s_n", "f_gm_n", "m_a_kg", "mode",
];

/// Write a time series as `trajectory.csv`: [`SERIES_HEADER`], one row per sample, floats in
/// their shortest exact representation.
pub fn write_series_csv(path: &Path, rows: &[SeriesRow]) -> Result<(), OutputError> {
    let err = |e: &dyn fmt::Display| OutputError {
        path: path.to_path_buf(),
        action: "write".into(),
        reason: e.to_string(),
    };
    let mut w = csv::Writer::from_path(path).map_err(|e| err(&e))?;
    w.write_record(SERIES_HEADER).map_err(|e| err(&e))?;
    for r in rows {
        let nums = [r.t_s, r.x_m, r.x_r, r.x_f, r.p, r.f_s, r.f_gm, r.m_a].map(|v| v.to_string());
        w.write_record(nums.iter().map(String::as_str).chain([r.mode.as_str()]))
            .map_err(|e| err(&e))?;
    }
    w.flush().map_err(|e| err(&e))
}
