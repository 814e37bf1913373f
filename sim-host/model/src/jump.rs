//! One kinematic jump (the paper's simulation): the prescribed `p(t)` drives motor + rod as
//! one body; the run ends by docs/model.md's run-length rules; jump heights are located exactly
//! by apex events.

use crate::error::SimError;
use crate::fastmath::{SINCOS_SMALL_MAX_RAD, sincos_small, sincos_small_lanes};
use crate::ground::{GroundLaw, Sand};
use crate::hybrid::{Contact, GroundMode};
use crate::integrate::{END_STAGE, STAGE_TIMES};
use crate::options::{SimOptions, check_options};
use crate::params::{ModelName, Params};
use crate::record::{JumpSummary, SeriesRow};
use crate::robot::Robot;
use crate::simulation::{Actuation, Simulation};
use crate::trajectory::{CosinePiece, Stroke};
use core::cell::Cell;
use nalgebra::Vector4;
use sandjumper_core::trajectory::{JumpKind, Kinematics, SineJump};

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

/// Kinematic drive: motor and rod move as one body, `p(t)` prescribed.
///
/// The integrator steps onto every breakpoint of the stroke, where `p''` jumps. A step that
/// ends on a breakpoint must see the segment it integrates, not the next one (the stroke
/// itself is right-continuous): [`begin_segment`](Self::begin_segment) names the end of the
/// current segment, and an evaluation at that end returns the left limit.
///
/// Strokes made of cosines ([`Stroke::cosine_piece`]) are evaluated by angle addition from
/// an anchor: one `sin_cos` per anchor, then [`sincos_small`] of the angle since the anchor
/// for each stage, re-anchoring once that angle exceeds [`SINCOS_SMALL_MAX_RAD`] (every few
/// steps; the anchor is placed ahead of the time that needs it, since time runs forward).
/// Within a few ulps of a `sin_cos` per evaluation, at a fraction of its cost. When
/// the integrator announces a step's stage times ([`Actuation::stage_times`]), `p''` for all
/// of them is computed at once ([`sincos_small_lanes`]); evaluations at other times, or of a
/// step that is not inside one piece, go through [`eval`](Self::eval).
#[derive(Clone, Debug)]
pub struct Kinematic<S> {
    /// The prescribed stroke.
    pub stroke: S,
    /// End of the segment being integrated, s (`+inf` after the last breakpoint).
    segment_end_s: f64,
    /// The cosine piece in use and its anchor (an empty piece until the first evaluation).
    piece: Cell<AnchoredPiece>,
    /// `p''` at the stage times of the step being attempted (see [`Actuation::stage_times`]).
    stages: StageAccel,
}

/// `p''` at each stage time of one attempted step.
#[derive(Clone, Copy, Debug)]
struct StageAccel {
    /// Stage times, s (NaN: none).
    times_s: [f64; STAGE_TIMES],
    /// `p''(t)` at each (the left limit at the segment's end), m/s^2.
    accel_m_s2: [f64; STAGE_TIMES],
}

impl StageAccel {
    const NONE: Self = Self {
        times_s: [f64::NAN; STAGE_TIMES],
        accel_m_s2: [0.0; STAGE_TIMES],
    };

    /// `p''` at `t` if `t` is the time of stage `stage`.
    #[inline]
    fn get(&self, stage: usize, t: f64) -> Option<f64> {
        (stage < STAGE_TIMES && self.times_s[stage] == t).then(|| self.accel_m_s2[stage])
    }
}

/// A cosine piece with the sine and cosine of its phase at an anchor time.
#[derive(Clone, Copy, Debug)]
struct AnchoredPiece {
    piece: CosinePiece,
    /// Anchor time, s (NaN: none yet).
    anchor_s: f64,
    /// `sin` and `cos` of the phase at the anchor.
    sin_cos: (f64, f64),
}

impl AnchoredPiece {
    /// The phase advanced since the anchor at `t`, rad.
    #[inline]
    fn angle_since_anchor(&self, t: f64) -> f64 {
        self.piece.angular_freq_rad_s * (t - self.anchor_s)
    }

