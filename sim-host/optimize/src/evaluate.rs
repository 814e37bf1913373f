//! One candidate stroke evaluated: the rig's feasibility check on its table, the kinematic
//! jump (docs/model.md, the paper's method) and the objective.

use serde::Serialize;

use sandjumper_model::SimOptions;
use sandjumper_model::jump::simulate_stroke;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable, TableRefusal};

use crate::family::MoveChain;

/// What the search maximises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// The highest rod apex of the run, m.
    Height,
    /// The highest apex after the push-off begins (the final hop), m.
    FinalHeight,
    /// The highest rise of the robot's centre of mass (motor, rod and foot), m: the jump as a
    /// jump, where the rod's apex also rewards a motor lowered in flight.
    ComRise,
    /// Jump height over the motor's peak mechanical power, m/W.
    HeightPerPeakPower,
    /// Jump height over the motor's positive mechanical work, m/J.
    HeightPerEnergy,
}

impl Objective {
    /// The name on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Height => "height",
            Self::FinalHeight => "final-height",
            Self::ComRise => "com-rise",
            Self::HeightPerPeakPower => "height-per-peak-power",
            Self::HeightPerEnergy => "height-per-energy",
        }
    }

    /// Unit of the objective's value.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Height | Self::FinalHeight | Self::ComRise => "m",
            Self::HeightPerPeakPower => "m/W",
            Self::HeightPerEnergy => "m/J",
        }
    }

    /// Whether the objective is a ratio (these need a least height: a stroke that barely
    /// moves spends nearly nothing).
    pub fn is_ratio(self) -> bool {
        matches!(self, Self::HeightPerPeakPower | Self::HeightPerEnergy)
    }
}

/// The limits a candidate must keep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SearchLimits {
    /// The rig's feasibility check: stroke, peak force `m_m (p'' + g)`, table capacity.
    #[serde(skip)]
    pub rig: RigLimits,
    /// Table rate the stroke is checked (and written) at, Hz.
    pub table_rate_hz: u32,
    /// Longest stroke (start to the end of the last move), s.
    pub max_duration_s: f64,
    /// Least jump height for the ratio objectives, m (they also need the foot to leave the
    /// ground).
    pub min_height_m: f64,
    /// Most the spring may be compressed below its free length, m.
    pub max_spring_compression_m: f64,
    /// Highest the rod may rise above its rest (the rig's frame), m.
    pub max_rise_m: f64,
}

/// A search problem: robot, ground, limits and objective.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The robot and sand (with `beds`, the nominal bed: the figure's jump is on it).
    pub params: Params,
    /// Other beds a stroke must jump on (a packing fraction known only to a range): with any,
    /// a candidate is scored on `params` and on each of them, its value is the worst of those
    /// and it is feasible only when it keeps every limit on each. Empty: `params` alone.
    pub beds: Vec<Params>,
    /// Ground model.
    pub model: ModelName,
    /// Limits.
    pub limits: SearchLimits,
    /// What is maximised.
    pub objective: Objective,
    /// Integration options of the kinematic runs.
    pub opts: SimOptions,
}

/// The figures of one evaluated candidate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// Highest rod apex, m.
    pub jump_height_m: f64,
    /// Highest apex after the push-off begins, m.
    pub final_jump_height_m: f64,
    /// Highest rise of the robot's centre of mass, m.
    pub com_rise_m: f64,
    /// Largest motor force of the kinematic run, `m_m (x_r'' + p'' + g)`, N.
    pub model_peak_force_n: f64,
    /// The rig check's force estimate `m_m (p'' + g)` on the table, N.
    pub table_peak_force_n: f64,
    /// Largest |F_m p'|, W.
    pub peak_power_w: f64,
    /// Positive work of the motor, J (the energy objective adds the potential energy a stroke
    /// releases by ending lower than it starts).
    pub work_j: f64,
    /// Duration of the stroke, s.
    pub duration_s: f64,
    /// The fastest landing (the centre of mass's downward speed at a touchdown) of the
    /// kinematic jump while the stroke still runs, m/s (0 when the foot does not land again
    /// before it ends); with several beds, on the nominal one.
    pub max_touchdown_speed_m_s: f64,
    /// The shortest delay from a landing to the next push of the kinematic jump, s (None: no
    /// push follows a landing); with several beds, on the nominal one.
    pub earliest_push_after_landing_s: Option<f64>,
    /// The objective's value (NaN when infeasible): with several beds, the worst of them.
    pub value: f64,
    /// The mean of the objective's values over the beds (`value` with one bed).
    pub mean_value: f64,
    /// The packing fraction of the bed whose value is `value` (the worst bed).
    pub worst_phi: f64,
    /// The limit the candidate breaks, in words (None: feasible).
    pub violation: Option<String>,
    /// How far past that limit, relative (0 when feasible).
    #[serde(skip)]
    pub excess: f64,
}

