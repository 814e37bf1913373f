//! Replay of an acquisition log in the simulator (the paper's method): the encoder record
//! becomes the prescribed motor stroke `p(t)` of a kinematic run.
//!
//! Method. Positions `p_k = encoder_sign * counts_k / counts_per_m + position_offset_m` are
//! taken on the log's own time grid (the least-squares sampling period of its time column;
//! replay time 0 is the log's first sample). A cubic Savitzky-Golay filter
//! ([`crate::replay::differentiate`]) gives the smoothed `p`, `p'` and `p''` at every sample; between
//! samples each is interpolated linearly, so `p''(t)` is continuous inside the log. Before
//! the first sample the stroke holds the first smoothed position with zero velocity and
//! acceleration, after the last it holds the last one (docs/model.md section 2, "hold last"); those
//! two instants are the stroke's breakpoints, where the integrator stops exactly.
//!
//! Default window: [`DEFAULT_WINDOW_S`] = 1 ms (11 samples at 10 kHz), whose second-derivative
//! cut-off is about 640 Hz at 10 kHz. Why so short: the plant responds to `p` itself, not to
//! `p''` (with `y = x_r + (m_m/M) p` the kinematic equation reads `M y'' = F_s - M g`), so
//! quantization noise in `p''` (a few m/s^2 per sample at 1 um) moves the rod by about one
//! count; but a position servo rings at a few hundred Hz (the SIL controller at ~500 Hz,
//! hundreds of m/s^2), and a wider window that removes that ringing changes the replayed jump
//! by several percent. Measured (tests `replay`, `replay_hil`): quantized exact sine jumps
//! within 1 %, HIL logs within 2 % of the original run. `--window-ms` changes it. The peak
//! motor force of a replay includes the quantization noise of `p''` and so reads high.

pub mod differentiate;
mod request;

pub use request::{ReplayOutcome, ReplayRequest, parse_window_ms, run, run_into, run_log};

use crate::replay::differentiate::SavitzkyGolay;
use sandjumper_acqlog::AcqLog;
use sandjumper_core::sample::flags;
use sandjumper_core::trajectory::Kinematics;
use sandjumper_model::jump::{JumpOutcome, kinematic_at_rest, run_kinematic};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::SeriesRow;
use sandjumper_model::trajectory::Stroke;
use serde::Serialize;

/// Default Savitzky-Golay window, s.
pub const DEFAULT_WINDOW_S: f64 = 1.0e-3;

/// A log's motor stroke as a prescribed `p(t)` for the kinematic simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayStroke {
    period_s: f64,
    position_m: Vec<f64>,
    velocity_m_s: Vec<f64>,
    accel_m_s2: Vec<f64>,
    push_off_start_s: f64,
    /// Log time of replay time 0 (the first sample's `t_s`), s.
    pub log_start_s: f64,
    /// Differentiator used.
    pub filter: SavitzkyGolay,
    /// Its second-derivative cut-off at the log's rate, Hz.
    pub cutoff_hz: f64,
}

impl ReplayStroke {
    /// Builds the stroke from a log with a cubic Savitzky-Golay window of `window_s`.
    pub fn from_log(log: &AcqLog, window_s: f64) -> Result<Self, String> {
        let period_s = log
            .measured_period_s()
            .ok_or_else(|| "a log needs at least two samples to be replayed".to_string())?;
        let rate_hz = 1.0 / period_s;
        let filter = SavitzkyGolay::for_window(rate_hz, window_s)?;
        let positions = log.positions_m();
        let d = filter.apply(&positions, period_s).map_err(|e| {
            format!(
                "{e} ({:.3} ms at {rate_hz:.1} Hz): the log is too short to replay with this window",
                filter.window_len() as f64 * period_s * 1e3
            )
        })?;
        let log_start_s = log.rows[0].t_s;
        Ok(Self {
            period_s,
            position_m: d.value,
            velocity_m_s: d.first,
            accel_m_s2: d.second,
            push_off_start_s: push_off_start_in_log(log)
                .map_or(0.0, |t| (t - log_start_s).max(0.0)),
            log_start_s,
            cutoff_hz: filter.cutoff_hz(rate_hz),
            filter,
        })
    }

    /// Sampling period of the replayed grid, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.position_m.len()
    }

    /// Whether there are no samples (never true for a stroke built from a log).
    pub fn is_empty(&self) -> bool {
        self.position_m.is_empty()
    }

    /// Largest |p''| of the smoothed stroke, m/s^2.
    pub fn peak_accel_m_s2(&self) -> f64 {
        self.accel_m_s2.iter().fold(0.0, |m, a| m.max(a.abs()))
    }
}