    /// The piece's kinematics at the phase `anchor + d`, given `(sin d, cos d)`: angle
    /// addition from the anchor's sine and cosine.
    #[inline]
    fn kinematics_after(&self, sin_d: f64, cos_d: f64) -> Kinematics {
        let (s0, c0) = self.sin_cos;
        self.piece
            .kinematics(s0 * cos_d + c0 * sin_d, c0 * cos_d - s0 * sin_d)
    }
}

impl<S: Stroke> Kinematic<S> {
    /// Drive by `stroke`.
    pub fn new(stroke: S) -> Self {
        Self {
            stroke,
            segment_end_s: f64::INFINITY,
            piece: Cell::new(AnchoredPiece {
                piece: CosinePiece::hold(f64::NAN, f64::NAN, 0.0),
                anchor_s: f64::NAN,
                sin_cos: (0.0, 1.0),
            }),
            stages: StageAccel::NONE,
        }
    }

    /// The next steps integrate the segment of `p(t)` that ends at `end_s` (a breakpoint, or
    /// `+inf`): at `t >= end_s` the left limit of `p` and its derivatives is used.
    pub fn begin_segment(&mut self, end_s: f64) {
        self.segment_end_s = end_s;
        self.stages = StageAccel::NONE;
    }

    /// `t`, or one ulp before the current segment's end when `t` is at or past it.
    #[inline]
    fn left_limited(&self, t: f64) -> f64 {
        if t >= self.segment_end_s {
            self.segment_end_s.next_down()
        } else {
            t
        }
    }

    /// `p''` at all stage times of a step: one batch of [`sincos_small_lanes`] from the
    /// anchor (re-anchored at the step's start when the step leaves its range), or the plain
    /// [`eval`](Self::eval) per stage when the step is not inside one cosine piece.
    fn eval_stages(&self, times: &[f64; STAGE_TIMES]) -> [f64; STAGE_TIMES] {
        self.eval_stages_in_piece(times)
            .unwrap_or_else(|| times.map(|t| self.eval(t).accel_m_s2))
    }

    /// [`eval_stages`](Self::eval_stages) when the whole step lies in one cosine piece within
    /// [`SINCOS_SMALL_MAX_RAD`] of an anchor (re-anchoring at the step's start if needed).
    #[inline]
    fn eval_stages_in_piece(&self, times: &[f64; STAGE_TIMES]) -> Option<[f64; STAGE_TIMES]> {
        // Only the step's end may reach the segment's end (the integrator steps onto it), so
        // the other stage times need no left limit.
        if times[END_STAGE - 1] >= self.segment_end_s {
            return None;
        }
        let mut stage_times = *times;
        stage_times[END_STAGE] = self.left_limited(times[END_STAGE]);
        let (first, last) = (stage_times[0], stage_times[END_STAGE]);
        let inside = |a: &AnchoredPiece| {
            a.piece.contains(first)
                && a.piece.contains(last)
                && a.angle_since_anchor(first).abs() <= SINCOS_SMALL_MAX_RAD
                && a.angle_since_anchor(last).abs() <= SINCOS_SMALL_MAX_RAD
        };
        let mut anchored = self.piece.get();
        if !inside(&anchored) {
            self.eval_anchoring(first);
            anchored = self.piece.get();
            if !inside(&anchored) {
                return None;
            }
        }
        if anchored.piece.angular_freq_rad_s == 0.0 {
            return Some([anchored.piece.kinematics(0.0, 1.0).accel_m_s2; STAGE_TIMES]);
        }
        let (ds, dc) = sincos_small_lanes(stage_times.map(|t| anchored.angle_since_anchor(t)));
        Some(core::array::from_fn(|i| {
            anchored.kinematics_after(ds[i], dc[i]).accel_m_s2
        }))
    }

    /// `p''(t)` at stage `stage`: from the step's batch when `t` is that stage's time.
    #[inline]
    fn accel_at(&self, stage: usize, t: f64) -> f64 {
        match self.stages.get(stage, t) {
            Some(a) => a,
            None => self.eval(t).accel_m_s2,
        }
    }

