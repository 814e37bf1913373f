//! One kinematic jump (the paper's simulation): the prescribed `p(t)` drives motor + rod as
//! one body; the run ends by MODEL.md's run-length rules; jump heights are located exactly
//! by apex events.

use crate::error::SimError;
use crate::hybrid::GroundMode;
use crate::params::{ModelName, Params};
use sandjumper_core::trajectory::JumpKind;
use serde::Serialize;

/// One jump to simulate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JumpSpec {
    /// Single, stutter or delayed stutter.
    pub kind: JumpKind,
    /// Forcing frequency f, Hz (T = 1/f).
    pub freq_hz: f64,
    /// Delay tau of the delayed stutter, s (ignored for the other kinds).
    pub tau_s: f64,
    /// Ground model.
    pub model: ModelName,
}

/// Integration options.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    /// Relative tolerance of the Dormand-Prince 5(4) step control.
    pub rtol: f64,
    /// Absolute tolerance (m, m/s, N), applied to every state component.
    pub atol: f64,
    /// Record a time series in [`JumpOutcome::series`].
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

/// Kinds of located events.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum EventKind {
    /// Foot reaches the stored ground level moving down.
    Touchdown,
    /// Spring pulls the foot off the ground (`-F_s - m_f g > 0`).
    LiftOff,
    /// An intruding foot comes to rest and the sand holds it.
    Static,
    /// A static foot starts moving down again (a new intrusion episode).
    Intrusion,
    /// The rod's apex (`x_r'` crosses zero downward).
    Apex,
}

impl EventKind {
    /// Name as written in outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Touchdown => "Touchdown",
            Self::LiftOff => "LiftOff",
            Self::Static => "Static",
            Self::Intrusion => "Intrusion",
            Self::Apex => "Apex",
        }
    }
}

impl core::fmt::Display for EventKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A located event.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Event {
    /// Time, s.
    pub t_s: f64,
    /// What happened.
    pub kind: EventKind,
}

/// The metrics of a run (MODEL.md section 1).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct JumpSummary {
    /// Max over the run of `x_r(t) - x_r(0)`, m (apex events, exact).
    pub jump_height_m: f64,
    /// The same maximum taken only after the push-off half begins, m.
    pub final_jump_height_m: f64,
    /// Deepest foot depth below the undisturbed surface, m.
    pub max_depth_m: f64,
    /// Largest added mass m_a reached, kg (0 unless the added-mass law is active).
    pub peak_added_mass_kg: f64,
    /// Time of the first lift-off, s, if the foot left the ground.
    pub liftoff_time_s: Option<f64>,
    /// Time of the first lift-off after the push-off half began, s.
    pub final_liftoff_time_s: Option<f64>,
    /// Time at which `jump_height_m` is reached, s.
    pub apex_time_s: f64,
    /// Time at which `final_jump_height_m` is reached, s.
    pub final_apex_time_s: f64,
    /// Largest |F_m| the prescribed p(t) implies (`m_m (x_r'' + p'' + g)`), N, sampled at
    /// every step end and event.
    pub peak_motor_force_n: f64,
    /// Mode switches and apexes, in time order.
    pub events: Vec<Event>,
    /// Number of right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Accepted integration steps.
    pub steps_accepted: u64,
    /// Rejected integration steps.
    pub steps_rejected: u64,
    /// Ground-mode switches.
    pub mode_switches: u64,
    /// Time the run ended, s.
    pub end_time_s: f64,
}

/// One sample of the time series (SI units).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SeriesRow {
    /// Time, s.
    pub t_s: f64,
    /// Motor height x_m, m.
    pub x_m: f64,
    /// Rod height x_r, m.
    pub x_r: f64,
    /// Foot height x_f, m.
    pub x_f: f64,
    /// Motor position relative to the rod, p = x_m - x_r, m.
    pub p: f64,
    /// Spring force F_s, N (> 0 compressed).
    pub f_s: f64,
    /// Ground force on the foot F_GM, N.
    pub f_gm: f64,
    /// Added mass m_a, kg.
    pub m_a: f64,
    /// Ground mode.
    pub mode: GroundMode,
}

/// Result of one jump.
#[derive(Clone, Debug, PartialEq)]
pub struct JumpOutcome {
    /// Metrics.
    pub summary: JumpSummary,
    /// Time series (empty unless [`SimOptions::record_series`]).
    pub series: Vec<SeriesRow>,
    /// Warnings (e.g. the prescribed p(t) asks more than F_peak).
    pub warnings: Vec<String>,
}

/// Simulate one kinematic jump (MODEL.md, the paper's method).
pub fn simulate_jump(
    params: &Params,
    spec: &JumpSpec,
    opts: &SimOptions,
) -> Result<JumpOutcome, SimError> {
    let _ = (params, spec, opts);
    Err(SimError::InvalidInput {
        field: "simulate_jump",
        value: "not yet implemented".into(),
        allowed: "nothing yet".into(),
    })
}

/// Simulate many jumps in parallel on the current rayon pool; results in the order of `specs`.
pub fn simulate_many(
    params: &Params,
    specs: &[JumpSpec],
    opts: &SimOptions,
) -> Vec<Result<JumpOutcome, SimError>> {
    use rayon::prelude::*;
    specs.par_iter().map(|s| simulate_jump(params, s, opts)).collect()
}
