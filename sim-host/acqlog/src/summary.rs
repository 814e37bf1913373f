//! What `sandjumper log check` reports about a log.

use super::AcqLog;
use sandjumper_core::sample::flags::FAULTED;
use serde::Serialize;
use std::fmt;

/// Duration, rate, gaps, faults, frames and position range of a log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LogSummary {
    /// Sample rows, interpolated ones included.
    pub samples: usize,
    /// First to last sample, s.
    pub duration_s: f64,
    /// `rate_hz` from the metadata.
    pub rate_hz: f64,
    /// Mean rate from the time column (least squares), Hz.
    pub measured_rate_hz: Option<f64>,
    /// Gaps filled by interpolation (only with `--allow-gaps`).
    pub gaps: usize,
    /// Samples interpolated into those gaps.
    pub interpolated_samples: u64,
    /// `dropped_samples` from the metadata (losses the acquisition counted itself).
    pub dropped_samples: u64,
    /// Rows with a nonzero `flags` value.
    pub flagged_samples: usize,
    /// Rows with the core's `FAULTED` flag set (a latched fault).
    pub faulted_samples: usize,
    /// Time of the first row with a latched fault, s.
    pub first_fault_t_s: Option<f64>,
    /// Distinct nonzero `flags` values with the time each first appeared, s.
    pub flag_values: Vec<FlagFirstSeen>,
    /// Rows with a camera frame number.
    pub camera_frames: usize,
    /// Frame numbers missing between the first and the last frame.
    pub camera_frames_missing: u64,
    /// Rows with a measured rod height.
    pub rod_height_samples: usize,
    /// Lowest and highest motor position relative to the rod, m.
    pub position_range_m: (f64, f64),
    /// Largest |force command|, N, if the log has one.
    pub peak_force_cmd_n: Option<f64>,
    /// Columns the log has, in writing order.
    pub columns: Vec<&'static str>,
}

/// A flags value and the first time it was seen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlagFirstSeen {
    /// The flags word.
    pub flags: u32,
    /// Time of the first row with it, s.
    pub first_t_s: f64,
}

impl LogSummary {
    /// Summarises a log that the reader accepted.
    pub fn of(log: &AcqLog) -> Self {
        let mut flag_values: Vec<FlagFirstSeen> = Vec::new();
        let mut flagged = 0;
        let mut faulted = 0;
        let mut first_fault = None;
        let mut frames = 0;
        let mut frame_range: Option<(u64, u64)> = None;
        let mut rod = 0;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut peak_force: Option<f64> = None;
        for row in &log.rows {
            if let Some(f) = row.flags.filter(|f| *f != 0) {
                flagged += 1;
                if f & u32::from(FAULTED) != 0 {
                    faulted += 1;
                    first_fault.get_or_insert(row.t_s);
                }
                if !flag_values.iter().any(|v| v.flags == f) {
                    flag_values.push(FlagFirstSeen {
                        flags: f,
                        first_t_s: row.t_s,
                    });
                }
            }
            if let Some(n) = row.camera_frame {
                frames += 1;
                frame_range = Some(match frame_range {
                    None => (n, n),
                    Some((a, b)) => (a.min(n), b.max(n)),
                });
            }
            if row.rod_height_m.is_some() {
                rod += 1;
            }
            let p = log.meta.position_m(row.encoder_counts);
            lo = lo.min(p);
            hi = hi.max(p);
            if let Some(f) = row.force_cmd_n {
                peak_force = Some(peak_force.unwrap_or(0.0).max(f.abs()));
            }
        }
        let camera_frames_missing = frame_range
            .map(|(a, b)| (b - a + 1).saturating_sub(frames as u64))
            .unwrap_or(0);
        Self {
            samples: log.rows.len(),
            duration_s: log.duration_s(),
            rate_hz: log.meta.rate_hz,
            measured_rate_hz: log.measured_period_s().map(|p| 1.0 / p),
            gaps: log.gaps.len(),
            interpolated_samples: log.interpolated_samples(),
            dropped_samples: log.meta.dropped_samples,
            flagged_samples: flagged,
            faulted_samples: faulted,
            first_fault_t_s: first_fault,
            flag_values,
            camera_frames: frames,
            camera_frames_missing,
            rod_height_samples: rod,
            position_range_m: (lo, hi),
            peak_force_cmd_n: peak_force,
            columns: log.columns.iter().map(|c| c.name()).collect(),
        }
    }
}

impl fmt::Display for LogSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "samples:            {}", self.samples)?;
        writeln!(f, "duration:           {:.6} s", self.duration_s)?;
        match self.measured_rate_hz {
            Some(m) => writeln!(
                f,
                "rate:               {} Hz (time column: {m:.3} Hz)",
                self.rate_hz
            )?,
            None => writeln!(f, "rate:               {} Hz", self.rate_hz)?,
        }
        writeln!(f, "columns:            {}", self.columns.join(","))?;
        writeln!(
            f,
            "gaps:               {} ({} samples interpolated)",
            self.gaps, self.interpolated_samples
        )?;
        writeln!(
            f,
            "dropped samples:    {} (from metadata)",
            self.dropped_samples
        )?;
        writeln!(f, "flagged samples:    {}", self.flagged_samples)?;
        match self.first_fault_t_s {
            Some(t) => writeln!(
                f,
                "faults:             {} samples with a latched fault, first at t = {t:.6} s",
                self.faulted_samples
            )?,
            None => writeln!(f, "faults:             none")?,
        }
        for v in &self.flag_values {
            writeln!(
                f,
                "  flags 0x{:08x} first at t = {:.6} s",
                v.flags, v.first_t_s
            )?;
        }
        writeln!(
            f,
            "camera frames:      {} ({} missing in sequence)",
            self.camera_frames, self.camera_frames_missing
        )?;
        writeln!(f, "rod height samples: {}", self.rod_height_samples)?;
        writeln!(
            f,
            "position range:     {:.6} .. {:.6} m",
            self.position_range_m.0, self.position_range_m.1
        )?;
        if let Some(p) = self.peak_force_cmd_n {
            writeln!(f, "peak |force_cmd|:   {p:.3} N")?;
        }
        Ok(())
    }
}