/// Start of the push-off half in log time. From the controller's flags when the log has them:
/// the first sample flagged `PUSH_OFF`. Otherwise from the `jump_*` metadata of a one-cycle
/// sine (0 for a single jump, `T/2` for a stutter, `T/2 + tau` for a delayed stutter), counted
/// from the first sample flagged `RUNNING`, else from log time `t_s = 0` if the log spans it
/// (a log whose time axis is the trajectory's), else from the log's first sample.
fn push_off_start_in_log(log: &AcqLog) -> Option<f64> {
    let first_flagged = |bit: u16| {
        log.rows
            .iter()
            .find(|r| r.flags.is_some_and(|f| f & u32::from(bit) != 0))
            .map(|r| r.t_s)
    };
    if let Some(t) = first_flagged(flags::PUSH_OFF) {
        return Some(t);
    }
    let jump = log.meta.jump.as_ref()?;
    let half = 0.5 / jump.freq_hz.filter(|f| *f > 0.0)?;
    let offset = match jump.kind.as_str() {
        "single" => 0.0,
        "stutter" => half,
        "delayed" | "delayed-stutter" | "delayed_stutter" => half + jump.tau_s.unwrap_or(0.0),
        _ => return None,
    };
    let (first, last) = (log.rows.first()?.t_s, log.rows.last()?.t_s);
    let start = first_flagged(flags::RUNNING).unwrap_or(if (first..=last).contains(&0.0) {
        0.0
    } else {
        first
    });
    Some(start + offset)
}

impl Stroke for ReplayStroke {
    fn eval(&self, t_s: f64) -> Kinematics {
        let last = self.position_m.len() - 1;
        let hold = |i: usize| Kinematics {
            position_m: self.position_m[i],
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        };
        if t_s.is_nan() || t_s < 0.0 {
            return hold(0);
        }
        let x = t_s / self.period_s;
        if x >= last as f64 {
            return hold(last);
        }
        let i = x.floor() as usize;
        let frac = x - i as f64;
        let lerp = |v: &[f64]| v[i] + (v[i + 1] - v[i]) * frac;
        Kinematics {
            position_m: lerp(&self.position_m),
            velocity_m_s: lerp(&self.velocity_m_s),
            accel_m_s2: lerp(&self.accel_m_s2),
        }
    }

    fn breakpoints_s(&self) -> Vec<f64> {
        vec![0.0, self.end_s()]
    }

    fn end_s(&self) -> f64 {
        (self.position_m.len() - 1) as f64 * self.period_s
    }

    fn push_off_start_s(&self) -> f64 {
        self.push_off_start_s
    }
}

/// How the log was turned into a stroke: reported with every replay.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReplayInfo {
    /// Samples replayed (interpolated ones included).
    pub samples: usize,
    /// Samples that were interpolated into gaps (`--allow-gaps`).
    pub interpolated_samples: u64,
    /// `rate_hz` from the metadata.
    pub rate_hz: f64,
    /// Rate of the replayed grid (least squares over the time column), Hz.
    pub grid_rate_hz: f64,
    /// Log time of replay time 0, s.
    pub log_start_s: f64,
    /// Replay time of the last sample, s.
    pub log_end_s: f64,
    /// Differentiator: `savitzky-golay`.
    pub differentiator: &'static str,
    /// Window, samples.
    pub window_samples: usize,
    /// Window, s.
    pub window_s: f64,
    /// Polynomial order.
    pub polynomial_order: usize,
    /// -3 dB frequency of the second derivative, Hz.
    pub cutoff_hz: f64,
    /// Largest |p''| of the smoothed stroke, m/s^2.
    pub peak_accel_m_s2: f64,
    /// Start of the push-off half (replay time) used for the final jump height, s.
    pub push_off_start_s: f64,
}

/// Predicted vs measured, when the log carries measurements.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasuredComparison {
    /// `measured_jump_height_m` from the metadata, m.
    pub measured_jump_height_m: Option<f64>,
    /// The replay's jump height, m.
    pub predicted_jump_height_m: f64,
    /// `(predicted - measured) / measured`, when both exist and measured > 0.
    pub jump_height_relative_error: Option<f64>,
    /// Rows with a measured rod height inside the simulated run.
    pub rod_height_samples: usize,
    /// RMS of predicted minus measured rod height over those rows, m.
    pub rod_height_rms_error_m: Option<f64>,
    /// Highest measured rod height, m.
    pub max_measured_rod_height_m: Option<f64>,
}

/// A replayed log: the simulation's outcome (as `sandjumper jump` reports it), how the stroke
/// was made, and predicted vs measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Replayed {
    /// The kinematic run driven by the log.
    pub outcome: JumpOutcome,
    /// How the stroke was made.
    pub info: ReplayInfo,
    /// Predicted vs measured (None when the log has no measurement).
    pub measured: Option<MeasuredComparison>,
}