    /// `p(t)` with its derivatives. At the end of the current segment it is the left limit:
    /// the stroke one ulp earlier, an error of order `ulp(t) |p'''|`, below 1e-12 of `p''`
    /// for the paper's strokes.
    #[inline]
    pub fn eval(&self, t: f64) -> Kinematics {
        let t = self.left_limited(t);
        let anchored = self.piece.get();
        if anchored.piece.contains(t) {
            let piece = anchored.piece;
            if piece.angular_freq_rad_s == 0.0 {
                return piece.kinematics(0.0, 1.0);
            }
            let step = anchored.angle_since_anchor(t);
            if step.abs() <= SINCOS_SMALL_MAX_RAD {
                let (ds, dc) = sincos_small(step);
                return anchored.kinematics_after(ds, dc);
            }
        }
        self.eval_anchoring(t)
    }

    /// [`eval`](Self::eval) outside the current piece or too far from its anchor: find the
    /// piece and anchor it ahead of `t` (one `sin_cos`), or evaluate the stroke itself when it
    /// has no cosine pieces.
    #[cold]
    #[inline(never)]
    fn eval_anchoring(&self, t: f64) -> Kinematics {
        let mut anchored = self.piece.get();
        if !anchored.piece.contains(t) {
            match self.stroke.cosine_piece(t) {
                Some(piece) if piece.contains(t) => anchored.piece = piece,
                _ => return self.stroke.eval(t),
            }
        }
        let piece = anchored.piece;
        let w = piece.angular_freq_rad_s;
        if w == 0.0 {
            anchored.anchor_s = t;
            anchored.sin_cos = (0.0, 1.0);
            self.piece.set(anchored);
            return piece.kinematics(0.0, 1.0);
        }
        // Time runs forward: an anchor ahead of `t` serves the steps after it for about twice
        // as long as one at `t` (the window reaches from `t` to the anchor's far side).
        anchored.anchor_s = t + ANCHOR_LEAD_RAD / w.abs();
        anchored.sin_cos = piece.phase_rad(anchored.anchor_s).sin_cos();
        self.piece.set(anchored);
        let (ds, dc) = sincos_small(anchored.angle_since_anchor(t));
        anchored.kinematics_after(ds, dc)
    }
}

/// How far ahead of the time that needs it a cosine piece is anchored, rad of phase: most of
/// [`SINCOS_SMALL_MAX_RAD`], with a margin so that the time itself stays within range of the
/// anchor after rounding.
const ANCHOR_LEAD_RAD: f64 = 0.9 * SINCOS_SMALL_MAX_RAD;

impl<S: Stroke> Actuation<4> for Kinematic<S> {
    #[inline]
    fn stage_times(&mut self, times: &[f64; STAGE_TIMES]) {
        self.stages = StageAccel {
            times_s: *times,
            accel_m_s2: self.eval_stages(times),
        };
    }
    #[inline]
    fn rod_accel(
        &self,
        robot: &Robot,
        stage: usize,
        t: f64,
        _y: &Vector4<f64>,
        f_s: f64,
        _dy: &mut Vector4<f64>,
    ) -> f64 {
        robot.rod_accel_kinematic(f_s, self.accel_at(stage, t))
    }
    fn motor_position(&self, t: f64, _y: &Vector4<f64>) -> f64 {
        self.eval(t).position_m
    }
    fn motor_velocity(&self, t: f64, _y: &Vector4<f64>) -> f64 {
        self.eval(t).velocity_m_s
    }
    fn motor_force(&self, robot: &Robot, t: f64, _y: &Vector4<f64>, f_s: f64) -> f64 {
        // F_m = m_m (x_r'' + p'' + g), the motor's own acceleration being x_r'' + p''. At a
        // step's end, p'' is the last stage's.
        let p_accel = self.accel_at(END_STAGE, t);
        robot.motor_force_for(robot.rod_accel_kinematic(f_s, p_accel) + p_accel)
    }
}

