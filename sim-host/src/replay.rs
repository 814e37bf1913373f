//! Replay of an acquisition log in the simulator (the paper's method): the encoder record
//! becomes the prescribed motor stroke `p(t)` of a kinematic run.
//!
//! Method. Positions `p_k = encoder_sign * counts_k / counts_per_m + position_offset_m` are
//! taken on the log's own time grid (the least-squares sampling period of its time column;
//! replay time 0 is the log's first sample). A cubic Savitzky-Golay filter
//! ([`crate::differentiate`]) gives the smoothed `p`, `p'` and `p''` at every sample; between
//! samples each is interpolated linearly, so `p''(t)` is continuous inside the log. Before
//! the first sample the stroke holds the first smoothed position with zero velocity and
//! acceleration, after the last it holds the last one (MODEL.md section 2, "hold last"); those
//! two instants are the stroke's breakpoints, where the integrator stops exactly.
//!
//! Default window: [`DEFAULT_WINDOW_S`] (31 samples at 10 kHz), whose second-derivative
//! cut-off is about 220 Hz at 10 kHz: far above the jumps' forcing band (<= 40 Hz) and the
//! robot's own resonances (~5-8 Hz), and it averages 1 um quantization to a p'' noise of about
//! 0.05 m/s^2 (against ~70 m/s^2 peaks of a 10 Hz, 18.75 mm stroke).

use crate::acqlog::AcqLog;
use crate::differentiate::SavitzkyGolay;
use crate::trajectory::Stroke;
use sandjumper_core::trajectory::Kinematics;

/// Default Savitzky-Golay window, s.
pub const DEFAULT_WINDOW_S: f64 = 3.0e-3;

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

/// Start of the push-off half in log time, from the `jump_*` metadata when it describes a
/// one-cycle sine: 0 for a single jump, `T/2` for a stutter, `T/2 + tau` for a delayed stutter.
fn push_off_start_in_log(log: &AcqLog) -> Option<f64> {
    let jump = log.meta.jump.as_ref()?;
    let half = 0.5 / jump.freq_hz.filter(|f| *f > 0.0)?;
    match jump.kind.as_str() {
        "single" => Some(0.0),
        "stutter" => Some(half),
        "delayed-stutter" | "delayed_stutter" => Some(half + jump.tau_s.unwrap_or(0.0)),
        _ => None,
    }
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