/// Fitness of an infeasible candidate: above every feasible one (whose fitness is minus a
/// value of order 0.01-1), growing with how far past its limit it is.
pub const INFEASIBLE_FITNESS: f64 = 1e3;

impl Evaluation {
    /// Feasible: every limit kept.
    pub fn feasible(&self) -> bool {
        self.violation.is_none()
    }

    /// What the optimiser minimises: minus the objective, or [`INFEASIBLE_FITNESS`] plus the
    /// relative excess.
    pub fn fitness(&self) -> f64 {
        if self.feasible() {
            -self.value
        } else {
            INFEASIBLE_FITNESS + self.excess.min(1e6)
        }
    }

    fn infeasible(duration_s: f64, why: String, excess: f64) -> Self {
        Self {
            jump_height_m: f64::NAN,
            final_jump_height_m: f64::NAN,
            com_rise_m: f64::NAN,
            model_peak_force_n: f64::NAN,
            table_peak_force_n: f64::NAN,
            peak_power_w: f64::NAN,
            work_j: f64::NAN,
            duration_s,
            max_touchdown_speed_m_s: f64::NAN,
            earliest_push_after_landing_s: None,
            value: f64::NAN,
            mean_value: f64::NAN,
            worst_phi: f64::NAN,
            violation: Some(why),
            excess: excess.max(0.0),
        }
    }
}

impl Problem {
    /// The potential energy `m_m g (p_start - p_end)` a stroke releases by ending lower than
    /// it starts (0 otherwise), J: a motor sliding down does no positive work, so the energy
    /// objective charges this too.
    pub fn released_energy_j(&self, chain: &MoveChain) -> f64 {
        let end = chain.moves.last().map_or(chain.start_m, |m| m.to_m);
        let r = &self.params.robot;
        (r.motor_mass_kg * r.gravity_m_s2 * (chain.start_m - end)).max(0.0)
    }

    /// The stroke table of `chain` at the search's table rate (what stroke.csv holds and the
    /// rig replays).
    pub fn table(&self, chain: &MoveChain) -> StrokeTable {
        StrokeTable {
            samples_m: chain.samples(self.limits.table_rate_hz),
            rate_hz: self.limits.table_rate_hz,
        }
    }

    /// Every bed a candidate is scored on: `params`, then `beds`.
    pub fn all_beds(&self) -> impl Iterator<Item = &Params> {
        std::iter::once(&self.params).chain(&self.beds)
    }

    /// Evaluate `chain`: limits first (cheap), then the kinematic jump, on every bed; its
    /// value is the worst bed's, and it is infeasible when it breaks a limit on any (the
    /// first bed it breaks one on is reported).
    pub fn evaluate(&self, chain: &MoveChain) -> Evaluation {
        let mut worst: Option<Evaluation> = None;
        let (mut sum, mut n) = (0.0, 0usize);
        let (mut nominal_landing, mut nominal_push) = (f64::NAN, None);
        for params in self.all_beds() {
            let e = self.evaluate_on(params, chain);
            if !e.feasible() {
                return e;
            }
            if n == 0 {
                nominal_landing = e.max_touchdown_speed_m_s;
                nominal_push = e.earliest_push_after_landing_s;
            }
            sum += e.value;
            n += 1;
            if worst.as_ref().is_none_or(|w| e.value < w.value) {
                worst = Some(e);
            }
        }
        let mut e = worst.expect("a problem has at least its own bed");
        e.mean_value = sum / n as f64;
        e.max_touchdown_speed_m_s = nominal_landing;
        e.earliest_push_after_landing_s = nominal_push;
        e
    }