/// A kinematic simulation at rest in static equilibrium at t = 0 (docs/model.md "Initial state"):
/// `F_s = M g`; on sand the foot has sunk to `z0` with `F_p(z0) = (M + m_f) g`.
pub fn kinematic_at_rest<S: Stroke>(
    params: &Params,
    model: ModelName,
    stroke: S,
    opts: &SimOptions,
) -> Result<Simulation<Kinematic<S>, 4>, SimError> {
    params.validate()?;
    check_options(opts)?;
    let robot = Robot::new(params);
    let sand = Sand::new(params, GroundLaw::resolve(model, &params.model));
    let (x_r, x_f) = rest_heights(&robot, &sand);
    let push_off = stroke.push_off_start_s();
    let contact = Contact::at_rest(&sand, x_f);
    Ok(Simulation::new(
        robot,
        sand,
        contact,
        Kinematic::new(stroke),
        Vector4::new(x_r, 0.0, x_f, 0.0),
        push_off,
        opts,
    ))
}

/// Rod and foot heights `(x_r, x_f)` of the initial static equilibrium, m: `F_s = M g`, the
/// foot sunk to `z0` with `F_p(z0) = (M + m_f) g`, nudged down by a few ulps if rounding
/// left the load above the sand's capacity (so the rest is exactly consistent).
pub fn rest_heights(robot: &Robot, sand: &Sand) -> (f64, f64) {
    let load = (robot.motor_rod_mass_kg() + robot.foot_mass_kg()) * robot.gravity_m_s2();
    let mut z0 = sand.initial_sink(load);
    let rest = robot.rest_rod_above_foot_m();
    for _ in 0..64 {
        let (x_f, x_r) = (-z0, -z0 + rest);
        let actual_load = robot.foot_load(robot.spring_force(x_r, 0.0, x_f, 0.0));
        if sand.law.is_rigid() || actual_load <= sand.penetration_force(z0) {
            break;
        }
        z0 = z0 + z0 * f64::EPSILON * 4.0;
    }
    (-z0 + rest, -z0)
}

/// Run-length rule: after the trajectory ends, keep going this long if the robot never lands, s.
pub const GROUNDED_TAIL_S: f64 = 0.5;
/// Run-length rule: while airborne, extend the run up to this long after the trajectory's end, s.
pub const AIRBORNE_TAIL_S: f64 = 3.0;

/// Run a kinematic simulation by docs/model.md's run-length rules: step onto every breakpoint
/// up to the stroke's end; then end at the first touchdown; if none comes, at end + 0.5 s,
/// extended while airborne up to end + 3 s.
pub fn run_kinematic<S: Stroke>(sim: &mut Simulation<Kinematic<S>, 4>) -> Result<(), SimError> {
    let end = sim.actuation.stroke.end_s();
    sim.settle()?;
    for bp in sim.actuation.stroke.breakpoints_s() {
        if bp > sim.time_s() {
            sim.actuation.begin_segment(bp);
            sim.advance_to(bp, false)?;
            sim.discontinuity();
        }
    }
    if sim.time_s() < end {
        sim.actuation.begin_segment(end);
        sim.advance_to(end, false)?;
        sim.discontinuity();
    }
    sim.actuation.begin_segment(f64::INFINITY);
    if sim.advance_to(end + GROUNDED_TAIL_S, true)? {
        return Ok(());
    }
    if sim.contact.mode == GroundMode::Aerial {
        sim.advance_to(end + AIRBORNE_TAIL_S, true)?;
    }
    Ok(())
}

/// The core's one-cycle sine of `kind` at `freq_hz` (delay `tau_s`) with the robot's stroke
/// amplitude; a request the trajectory refuses is an `InvalidInput` naming it.
pub fn sine_stroke(
    params: &Params,
    kind: JumpKind,
    freq_hz: f64,
    tau_s: f64,
) -> Result<SineJump, SimError> {
    SineJump::new(kind, params.robot.stroke_amplitude_m, freq_hz, tau_s).map_err(|e| {
        SimError::InvalidInput {
            field: "trajectory",
            value: format!("{kind:?} at {freq_hz} Hz, tau {tau_s} s"),
            allowed: e.to_string(),
        }
    })
}

