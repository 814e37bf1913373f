//! The slow-intrusion fixture's physics (docs/model.md section 6): the motor is
//! clamped to the bed, so the rod and the foot (rigidly fixed to it for this test) are the only
//! moving body, driven by the motor force into the sand below.
//!
//! With the motor fixed, `p = x_m - x_r` grows as the rod goes down; the foot meets the free
//! surface at `p = surface_p_m`, so the depth is `z = p - surface_p_m`. Moving mass
//! `m = m_r + m_f`:
//!
//! `m p'' = m g + F_m - F_GM`
//!
//! The sand is elastic-perfectly-plastic under the foot \[chosen\]: a contact spring of
//! stiffness [`CONTACT_STIFFNESS_N_M`] (with damping) on the bottom of the hole, which flows
//! plastically when its force would exceed the resisting force `F_p(z)` (plus the
//! re-intrusion overshoot once the foot has left the hole bottom, anchored where it meets the
//! sand again), plus the drag `alpha v^2` while flowing. Withdrawing leaves the hole: no force
//! until the foot is back on its bottom. The drive: saturation at `F_peak` and a
//! first-order current lag, as in [`crate::plant::Plant`] (the DAC's quantization is the rig's,
//! outside this module). Integrated with semi-implicit Euler in steps of [`SUBSTEP_S`].

use crate::error::SimError;
use crate::ground::{GroundLaw, Sand};
use crate::params::{ModelName, Params};

/// Stiffness of the sand under the foot before it yields, N/m [chosen: 40 N compress it 0.2 mm].
pub const CONTACT_STIFFNESS_N_M: f64 = 2.0e5;
/// Damping ratio of the contact \[chosen\].
pub const CONTACT_DAMPING_RATIO: f64 = 0.5;
/// Integration step, s (a tenth of the rigs' 100 us control period).
pub const SUBSTEP_S: f64 = 1e-5;

/// The clamped motor, the rod with its foot, and the sand.
#[derive(Debug)]
pub struct IntrusionRig {
    sand: Sand,
    mass_kg: f64,
    gravity: f64,
    force_constant_n_a: f64,
    peak_force_n: f64,
    current_lag_s: f64,
    surface_p_m: f64,
    /// `p`, m, and `p'`, m/s.
    p_m: f64,
    v_m_s: f64,
    /// Depth of the hole's bottom (plastic depth), m.
    hole_m: f64,
    /// The foot has left the hole's bottom since it last flowed.
    left_bottom: bool,
    anchor_m: Option<f64>,
    motor_force_n: f64,
    command_n: f64,
}

impl IntrusionRig {
    /// The foot resting on the surface (`p = surface_p_m`), motor force holding the rod.
    pub fn new(params: &Params, model: ModelName, surface_p_m: f64) -> Result<Self, SimError> {
        let law = GroundLaw::resolve(model, &params.model);
        if law.is_rigid() {
            return Err(SimError::InvalidInput {
                field: "model",
                value: model.as_str().into(),
                allowed: "a sand model (eq1-linear, eq1, eq4): a rigid floor cannot be intruded"
                    .into(),
            });
        }
        let mass_kg = params.robot.rod_mass_kg + params.robot.foot_mass_kg;
        let gravity = params.robot.gravity_m_s2;
        let hold = -mass_kg * gravity;
        Ok(Self {
            sand: Sand::new(params, law),
            mass_kg,
            gravity,
            force_constant_n_a: params.drive.force_constant_n_a,
            peak_force_n: params.drive.peak_force_n,
            current_lag_s: params.drive.current_lag_s,
            surface_p_m,
            p_m: surface_p_m,
            v_m_s: 0.0,
            hole_m: 0.0,
            left_bottom: false,
            anchor_m: None,
            motor_force_n: hold,
            command_n: hold,
        })
    }

    /// Depth of the foot below the free surface now, m.
    pub fn depth_m(&self) -> f64 {
        self.p_m - self.surface_p_m
    }

    /// Moving mass (rod and foot), kg.
    pub fn moving_mass_kg(&self) -> f64 {
        self.mass_kg
    }

    /// `p`, m.
    pub fn position_m(&self) -> f64 {
        self.p_m
    }

    /// The force the motor applies now (after the current lag), N.
    pub fn motor_force_n(&self) -> f64 {
        self.motor_force_n
    }

    /// The motor's force constant, N/A.
    pub fn force_constant_n_a(&self) -> f64 {
        self.force_constant_n_a
    }

    /// Advance `steps` integration steps of [`SUBSTEP_S`] with the drive commanded to
    /// `command_n` (clamped to `F_peak`, through the current lag).
    pub fn advance_steps(&mut self, steps: u32, command_n: f64) -> Result<(), SimError> {
        self.command_n = command_n;
        let target = self.command_n.clamp(-self.peak_force_n, self.peak_force_n);
        let dt = SUBSTEP_S;
        let lag = if self.current_lag_s > 0.0 {
            1.0 - (-dt / self.current_lag_s).exp()
        } else {
            1.0
        };
        for _ in 0..steps {
            self.motor_force_n += (target - self.motor_force_n) * lag;
            let f_gm = self.sand_force(self.depth_m(), self.v_m_s);
            let accel = self.gravity + (self.motor_force_n - f_gm) / self.mass_kg;
            self.v_m_s += accel * dt;
            self.p_m += self.v_m_s * dt;
        }
        if !(self.p_m.is_finite() && self.v_m_s.is_finite()) {
            return Err(SimError::InvalidInput {
                field: "intrusion fixture",
                value: format!("p = {} m, v = {} m/s", self.p_m, self.v_m_s),
                allowed: "a finite state (the simulation diverged)".into(),
            });
        }
        Ok(())
    }

    /// The sand's force on the foot at depth `z` moving at `v` (down positive), and whether it
    /// flows; updates the hole.
    fn sand_force(&mut self, z: f64, v: f64) -> f64 {
        let gap = z - self.hole_m;
        if gap <= 0.0 || z <= 0.0 {
            if self.hole_m > 0.0 {
                self.left_bottom = true;
            }
            return 0.0;
        }
        let k = CONTACT_STIFFNESS_N_M;
        let c = 2.0 * CONTACT_DAMPING_RATIO * (k * self.mass_kg).sqrt();
        let elastic = (k * gap + c * v).max(0.0);
        if self.left_bottom {
            // Back on the bottom after leaving it: a re-intrusion episode starts here.
            self.anchor_m = Some(self.hole_m);
            self.left_bottom = false;
        }
        let yield_n = self.sand.resisting_force(z, self.anchor_m);
        if elastic <= yield_n {
            return elastic;
        }
        // Plastic flow: the hole deepens so the contact carries exactly the yield force.
        self.hole_m = z - yield_n / k;
        let drag = if v > 0.0 {
            self.sand.drag_coefficient(z) * v * v
        } else {
            0.0
        };
        yield_n + drag
    }
}
