//! The robot: three bodies on one vertical line and the spring (docs/model.md section 1).
//!
//! Heights `x` positive up, m; velocities m/s; forces N. `F_s > 0`: spring compressed.

use crate::params::Params;

/// Masses, spring and gravity, read through accessors. Built only by [`Robot::new`], which
/// also forms the reciprocals the right-hand side multiplies by: the fields are private so
/// that a mass cannot change without them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Robot {
    motor_mass_kg: f64,
    rod_mass_kg: f64,
    foot_mass_kg: f64,
    spring_stiffness_n_m: f64,
    spring_damping_n_s_m: f64,
    spring_rest_length_m: f64,
    gravity_m_s2: f64,
    /// `1/M`, `m_m/M`, `1/m_r`, `1/m_m`, `1/m_f`: divisions taken out of every evaluation of
    /// the right-hand side, where they would sit on the critical path of each stage.
    reciprocals: Reciprocals,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Reciprocals {
    motor_rod_per_kg: f64,
    motor_share: f64,
    rod_per_kg: f64,
    motor_per_kg: f64,
    foot_per_kg: f64,
}

impl Robot {
    /// The robot of `params`.
    pub fn new(params: &Params) -> Self {
        let r = &params.robot;
        Self {
            motor_mass_kg: r.motor_mass_kg,
            rod_mass_kg: r.rod_mass_kg,
            foot_mass_kg: r.foot_mass_kg,
            spring_stiffness_n_m: r.spring_stiffness_n_m,
            spring_damping_n_s_m: r.spring_damping_n_s_m,
            spring_rest_length_m: r.spring_rest_length_m,
            gravity_m_s2: r.gravity_m_s2,
            reciprocals: Reciprocals {
                motor_rod_per_kg: 1.0 / (r.motor_mass_kg + r.rod_mass_kg),
                motor_share: r.motor_mass_kg / (r.motor_mass_kg + r.rod_mass_kg),
                rod_per_kg: 1.0 / r.rod_mass_kg,
                motor_per_kg: 1.0 / r.motor_mass_kg,
                foot_per_kg: 1.0 / r.foot_mass_kg,
            },
        }
    }

    /// m_m, kg.
    #[inline]
    pub fn motor_mass_kg(&self) -> f64 {
        self.motor_mass_kg
    }

    /// m_r, kg.
    #[inline]
    pub fn rod_mass_kg(&self) -> f64 {
        self.rod_mass_kg
    }

    /// m_f, kg.
    #[inline]
    pub fn foot_mass_kg(&self) -> f64 {
        self.foot_mass_kg
    }

    /// k_s, N/m.
    #[inline]
    pub fn spring_stiffness_n_m(&self) -> f64 {
        self.spring_stiffness_n_m
    }

    /// c_s, N s/m.
    #[inline]
    pub fn spring_damping_n_s_m(&self) -> f64 {
        self.spring_damping_n_s_m
    }

    /// L0, m.
    #[inline]
    pub fn spring_rest_length_m(&self) -> f64 {
        self.spring_rest_length_m
    }

    /// g, m/s^2.
    #[inline]
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// `M = m_m + m_r`, kg.
    pub fn motor_rod_mass_kg(&self) -> f64 {
        self.motor_mass_kg + self.rod_mass_kg
    }

    /// `F_s = k_s (L0 - (x_r - x_f)) + c_s (x_f' - x_r')`, N.
    #[inline]
    pub fn spring_force(&self, x_r: f64, v_r: f64, x_f: f64, v_f: f64) -> f64 {
        self.spring_stiffness_n_m * (self.spring_rest_length_m - (x_r - x_f))
            + self.spring_damping_n_s_m * (v_f - v_r)
    }

    /// Downward load of the foot on the ground, `L = F_s + m_f g`, N.
    #[inline]
    pub fn foot_load(&self, spring_force_n: f64) -> f64 {
        spring_force_n + self.foot_mass_kg * self.gravity_m_s2
    }

    /// Rod-above-foot distance `x_r - x_f` at which the spring carries motor and rod at rest
    /// (`F_s = M g`), m.
    pub fn rest_rod_above_foot_m(&self) -> f64 {
        self.spring_rest_length_m
            - self.motor_rod_mass_kg() * self.gravity_m_s2 / self.spring_stiffness_n_m
    }

    /// Kinematic drive: `M x_r'' = -M g + F_s - m_m p''`, m/s^2.
    #[inline]
    pub fn rod_accel_kinematic(&self, spring_force_n: f64, p_accel_m_s2: f64) -> f64 {
        let r = &self.reciprocals;
        spring_force_n * r.motor_rod_per_kg - (self.gravity_m_s2 + r.motor_share * p_accel_m_s2)
    }

    /// Force-driven: `m_r x_r'' = -m_r g - F_m + F_s`, m/s^2.
    #[inline]
    pub fn rod_accel_forced(&self, spring_force_n: f64, motor_force_n: f64) -> f64 {
        (spring_force_n - motor_force_n) * self.reciprocals.rod_per_kg - self.gravity_m_s2
    }

    /// Force-driven: `m_m x_m'' = -m_m g + F_m`, m/s^2.
    #[inline]
    pub fn motor_accel(&self, motor_force_n: f64) -> f64 {
        motor_force_n * self.reciprocals.motor_per_kg - self.gravity_m_s2
    }

    /// Acceleration of the foot alone under its weight and the spring, `-g - F_s/m_f`, m/s^2.
    #[inline]
    pub fn foot_accel_aerial(&self, spring_force_n: f64) -> f64 {
        -(spring_force_n * self.reciprocals.foot_per_kg) - self.gravity_m_s2
    }

    /// Motor force implied by the motor's acceleration, `F_m = m_m (x_m'' + g)`, N.
    #[inline]
    pub fn motor_force_for(&self, motor_accel_m_s2: f64) -> f64 {
        self.motor_mass_kg * (motor_accel_m_s2 + self.gravity_m_s2)
    }

    /// Natural frequency of motor + rod on the spring over a rigid floor, `sqrt(k_s/M)/2pi`, Hz.
    pub fn hard_ground_frequency_hz(&self) -> f64 {
        (self.spring_stiffness_n_m / self.motor_rod_mass_kg()).sqrt() / core::f64::consts::TAU
    }
}