/// Simulate one kinematic jump (docs/model.md, the paper's method).
pub fn simulate_jump(
    params: &Params,
    spec: &JumpSpec,
    opts: &SimOptions,
) -> Result<JumpOutcome, SimError> {
    if !(spec.freq_hz.is_finite() && spec.freq_hz > 0.0) {
        return Err(SimError::InvalidInput {
            field: "freq_hz",
            value: spec.freq_hz.to_string(),
            allowed: "a frequency > 0 Hz".into(),
        });
    }
    if !(spec.tau_s.is_finite() && spec.tau_s >= 0.0) {
        return Err(SimError::InvalidInput {
            field: "tau_s",
            value: spec.tau_s.to_string(),
            allowed: "a delay >= 0 s".into(),
        });
    }
    let stroke = sine_stroke(params, spec.kind, spec.freq_hz, spec.tau_s)?;
    simulate_stroke(params, spec.model, stroke, opts)
}

/// Simulate one kinematic jump driven by any prescribed `stroke` (a sampled table, an
/// optimiser's candidate), from rest at the stroke's start, by the same run-length rules.
pub fn simulate_stroke<S: Stroke>(
    params: &Params,
    model: ModelName,
    stroke: S,
    opts: &SimOptions,
) -> Result<JumpOutcome, SimError> {
    let mut sim = kinematic_at_rest(params, model, stroke, opts)?;
    run_kinematic(&mut sim)?;
    let summary = sim.summary();
    let mut warnings = Vec::new();
    if summary.peak_motor_force_n > params.drive.peak_force_n {
        warnings.push(format!(
            "the prescribed p(t) needs a motor force of {:.0} N, above F_peak = {:.0} N: the real motor cannot follow it",
            summary.peak_motor_force_n, params.drive.peak_force_n
        ));
    }
    Ok(JumpOutcome {
        summary,
        series: sim.take_series(),
        warnings,
    })
}

