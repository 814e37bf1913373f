//! The hybrid run loop shared by kinematic jumps and the force-driven plant: Dormand-Prince
//! steps, guards checked on the dense output, events located and applied, metrics kept.
//!
//! State layout (SI): `[x_r, v_r, x_f, v_f, ..]`; the force-driven plant appends `[x_m, v_m]`.

use crate::error::SimError;
use crate::events::{Event, EventKind};
use crate::ground::Sand;
use crate::hybrid::{Contact, GroundMode, Transition};
use crate::integrate::{DenseStep, DormandPrince, Rhs, STAGE_TIMES, StepFailure, locate_crossing};
use crate::options::SimOptions;
use crate::record::{JumpSummary, SeriesRow};
use crate::robot::Robot;
use nalgebra::SVector;

/// Events are located to this precision in time, s.
pub const EVENT_TOLERANCE_S: f64 = 1e-12;
/// Smallest upward rod speed before an apex that counts, m/s (a height error below 1e-19 m).
const APEX_MIN_SPEED_M_S: f64 = 1e-9;
/// Most mode switches allowed at one instant.
const MAX_SWITCHES_PER_INSTANT: u32 = 8;

/// How motor and rod are driven.
pub trait Actuation<const N: usize> {
    /// The integrator's next attempted step has its stages at `times` (see
    /// [`Rhs::stage_times`]): a drive that depends on time alone may evaluate it for all of
    /// them at once.
    #[inline]
    fn stage_times(&mut self, times: &[f64; STAGE_TIMES]) {
        let _ = times;
    }
    /// Rod acceleration for spring force `f_s` at `t`, the time of stage `stage` (an index
    /// into the last [`stage_times`](Self::stage_times), or `>= STAGE_TIMES` for none);
    /// writes the derivatives of any extra states (index 4 on) into `dy`. m/s^2.
    fn rod_accel(
        &self,
        robot: &Robot,
        stage: usize,
        t: f64,
        y: &SVector<f64, N>,
        f_s: f64,
        dy: &mut SVector<f64, N>,
    ) -> f64;
    /// Motor position relative to the rod, `p = x_m - x_r`, m.
    fn motor_position(&self, t: f64, y: &SVector<f64, N>) -> f64;
    /// Motor velocity relative to the rod, `p' = v_m - v_r`, m/s.
    fn motor_velocity(&self, t: f64, y: &SVector<f64, N>) -> f64;
    /// Motor force F_m, N, at spring force `f_s`.
    fn motor_force(&self, robot: &Robot, t: f64, y: &SVector<f64, N>, f_s: f64) -> f64;
}

/// Metrics accumulated while running.
#[derive(Clone, Debug, Default)]
struct Metrics {
    best_height_m: f64,
    best_time_s: f64,
    final_height_m: f64,
    final_time_s: f64,
    first_liftoff_s: Option<f64>,
    final_liftoff_s: Option<f64>,
    /// The robot's centre of mass at the start, m.
    com0_m: f64,
    /// Highest centre of mass above `com0_m` so far, m.
    com_rise_m: f64,
    /// Most the spring was compressed below its free length so far, m.
    max_spring_compression_m: f64,
    /// The centre of mass's downward speed at each touchdown so far, m/s.
    touchdown_speeds_m_s: Vec<f64>,
    peak_added_mass_kg: f64,
    peak_motor_force_n: f64,
    peak_motor_power_w: f64,
    motor_work_j: f64,
    /// Time and motor power at the last observation (the work's trapezoid), s and W.
    last_power: Option<(f64, f64)>,
    mode_switches: u64,
}