    /// Evaluate `chain` on the bed `params` alone.
    pub fn evaluate_on(&self, params: &Params, chain: &MoveChain) -> Evaluation {
        let duration_s = chain.duration_s();
        let l = &self.limits;
        if duration_s > l.max_duration_s {
            return Evaluation::infeasible(
                duration_s,
                format!(
                    "lasts {duration_s:.3} s, longer than the limit {} s",
                    l.max_duration_s
                ),
                duration_s / l.max_duration_s - 1.0,
            );
        }
        let table = self.table(chain);
        let check = match table.check(&l.rig) {
            Ok(c) => c,
            Err(e) => {
                let excess = match e {
                    TableRefusal::Force {
                        force_n, limit_n, ..
                    } => force_n / limit_n - 1.0,
                    TableRefusal::Stroke { p_m, stroke_m, .. } => p_m.abs() / stroke_m - 1.0,
                    TableRefusal::TooLong {
                        samples, capacity, ..
                    } => samples as f64 / capacity as f64 - 1.0,
                    TableRefusal::TooShort { .. } => 1.0,
                };
                return Evaluation::infeasible(
                    duration_s,
                    format!("the rig refuses it: {e}"),
                    excess,
                );
            }
        };
        // The jump of the table the rig replays (and stroke.csv holds), not of the analytic
        // chain it samples: the two differ by a few per cent at 1 kHz.
        let stroke = match table.kinematic_stroke() {
            Ok(s) => s,
            Err(e) => return Evaluation::infeasible(duration_s, e, 1.0),
        };
        let outcome = match simulate_stroke(params, self.model, stroke, &self.opts) {
            Ok(o) => o,
            Err(e) => {
                return Evaluation::infeasible(
                    duration_s,
                    format!("the simulation failed: {e}"),
                    1.0,
                );
            }
        };
        let s = &outcome.summary;
        let peak = params.drive.peak_force_n;
        let mut e = Evaluation {
            jump_height_m: s.jump_height_m,
            final_jump_height_m: s.final_jump_height_m,
            com_rise_m: s.com_rise_m,
            model_peak_force_n: s.peak_motor_force_n,
            table_peak_force_n: check.peak_force_n,
            peak_power_w: s.peak_motor_power_w,
            work_j: s.motor_work_j,
            duration_s,
            max_touchdown_speed_m_s: crate::validity::landings_before(s, duration_s)
                .iter()
                .map(|l| l.1)
                .fold(0.0, f64::max),
            earliest_push_after_landing_s: crate::validity::pushes_after_landings(s, chain).0,
            value: f64::NAN,
            mean_value: f64::NAN,
            worst_phi: params.sand.packing_fraction,
            violation: None,
            excess: 0.0,
        };
        if s.peak_motor_force_n > peak {
            e.violation = Some(format!(
                "the kinematic jump needs {:.0} N of motor force (m_m (x_r'' + p'' + g)), above \
                 the drive's {peak} N",
                s.peak_motor_force_n
            ));
            e.excess = s.peak_motor_force_n / peak - 1.0;
            return e;
        }
        // The robot's physical limits, in millimetres in the words.
        for (value, limit, words) in [
            (
                s.max_spring_compression_m,
                l.max_spring_compression_m,
                "compresses the spring {v} mm, beyond the {l} mm it allows",
            ),
            (
                s.jump_height_m,
                l.max_rise_m,
                "raises the rod {v} mm, above the rig's {l} mm",
            ),
        ] {
            if value > limit {
                e.violation = Some(
                    words
                        .replace("{v}", &format!("{:.1}", 1e3 * value))
                        .replace("{l}", &format!("{:.1}", 1e3 * limit)),
                );
                e.excess = value / limit - 1.0;
                return e;
            }
        }
        if self.objective.is_ratio() && s.liftoff_time_s.is_none() {
            // A rod raised by a retracting motor is not a jump.
            e.violation = Some("the foot never leaves the ground".into());
            e.excess = 1.0;
            return e;
        }
        if self.objective.is_ratio() && s.jump_height_m < l.min_height_m {
            e.violation = Some(format!(
                "jumps {:.2} mm, below the least height {:.2} mm of a ratio objective",
                1e3 * s.jump_height_m,
                1e3 * l.min_height_m
            ));
            e.excess = 1.0 - s.jump_height_m / l.min_height_m;
            return e;
        }
        e.value = match self.objective {
            Objective::Height => s.jump_height_m,
            Objective::FinalHeight => s.final_jump_height_m,
            Objective::ComRise => s.com_rise_m,
            Objective::HeightPerPeakPower => s.jump_height_m / s.peak_motor_power_w,
            Objective::HeightPerEnergy => {
                s.jump_height_m / (s.motor_work_j + self.released_energy_j(chain))
            }
        };
        if !e.value.is_finite() {
            e.violation = Some(format!("objective value {} is not finite", e.value));
            e.excess = 1.0;
        }
        e
    }
}
