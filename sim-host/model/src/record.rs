//! What a run records: its summary metrics (docs/model.md section 1) and its time series.

use crate::events::Event;
use crate::hybrid::GroundMode;
use serde::Serialize;

/// The metrics of a run (docs/model.md section 1).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct JumpSummary {
    /// Max over the run of `x_r(t) - x_r(0)`, m (apex events, exact).
    pub jump_height_m: f64,
    /// The highest rod apex (`x_r - x_r(0)`) after the push-off half begins, m; negative
    /// when the push-off hop peaks below the rest height (single jump: equals `jump_height_m`).
    pub final_jump_height_m: f64,
    /// Deepest foot depth below the undisturbed surface, m.
    pub max_depth_m: f64,
    /// Largest added mass m_a reached, kg (0 unless the added-mass law is active).
    pub peak_added_mass_kg: f64,
    /// Time of the first lift-off, s, if the foot left the ground.
    pub liftoff_time_s: Option<f64>,
    /// Highest rise of the robot's centre of mass (motor, rod and foot) above where it
    /// started, m: the jump as a jump, where the rod's apex also counts a motor lowered in
    /// flight. Exact in flight (the ballistic apex from each lift-off); elsewhere the highest
    /// at any integration step's end.
    pub com_rise_m: f64,
    /// Most the spring was compressed below its free length (`L0 - (x_r - x_f)`), m, at any
    /// integration step's end or event.
    pub max_spring_compression_m: f64,
    /// The robot's landing speed at each touchdown, in order, m/s: its centre of mass's
    /// downward speed just before the contact (the foot alone rings on the spring in flight,
    /// so its own speed says little about the landing); one per `Touchdown` event.
    pub touchdown_speeds_m_s: Vec<f64>,
    /// Time of the first lift-off after the push-off half began, s.
    pub final_liftoff_time_s: Option<f64>,
    /// Time at which `jump_height_m` is reached, s.
    pub apex_time_s: f64,
    /// Time at which `final_jump_height_m` is reached, s.
    pub final_apex_time_s: f64,
    /// Largest |F_m| the prescribed p(t) implies (`m_m (x_r'' + p'' + g)`), N, sampled at
    /// every step end and event.
    pub peak_motor_force_n: f64,
    /// Largest |F_m p'| (the motor's mechanical power), W, sampled as the force is.
    pub peak_motor_power_w: f64,
    /// The motor's positive mechanical work `integral max(F_m p', 0) dt`, J (trapezoids
    /// between the same samples).
    pub motor_work_j: f64,
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

impl JumpSummary {
    /// What a final jump height that is not positive means, in words: the push-off hop
    /// peaked at or below the rod's rest height (a bare negative height reads as a bug).
    /// `None` when the push-off lifted the rod above rest.
    pub fn final_height_note(&self) -> Option<&'static str> {
        (self.final_jump_height_m <= 0.0)
            .then_some("push-off did not lift the rod above its rest height")
    }
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