/// A running hybrid simulation.
#[derive(Clone, Debug)]
pub struct Simulation<A, const N: usize> {
    /// The robot.
    pub robot: Robot,
    /// The ground.
    pub sand: Sand,
    /// Foot-ground contact (mode and episode).
    pub contact: Contact,
    /// How motor and rod are driven.
    pub actuation: A,
    t: f64,
    y: SVector<f64, N>,
    dp: DormandPrince<N>,
    x_r0: f64,
    push_off_start_s: f64,
    events: Vec<Event>,
    metrics: Metrics,
    series: Option<Vec<SeriesRow>>,
    series_interval_s: f64,
    next_sample_s: f64,
    max_steps: u64,
    /// The current mode's guard values at the current state (see
    /// [`Contact::guard_values_with`]).
    start_guards: [f64; 2],
}

impl<A: Actuation<N>, const N: usize> Simulation<A, N> {
    /// A simulation from state `y0` at time 0 (rod height `y0[0]` is the jump height's zero).
    pub fn new(
        robot: Robot,
        sand: Sand,
        contact: Contact,
        actuation: A,
        y0: SVector<f64, N>,
        push_off_start_s: f64,
        opts: &SimOptions,
    ) -> Self {
        let mut sim = Self {
            robot,
            sand,
            contact,
            actuation,
            t: 0.0,
            y: y0,
            dp: plant_stepper(opts, &y0),
            x_r0: y0[0],
            push_off_start_s,
            events: Vec::new(),
            metrics: Metrics::default(),
            series: opts.record_series.then(Vec::new),
            series_interval_s: opts.series_interval_s,
            next_sample_s: 0.0,
            max_steps: opts.max_steps,
            start_guards: [f64::NEG_INFINITY; 2],
        };
        sim.refresh_guards();
        sim.begin_final_metrics(push_off_start_s);
        sim.metrics.com0_m = sim.centre_of_mass(0.0, &y0).0;
        sim.observe(0.0, &y0);
        sim.sample(0.0, &y0);
        sim
    }

    /// Apply any switch already due at the current instant (a guard positive at the start,
    /// e.g. through rounding of the initial equilibrium). Call before the first step.
    pub fn settle(&mut self) -> Result<(), SimError> {
        let f_s = self.spring_force(&self.y);
        let guards = self
            .contact
            .guards(&self.robot, &self.sand, self.y[2], self.y[3], f_s);
        if let Some(g) = guards.iter().find(|g| g.value > 0.0) {
            self.switch(g.transition)?;
        }
        Ok(())
    }