/// Replays `log` through the kinematic simulation with `model` and `params` (docs/model.md: the
/// paper's method). Errors are bad input (a log too short for the window, a simulation that
/// fails): a message saying what and why.
pub fn replay_log(
    log: &AcqLog,
    params: &Params,
    model: ModelName,
    window_s: f64,
    opts: &SimOptions,
) -> Result<Replayed, String> {
    let stroke = ReplayStroke::from_log(log, window_s)?;
    let info = ReplayInfo {
        samples: stroke.len(),
        interpolated_samples: log.interpolated_samples(),
        rate_hz: log.meta.rate_hz,
        grid_rate_hz: 1.0 / stroke.period_s(),
        log_start_s: stroke.log_start_s,
        log_end_s: stroke.end_s(),
        differentiator: "savitzky-golay",
        window_samples: stroke.filter.window_len(),
        window_s: stroke.filter.window_len() as f64 * stroke.period_s(),
        polynomial_order: stroke.filter.order(),
        cutoff_hz: stroke.cutoff_hz,
        peak_accel_m_s2: stroke.peak_accel_m_s2(),
        push_off_start_s: stroke.push_off_start_s(),
    };
    let has_rod_heights = log.rows.iter().any(|r| r.rod_height_m.is_some());
    let mut opts = opts.clone();
    if has_rod_heights && !opts.record_series {
        opts.record_series = true;
        opts.series_interval_s = opts.series_interval_s.min(stroke.period_s().max(1e-4));
    }
    let mut sim = kinematic_at_rest(params, model, stroke, &opts)
        .map_err(|e| format!("replay simulation could not start: {e}"))?;
    run_kinematic(&mut sim).map_err(|e| format!("replay simulation failed: {e}"))?;
    let summary = sim.summary();
    let mut warnings = Vec::new();
    if summary.peak_motor_force_n > params.drive.peak_force_n {
        warnings.push(format!(
            "the replayed p(t) needs a motor force of {:.0} N, above F_peak = {:.0} N",
            summary.peak_motor_force_n, params.drive.peak_force_n
        ));
    }
    if !log.gaps.is_empty() {
        warnings.push(format!(
            "{} sample(s) in {} gap(s) of the log were interpolated linearly (--allow-gaps)",
            log.interpolated_samples(),
            log.gaps.len()
        ));
    }
    if log.meta.dropped_samples > 0 {
        warnings.push(format!(
            "the log's metadata reports {} dropped sample(s)",
            log.meta.dropped_samples
        ));
    }
    let series = sim.take_series();
    let measured = compare_with_measurements(log, info.log_start_s, summary.jump_height_m, &series);
    let series = if opts.record_series {
        series
    } else {
        Vec::new()
    };
    Ok(Replayed {
        outcome: JumpOutcome {
            summary,
            series,
            warnings,
        },
        info,
        measured,
    })
}

/// Predicted vs measured jump height and rod heights (rod height above its rest height,
/// `x_r(t) - x_r(0)`, interpolated linearly in the recorded series).
fn compare_with_measurements(
    log: &AcqLog,
    log_start_s: f64,
    predicted_jump_height_m: f64,
    series: &[SeriesRow],
) -> Option<MeasuredComparison> {
    let measured_jump = log.meta.measured_jump_height_m;
    let rods: Vec<(f64, f64)> = log
        .rows
        .iter()
        .filter_map(|r| r.rod_height_m.map(|h| (r.t_s - log_start_s, h)))
        .collect();
    if measured_jump.is_none() && rods.is_empty() {
        return None;
    }
    let rest = series.first().map(|s| s.x_r);
    let mut sq = 0.0;
    let mut n = 0;
    if let Some(rest) = rest {
        for &(t, h) in &rods {
            let k = series.partition_point(|s| s.t_s <= t);
            if k == 0 || k >= series.len() {
                continue;
            }
            let (a, b) = (&series[k - 1], &series[k]);
            let frac = if b.t_s > a.t_s {
                (t - a.t_s) / (b.t_s - a.t_s)
            } else {
                0.0
            };
            let predicted = a.x_r + (b.x_r - a.x_r) * frac - rest;
            sq += (predicted - h).powi(2);
            n += 1;
        }
    }
    Some(MeasuredComparison {
        measured_jump_height_m: measured_jump,
        predicted_jump_height_m,
        jump_height_relative_error: measured_jump
            .filter(|m| *m > 0.0)
            .map(|m| (predicted_jump_height_m - m) / m),
        rod_height_samples: n,
        rod_height_rms_error_m: (n > 0).then(|| (sq / n as f64).sqrt()),
        max_measured_rod_height_m: rods.iter().map(|r| r.1).reduce(f64::max),
    })
}
