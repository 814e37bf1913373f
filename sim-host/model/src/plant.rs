//! Force-driven plant for hardware-in-the-loop: all three bodies integrated, the motor force
//! held constant over each control period (zero-order hold), events located inside.

use crate::error::SimError;
use crate::fastmath::exp_neg;
use crate::ground::{GroundLaw, Sand};
use crate::hybrid::Contact;
use crate::hybrid::GroundMode;
use crate::jump::rest_heights;
use crate::options::{SimOptions, check_options};
use crate::params::{DriveParams, ModelName, Params};
use crate::record::JumpSummary;
use crate::robot::Robot;
use crate::simulation::{Actuation, Simulation};
use nalgebra::Vector6;

/// The motor drive of docs/model.md: `F_m = clamp(K_f i, -F_peak, F_peak)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorDrive {
    /// K_f, N/A.
    pub force_constant_n_a: f64,
    /// F_peak, N.
    pub peak_force_n: f64,
    /// First-order current lag time constant, s (0: none).
    pub current_lag_s: f64,
}

impl MotorDrive {
    /// The drive described by `drive`.
    pub fn new(drive: &DriveParams) -> Self {
        Self {
            force_constant_n_a: drive.force_constant_n_a,
            peak_force_n: drive.peak_force_n,
            current_lag_s: drive.current_lag_s,
        }
    }

    /// Commanded force for a current command, N: `clamp(K_f i, -F_peak, F_peak)`.
    pub fn force_n(&self, current_a: f64) -> f64 {
        (self.force_constant_n_a * current_a).clamp(-self.peak_force_n, self.peak_force_n)
    }
}

/// Snapshot of the plant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantState {
    /// Time, s.
    pub t_s: f64,
    /// Motor (carriage) height, m.
    pub x_m: f64,
    /// Rod height, m.
    pub x_r: f64,
    /// Foot height, m.
    pub x_f: f64,
    /// Motor velocity, m/s.
    pub v_m: f64,
    /// Rod velocity, m/s.
    pub v_r: f64,
    /// Foot velocity, m/s.
    pub v_f: f64,
    /// Motor position relative to the rod, p = x_m - x_r, m (what the encoder measures).
    pub p: f64,
    /// Spring force, N.
    pub f_s: f64,
    /// Ground force on the foot, N.
    pub f_gm: f64,
    /// Motor force actually applied (after clamp and lag), N.
    pub f_m: f64,
    /// Added mass, kg.
    pub m_a: f64,
    /// Ground mode.
    pub mode: GroundMode,
    /// Foot depth below the undisturbed surface, m (negative above it).
    pub depth_m: f64,
}

/// Force-driven actuation: `F_m(t)` = commanded force (clamped to F_peak) held over a
/// control period, reached through the optional first-order current lag (solved exactly:
/// `F_m(t) = F_cmd + (F_m(t_k) - F_cmd) exp(-(t - t_k)/tau)`).
#[derive(Clone, Debug, PartialEq)]
pub struct Forced {
    /// Start of the current control period, s.
    pub period_start_s: f64,
    /// Applied force at the start of the period, N.
    pub force_at_start_n: f64,
    /// Commanded (clamped) force, N.
    pub command_n: f64,
    /// Lag time constant, s (0: none).
    pub lag_s: f64,
    /// The last evaluation `(t, F_m(t))`: a Dormand-Prince step evaluates its end twice, the
    /// metrics and the next period's start once more (saves an `exp` each).
    last: core::cell::Cell<(f64, f64)>,
}

impl Forced {
    /// A period starting at `period_start_s` with the applied force `force_at_start_n`, N,
    /// moving towards `command_n`, N, with lag time constant `lag_s`, s (0: none).
    pub fn new(period_start_s: f64, force_at_start_n: f64, command_n: f64, lag_s: f64) -> Self {
        Self {
            period_start_s,
            force_at_start_n,
            command_n,
            lag_s,
            last: core::cell::Cell::new((f64::NAN, 0.0)),
        }
    }

    /// Applied motor force at `t`, N.
    #[inline]
    pub fn force_n(&self, t: f64) -> f64 {
        if self.lag_s > 0.0 {
            let (t_last, f_last) = self.last.get();
            if t_last == t {
                return f_last;
            }
            let f = self.command_n
                + (self.force_at_start_n - self.command_n)
                    * exp_neg((t - self.period_start_s) / self.lag_s);
            self.last.set((t, f));
            f
        } else {
            self.command_n
        }
    }
}

impl Actuation<6> for Forced {
    #[inline]
    fn rod_accel(
        &self,
        robot: &Robot,
        _stage: usize,
        t: f64,
        y: &Vector6<f64>,
        f_s: f64,
        dy: &mut Vector6<f64>,
    ) -> f64 {
        let f_m = self.force_n(t);
        dy[4] = y[5];
        dy[5] = robot.motor_accel(f_m);
        robot.rod_accel_forced(f_s, f_m)
    }
    fn motor_position(&self, _t: f64, y: &Vector6<f64>) -> f64 {
        y[4] - y[0]
    }
    fn motor_velocity(&self, _t: f64, y: &Vector6<f64>) -> f64 {
        y[5] - y[1]
    }
    fn motor_force(&self, _robot: &Robot, t: f64, _y: &Vector6<f64>, _f_s: f64) -> f64 {
        self.force_n(t)
    }
}