    /// Current time, s.
    pub fn time_s(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn state(&self) -> &SVector<f64, N> {
        &self.y
    }

    /// Spring force at the current state, N.
    pub fn spring_force(&self, y: &SVector<f64, N>) -> f64 {
        self.robot.spring_force(y[0], y[1], y[2], y[3])
    }

    /// Events so far.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// The right-hand side was changed from outside (a new motor force, a breakpoint).
    pub fn discontinuity(&mut self) {
        self.dp.discontinuity();
    }

    /// Take the recorded series.
    pub fn take_series(&mut self) -> Vec<SeriesRow> {
        self.series.take().unwrap_or_default()
    }

    /// Integrate to `t_end` (reached exactly). With `stop_at_touchdown`, return early right
    /// after a touchdown; returns whether that happened.
    pub fn advance_to(&mut self, t_end: f64, stop_at_touchdown: bool) -> Result<bool, SimError> {
        while self.t < t_end {
            if self.dp.accepted + self.dp.rejected >= self.max_steps {
                return Err(SimError::TooManySteps {
                    t_s: self.t,
                    limit: self.max_steps,
                });
            }
            {
                let mut f = PlantRhs {
                    robot: &self.robot,
                    sand: &self.sand,
                    contact: &self.contact,
                    actuation: &mut self.actuation,
                };
                self.dp
                    .step(&mut f, self.t, &self.y, t_end)
                    .map_err(|e| match e {
                        StepFailure::StepSizeTooSmall { t, h } => {
                            SimError::StepSizeTooSmall { t_s: t, step_s: h }
                        }
                        StepFailure::NonFinite { t } => SimError::NonFinite { t_s: t },
                    })?;
            }
            let step = self.dp.dense();
            let (switch, end_guards) = self.first_switch(step);
            let t_new = switch.map_or(step.t1, |(t, _)| t);
            let mut y_new = step.eval(t_new);
            if !y_new.iter().all(|v| v.is_finite()) {
                return Err(SimError::NonFinite { t_s: t_new });
            }
            let apexes = apexes(step, self.y[1], t_new, y_new[1]);
            for (te, x_r) in apexes.into_iter().flatten() {
                self.events.push(Event {
                    t_s: te,
                    kind: EventKind::Apex,
                });
                self.consider_height(te, x_r - self.x_r0);
            }
            if self.series.is_some() {
                let step = *self.dp.dense();
                self.sample_until(&step, t_new);
            }
            if self.contact.mode == GroundMode::Static {
                // A static foot does not move (its velocity is held at 0).
                y_new[2] = self.y[2];
                y_new[3] = 0.0;
            }
            self.t = t_new;
            self.y = y_new;
            self.contact.track(self.y[2]);
            self.observe_step_end();
            match switch {
                // The end-of-step guards were computed in first_switch (static foot state unchanged).
                None if self.contact.mode != GroundMode::Static => self.start_guards = end_guards,
                _ => self.refresh_guards(),
            }
            if let Some((_, transition)) = switch {
                let touched = self.switch(transition)?;
                if touched && stop_at_touchdown {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// The earliest guard crossing inside the step, located on the dense output.
    fn first_switch(&self, step: &DenseStep<N>) -> (Option<(f64, Transition)>, [f64; 2]) {
        let guards = |t: f64| {
            let y = step.at(t);
            self.contact
                .guard_values_with(&self.robot, &self.sand, y.get(2), y.get(3), || {
                    self.robot
                        .spring_force(y.get(0), y.get(1), y.get(2), y.get(3))
                })
        };
        let start = self.start_guards;
        let t_mid = 0.5 * (step.t0 + step.t1);
        let (mid, end) = (guards(t_mid), guards(step.t1));
        let mut best: Option<(f64, Transition)> = None;
        for i in 0..2 {
            let samples = [(step.t0, start[i]), (t_mid, mid[i]), (step.t1, end[i])];
            for w in samples.windows(2) {
                let ((ta, ga), (tb, gb)) = (w[0], w[1]);
                if ga <= 0.0 && gb > 0.0 {
                    let g = |t: f64| guards(t)[i];
                    let te = locate_crossing(g, ta, ga, tb, gb, EVENT_TOLERANCE_S);
                    if best.is_none_or(|(tb, _)| te < tb) {
                        best = Some((te, self.contact.guard_transitions()[i]));
                    }
                    break;
                }
            }
        }
        (best, end)
    }

    /// Guards at the current state (cached for the next step's start).
    fn refresh_guards(&mut self) {
        let f_s = self.spring_force(&self.y);
        self.start_guards =
            self.contact
                .guard_values_with(&self.robot, &self.sand, self.y[2], self.y[3], || f_s);
    }

    /// Apply a transition and any that are due at the same instant.
    fn switch(&mut self, first: Transition) -> Result<bool, SimError> {
        let mut touched = false;
        let mut next = Some(first);
        let mut count = 0;
        while let Some(transition) = next {
            count += 1;
            if count > MAX_SWITCHES_PER_INSTANT {
                return Err(SimError::ModeSwitchLoop {
                    t_s: self.t,
                    limit: MAX_SWITCHES_PER_INSTANT,
                });
            }
            let f_s = self.spring_force(&self.y);
            let mut v_f = self.y[3];
            // The robot's descent as the foot lands (its centre of mass: the foot alone
            // rings on the spring in flight).
            let landing_speed = -self.centre_of_mass(self.t, &self.y).1;
            let event = self.contact.apply(
                transition,
                &self.robot,
                &self.sand,
                self.y[2],
                &mut v_f,
                f_s,
            );
            self.y[3] = v_f;
            if let Some(kind) = event {
                self.record(kind);
                if kind == EventKind::Touchdown {
                    self.metrics.touchdown_speeds_m_s.push(landing_speed);
                    touched = true;
                }
            }
            let f_s = self.spring_force(&self.y);
            let guards = self
                .contact
                .guards(&self.robot, &self.sand, self.y[2], self.y[3], f_s);
            next = guards.iter().find(|g| g.value > 0.0).map(|g| g.transition);
            if event.is_none() {
                break;
            }
        }
        self.dp.discontinuity();
        self.refresh_guards();
        self.sample(self.t, &self.y.clone());
        Ok(touched)
    }

    /// Set when the push-off half begins, s (the final jump height and final lift-off are
    /// measured from then on). Call before the run reaches that time.
    pub fn set_push_off_start(&mut self, push_off_start_s: f64) {
        self.push_off_start_s = push_off_start_s;
        self.begin_final_metrics(push_off_start_s);
        if push_off_start_s <= self.t {
            let (t, h) = (self.t, self.y[0] - self.x_r0);
            self.consider_height(t, h);
        }
    }

    /// The final jump height is the highest rod apex once the push-off half has begun. The
    /// rest height at t = 0 is a candidate only when the push-off starts at 0 (single jump);
    /// for a stutter the rod is still falling from its preliminary hop at the push-off start,
    /// and that tail is not the push-off's height. A push-off hop that peaks below the rest
    /// height gives a negative final height, reported as is.
    fn begin_final_metrics(&mut self, push_off_start_s: f64) {
        self.metrics.final_time_s = push_off_start_s;
        self.metrics.final_height_m = if push_off_start_s > 0.0 {
            f64::NEG_INFINITY
        } else {
            0.0
        };
        self.metrics.final_liftoff_s = None;
    }

    fn record(&mut self, kind: EventKind) {
        self.events.push(Event { t_s: self.t, kind });
        if kind != EventKind::Apex {
            self.metrics.mode_switches += 1;
        }
        if kind == EventKind::LiftOff {
            // In flight only gravity moves the centre of mass (the motor's force, the spring's
            // and its damper's are internal): its apex is ballistic, exact.
            let (x, v) = self.centre_of_mass(self.t, &self.y);
            let apex = x + v.max(0.0).powi(2) / (2.0 * self.robot.gravity_m_s2());
            let m = &mut self.metrics;
            m.com_rise_m = m.com_rise_m.max(apex - m.com0_m);
            self.metrics.first_liftoff_s.get_or_insert(self.t);
            if self.t >= self.push_off_start_s {
                self.metrics.final_liftoff_s.get_or_insert(self.t);
            }
        }
    }

    fn consider_height(&mut self, t: f64, height: f64) {
        let m = &mut self.metrics;
        if height > m.best_height_m {
            m.best_height_m = height;
            m.best_time_s = t;
        }
        if t >= self.push_off_start_s && height > m.final_height_m {
            m.final_height_m = height;
            m.final_time_s = t;
        }
    }

    /// The robot's centre of mass and its velocity, m and m/s: motor (at `x_r + p`), rod and
    /// foot.
    fn centre_of_mass(&self, t: f64, y: &SVector<f64, N>) -> (f64, f64) {
        let r = &self.robot;
        let (m_m, m_r, m_f) = (r.motor_mass_kg(), r.rod_mass_kg(), r.foot_mass_kg());
        let total = m_m + m_r + m_f;
        let p = self.actuation.motor_position(t, y);
        let dp = self.actuation.motor_velocity(t, y);
        (
            (m_m * (y[0] + p) + m_r * y[0] + m_f * y[2]) / total,
            (m_m * (y[1] + dp) + m_r * y[1] + m_f * y[3]) / total,
        )
    }

    /// Metrics at a step end or event.
    fn observe(&mut self, t: f64, y: &SVector<f64, N>) {
        let com = self.centre_of_mass(t, y).0 - self.metrics.com0_m;
        self.metrics.com_rise_m = self.metrics.com_rise_m.max(com);
        let compression = self.robot.spring_rest_length_m() - (y[0] - y[2]);
        self.metrics.max_spring_compression_m =
            self.metrics.max_spring_compression_m.max(compression);
        let f_s = self.spring_force(y);
        let m_a = self.contact.added_mass(&self.sand, y[2]);
        let f_m = self.actuation.motor_force(&self.robot, t, y, f_s);
        let power = f_m * self.actuation.motor_velocity(t, y);
        let m = &mut self.metrics;
        m.peak_added_mass_kg = m.peak_added_mass_kg.max(m_a);
        m.peak_motor_force_n = m.peak_motor_force_n.max(f_m.abs());
        m.peak_motor_power_w = m.peak_motor_power_w.max(power.abs());
        // Positive work only: the drive spends energy to push and to brake alike, and does
        // not recover it (trapezoids between observations, each side clipped at 0).
        if let Some((t0, p0)) = m.last_power
            && t > t0
        {
            m.motor_work_j += 0.5 * (t - t0) * (p0.max(0.0) + power.max(0.0));
        }
        m.last_power = Some((t, power));
    }

    /// [`observe`](Self::observe) the current state.
    fn observe_step_end(&mut self) {
        let (t, y) = (self.t, self.y);
        self.observe(t, &y);
    }

    fn sample_until(&mut self, step: &DenseStep<N>, t_new: f64) {
        if self.series.is_none() || self.series_interval_s <= 0.0 {
            return;
        }
        while self.next_sample_s <= t_new {
            let t = self.next_sample_s;
            let y = step.eval(t);
            self.sample(t, &y);
        }
    }

    /// Append one series row (and move the grid on when `t` is on it).
    fn sample(&mut self, t: f64, y: &SVector<f64, N>) {
        let Some(series) = self.series.as_mut() else {
            return;
        };
        let f_s = self.robot.spring_force(y[0], y[1], y[2], y[3]);
        let foot = self.contact.foot(&self.robot, &self.sand, y[2], y[3], f_s);
        let p = self.actuation.motor_position(t, y);
        series.push(SeriesRow {
            t_s: t,
            x_m: y[0] + p,
            x_r: y[0],
            x_f: y[2],
            p,
            f_s,
            f_gm: foot.ground_force_n,
            m_a: foot.added_mass_kg,
            mode: self.contact.mode,
        });
        while self.next_sample_s <= t {
            self.next_sample_s += self.series_interval_s;
        }
    }

    /// Metrics of the run so far (the end point counts as a candidate for the highest point).
    pub fn summary(&self) -> JumpSummary {
        let mut copy = self.metrics.clone();
        let end_height = self.y[0] - self.x_r0;
        if end_height > copy.best_height_m {
            copy.best_height_m = end_height;
            copy.best_time_s = self.t;
        }
        if self.t >= self.push_off_start_s && end_height > copy.final_height_m {
            copy.final_height_m = end_height;
            copy.final_time_s = self.t;
        }
        JumpSummary {
            jump_height_m: copy.best_height_m,
            final_jump_height_m: copy.final_height_m,
            max_depth_m: self.contact.max_depth_m,
            peak_added_mass_kg: copy.peak_added_mass_kg,
            liftoff_time_s: copy.first_liftoff_s,
            final_liftoff_time_s: copy.final_liftoff_s,
            com_rise_m: copy.com_rise_m,
            max_spring_compression_m: copy.max_spring_compression_m,
            touchdown_speeds_m_s: copy.touchdown_speeds_m_s,
            apex_time_s: copy.best_time_s,
            final_apex_time_s: copy.final_time_s,
            peak_motor_force_n: copy.peak_motor_force_n,
            peak_motor_power_w: copy.peak_motor_power_w,
            motor_work_j: copy.motor_work_j,
            events: self.events.clone(),
            rhs_evaluations: self.dp.rhs_evaluations,
            steps_accepted: self.dp.accepted,
            steps_rejected: self.dp.rejected,
            mode_switches: copy.mode_switches,
            end_time_s: self.t,
        }
    }
}

/// The Dormand-Prince stepper of a plant run from `y0` (layout `[x_r, v_r, x_f, v_f, ..]`),
/// tolerances and largest step from `opts`, weighing the errors as every simulation does.
pub fn plant_stepper<const N: usize>(opts: &SimOptions, y0: &SVector<f64, N>) -> DormandPrince<N> {
    let mut dp = DormandPrince::new(opts.rtol, opts.atol, opts.max_step_s, 1e-5);
    // Heights are reported from the start: positions (even components) are weighed by
    // their displacement from the initial state, velocities by their size.
    for i in (0..N).step_by(2) {
        dp.origin[i] = y0[i];
    }
    // The foot's velocity rings about zero at the foot mode (about 53 Hz in flight):
    // weighed by its value at the step, its tolerance would collapse at every crossing.
    // It is weighed by the largest foot speed reached instead (21 % fewer steps for the
    // same heights). The rod's velocity is not: under a stale large scale, the decaying
    // 8 Hz ringing of a long delay on hard ground accumulates phase error (1.6e-6 m
    // instead of 6.3e-7 m at rtol 1e-6).
    dp.scale_by_largest[3] = true;
    dp
}

/// Rod apexes (`x_r'` crossing 0 downward) in `[step.t0, t_new]`, located exactly on the
/// dense output: `(t, x_r)` of each (at most one per half of the interval). `v_r0` and
/// `v_r_new` are the rod velocities at both ends (as the dense output gives them).
fn apexes<const N: usize>(
    step: &DenseStep<N>,
    v_r0: f64,
    t_new: f64,
    v_r_new: f64,
) -> [Option<(f64, f64)>; 2] {
    let t0 = step.t0;
    let t_mid = 0.5 * (t0 + t_new);
    let g = |t: f64| -step.at(t).get(1);
    let samples = [(t0, -v_r0), (t_mid, g(t_mid)), (t_new, -v_r_new)];
    let mut found = [None; 2];
    for (w, slot) in samples.windows(2).zip(&mut found) {
        let ((ta, ga), (tb, gb)) = (w[0], w[1]);
        // The rod must have been rising faster than APEX_MIN_SPEED: no apexes from rounding noise at rest.
        if ga < -APEX_MIN_SPEED_M_S && gb >= 0.0 {
            let te = if gb == 0.0 {
                tb
            } else {
                locate_crossing(g, ta, ga, tb, gb, EVENT_TOLERANCE_S)
            };
            *slot = Some((te, step.at(te).get(0)));
        }
    }
    found
}

/// The right-hand side: `[x_r', v_r', x_f', v_f', ..]` in the current ground mode.
struct PlantRhs<'a, A> {
    robot: &'a Robot,
    sand: &'a Sand,
    contact: &'a Contact,
    actuation: &'a mut A,
}

impl<A: Actuation<N>, const N: usize> Rhs<N> for PlantRhs<'_, A> {
    #[inline]
    fn stage_times(&mut self, times: &[f64; STAGE_TIMES]) {
        self.actuation.stage_times(times);
    }

    #[inline]
    fn eval(&mut self, stage: usize, t: f64, y: &SVector<f64, N>) -> SVector<f64, N> {
        let (robot, contact) = (self.robot, self.contact);
        let f_s = robot.spring_force(y[0], y[1], y[2], y[3]);
        let mut dy = SVector::<f64, N>::zeros();
        let a_r = self.actuation.rod_accel(robot, stage, t, y, f_s, &mut dy);
        dy[0] = y[1];
        dy[1] = a_r;
        if contact.mode == GroundMode::Static {
            dy[2] = 0.0;
            dy[3] = 0.0;
        } else {
            dy[2] = y[3];
            dy[3] = contact.foot(robot, self.sand, y[2], y[3], f_s).accel_m_s2;
        }
        dy
    }
}