/// Simulate many jumps in parallel on the current rayon pool; results in the order of `specs`.
pub fn simulate_many(
    params: &Params,
    specs: &[JumpSpec],
    opts: &SimOptions,
) -> Vec<Result<JumpOutcome, SimError>> {
    use rayon::prelude::*;
    specs
        .par_iter()
        .map(|s| simulate_jump(params, s, opts))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_end_of_a_segment_sees_the_left_limit_of_the_stroke() {
        let stroke = SineJump::new(JumpKind::DelayedStutter, 0.01875, 10.0, 0.2).unwrap();
        let mut k = Kinematic::new(stroke);
        let half = 0.05;
        // Right-continuous: at T/2 the hold (p'' = 0) has begun.
        assert_eq!(k.eval(half).accel_m_s2, 0.0);
        // Integrating the first half, its end is the bottom of the cosine: p'' = A w^2.
        k.begin_segment(half);
        let w = core::f64::consts::TAU * 10.0;
        let left = k.eval(half).accel_m_s2;
        assert!((left - 0.01875 * w * w).abs() < 1e-9, "left limit {left}");
        // Inside the segment nothing changes (within the few ulps of the anchored
        // evaluation, whose anchor lies ahead of the time evaluated).
        let (inside, exact) = (k.eval(0.02), stroke.eval(0.02));
        let full = [0.01875, 0.01875 * w, 0.01875 * w * w];
        let got = [inside.position_m, inside.velocity_m_s, inside.accel_m_s2];
        let want = [exact.position_m, exact.velocity_m_s, exact.accel_m_s2];
        for i in 0..3 {
            assert!(
                (got[i] - want[i]).abs() < 8.0 * f64::EPSILON * full[i],
                "{inside:?} vs {exact:?}"
            );
        }
        // The next segment starts with the hold again.
        k.begin_segment(half + 0.2);
        assert_eq!(k.eval(half).accel_m_s2, 0.0);
    }
    #[test]
    fn stage_batches_match_the_stroke_and_fall_back_off_their_step() {
        // Steps as the integrator takes them: stage times announced, then evaluated by
        // stage; some steps end on a breakpoint (left limit), some are retried shorter
        // (rejected), one straddles a breakpoint (no single piece: per-stage evaluation).
        let c = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0];
        let robot = Robot::new(&Params::preset(0.57).unwrap());
        let y = Vector4::zeros();
        let mut dy = Vector4::zeros();
        for (kind, tau) in [(JumpKind::Single, 0.0), (JumpKind::DelayedStutter, 0.2)] {
            let stroke = SineJump::new(kind, 0.01875, 17.0, tau).unwrap();
            let mut k = Kinematic::new(stroke);
            let w = core::f64::consts::TAU * 17.0;
            let scale = 0.01875 * w * w;
            let mut worst = 0.0_f64;
            let mut check = |k: &mut Kinematic<SineJump>, t0: f64, h: f64, end: f64| {
                let times = c.map(|c| if c == 1.0 { t0 + h } else { t0 + c * h });
                k.stage_times(&times);
                for (stage, &t) in times.iter().enumerate() {
                    // rod_accel = f_s / (m_m + m_r) - g - share p'': with f_s = 0 it gives p''.
                    let got = k.rod_accel(&robot, stage, t, &y, 0.0, &mut dy);
                    let want = robot.rod_accel_kinematic(0.0, {
                        let t = if t >= end { end.next_down() } else { t };
                        stroke.eval(t).accel_m_s2
                    });
                    worst = worst.max((got - want).abs() / scale);
                }
            };
            let bps = stroke.breakpoints_s();
            let mut t = 0.0;
            for &bp in bps.iter().chain([f64::INFINITY].iter()) {
                k.begin_segment(bp);
                let limit = bp.min(stroke.end_s() + 0.05);
                while t < limit {
                    let h = (limit - t).min(7e-4);
                    check(&mut k, t, 2.0 * h, bp); // rejected, or past the breakpoint
                    check(&mut k, t, h, bp);
                    t += h;
                }
                t = limit;
            }
            assert!(
                worst < 8.0 * f64::EPSILON,
                "{kind:?}: {worst:e} of full scale"
            );
            // A time that is not the named stage's is evaluated on its own.
            k.begin_segment(f64::INFINITY);
            k.stage_times(&c.map(|c| 0.01 + c * 1e-4));
            let got = k.rod_accel(&robot, 2, 0.02, &y, 0.0, &mut dy);
            let want = robot.rod_accel_kinematic(0.0, stroke.eval(0.02).accel_m_s2);
            assert!((got - want).abs() < 8.0 * f64::EPSILON * scale);
        }
    }

    #[test]
    fn anchored_evaluation_matches_the_stroke_within_a_few_ulps() {
        // Times as an integrator visits them: forward in small steps with stage times in
        // between, a jump back (a rejected step), and every breakpoint's left limit.
        for (kind, tau) in [(JumpKind::Single, 0.0), (JumpKind::DelayedStutter, 0.2)] {
            let stroke = SineJump::new(kind, 0.01875, 17.0, tau).unwrap();
            let mut k = Kinematic::new(stroke);
            let w = core::f64::consts::TAU * 17.0;
            let (mut worst, mut steps) = (0.0_f64, 0);
            let mut t = 0.0;
            while t < stroke.end_s() + 0.05 {
                for c in [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 0.5] {
                    let ts = t + c * 3e-4;
                    let (a, b) = (k.eval(ts), stroke.eval(ts));
                    worst = worst
                        .max((a.position_m - b.position_m).abs() / 0.01875)
                        .max((a.velocity_m_s - b.velocity_m_s).abs() / (0.01875 * w))
                        .max((a.accel_m_s2 - b.accel_m_s2).abs() / (0.01875 * w * w));
                }
                steps += 1;
                t += 3e-4;
            }
            assert!(
                worst < 8.0 * f64::EPSILON,
                "{kind:?}: {worst:e} of full scale"
            );
            assert!(steps > 100, "visited the stroke");
            for bp in stroke.breakpoints_s() {
                k.begin_segment(bp);
                let left = k.eval(bp);
                let exact = stroke.eval(bp.next_down());
                assert!(
                    (left.accel_m_s2 - exact.accel_m_s2).abs() < 1e-12 * w * w,
                    "{bp}"
                );
            }
        }
    }
}