/// The force-driven plant: the same robot and ground as kinematic runs, with the motor a
/// separate body. State `[x_r, v_r, x_f, v_f, x_m, v_m]`.
#[derive(Clone, Debug)]
pub struct Plant {
    sim: Simulation<Forced, 6>,
    drive: MotorDrive,
}

impl Plant {
    /// A plant at rest in static equilibrium with `p = initial_p_m`: `F_s = M g`, the motor
    /// force holding the carriage (`F_m = m_m g`), the foot sunk to `z0` on sand.
    pub fn new(
        params: &Params,
        model: ModelName,
        initial_p_m: f64,
        opts: &SimOptions,
    ) -> Result<Plant, SimError> {
        params.validate()?;
        check_options(opts)?;
        let limit = params.robot.stroke_limit_m;
        if !(initial_p_m.is_finite() && initial_p_m.abs() <= limit) {
            return Err(SimError::InvalidInput {
                field: "initial_p_m",
                value: initial_p_m.to_string(),
                allowed: format!("|p| <= stroke limit {limit} m"),
            });
        }
        let robot = Robot::new(params);
        let sand = Sand::new(params, GroundLaw::resolve(model, &params.model));
        let (x_r, x_f) = rest_heights(&robot, &sand);
        let hold = robot.motor_mass_kg() * robot.gravity_m_s2();
        let drive = MotorDrive::new(&params.drive);
        let forced = Forced::new(0.0, hold, hold, drive.current_lag_s);
        let y0 = Vector6::new(x_r, 0.0, x_f, 0.0, x_r + initial_p_m, 0.0);
        let contact = Contact::at_rest(&sand, x_f);
        let mut sim = Simulation::new(robot, sand, contact, forced, y0, 0.0, opts);
        sim.settle()?;
        Ok(Plant { sim, drive })
    }

    /// Set when the push-off half of the trajectory begins, s of plant time (the summary's
    /// final jump height, final apex and final lift-off count from then on, as in a
    /// kinematic jump). Call before the plant reaches that time.
    pub fn set_push_off_start(&mut self, push_off_start_s: f64) {
        self.sim.set_push_off_start(push_off_start_s);
    }

    /// The motor drive (force constant, F_peak, lag) of this plant.
    pub fn drive(&self) -> &MotorDrive {
        &self.drive
    }

    /// Advance exactly `dt_s` with the commanded motor force held (zero-order hold; clamped to
    /// ±F_peak; through the current lag if any). Mode switches inside are located exactly.
    pub fn advance(&mut self, dt_s: f64, motor_force_n: f64) -> Result<(), SimError> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(SimError::InvalidInput {
                field: "dt_s",
                value: dt_s.to_string(),
                allowed: "a control period > 0 s".into(),
            });
        }
        if !motor_force_n.is_finite() {
            return Err(SimError::InvalidInput {
                field: "motor_force_n",
                value: motor_force_n.to_string(),
                allowed: "a finite force".into(),
            });
        }
        let t = self.sim.time_s();
        let applied = self.sim.actuation.force_n(t);
        self.sim.actuation = Forced::new(
            t,
            applied,
            motor_force_n.clamp(-self.drive.peak_force_n, self.drive.peak_force_n),
            self.drive.current_lag_s,
        );
        // With a current lag the applied force is continuous across the period boundary (only
        // its slope changes), so the right-hand side at `t` is unchanged and the integrator's
        // last stage stays valid (one evaluation fewer per period); without a lag it steps.
        if self.drive.current_lag_s <= 0.0 {
            self.sim.discontinuity();
        }
        self.sim.advance_to(t + dt_s, false)?;
        Ok(())
    }

    /// Advance exactly `dt_s` with a current command `i` (A): `F = clamp(K_f i, ±F_peak)`.
    pub fn advance_current(&mut self, dt_s: f64, current_a: f64) -> Result<(), SimError> {
        let force = self.drive.force_n(current_a);
        self.advance(dt_s, force)
    }

    /// Current state.
    pub fn state(&self) -> PlantState {
        let y = self.sim.state();
        let t = self.sim.time_s();
        let f_s = self.sim.spring_force(y);
        let foot = self
            .sim
            .contact
            .foot(&self.sim.robot, &self.sim.sand, y[2], y[3], f_s);
        PlantState {
            t_s: t,
            x_m: y[4],
            x_r: y[0],
            x_f: y[2],
            v_m: y[5],
            v_r: y[1],
            v_f: y[3],
            p: y[4] - y[0],
            f_s,
            f_gm: foot.ground_force_n,
            f_m: self.sim.actuation.force_n(t),
            m_a: foot.added_mass_kg,
            mode: self.sim.contact.mode,
            depth_m: -y[2],
        }
    }

    /// Metrics of what has been simulated so far (heights relative to the initial rod height).
    pub fn summary(&self) -> JumpSummary {
        self.sim.summary()
    }
}
