//! The prescribed motor stroke `p(t)` of kinematic runs: an adapter over the core's
//! trajectories (one implementation shared by firmware and simulator), open to replayed logs.

use sandjumper_core::trajectory::{Kinematics, SineJump};

/// A prescribed `p(t)` (m) with its derivatives and the times where `p''` jumps.
pub trait Stroke {
    /// `p(t)`, `p'(t)`, `p''(t)` at `t_s`.
    fn eval(&self, t_s: f64) -> Kinematics;
    /// Ascending times where `p''` is discontinuous; the integrator steps onto each exactly.
    fn breakpoints_s(&self) -> Vec<f64>;
    /// Time the prescribed motion ends, s.
    fn end_s(&self) -> f64;
    /// Start of the push-off half, s (final jump height is taken from here on).
    fn push_off_start_s(&self) -> f64;
}

impl Stroke for SineJump {
    fn eval(&self, t_s: f64) -> Kinematics {
        SineJump::eval(self, t_s)
    }
    fn breakpoints_s(&self) -> Vec<f64> {
        SineJump::breakpoints_s(self).iter().copied().collect()
    }
    fn end_s(&self) -> f64 {
        SineJump::end_s(self)
    }
    fn push_off_start_s(&self) -> f64 {
        SineJump::push_off_start_s(self)
    }
}

/// The motor held at a fixed position `p` (a robot left at rest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldStroke {
    /// Held position, m.
    pub position_m: f64,
}

impl Stroke for HoldStroke {
    fn eval(&self, _t_s: f64) -> Kinematics {
        Kinematics {
            position_m: self.position_m,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        }
    }
    fn breakpoints_s(&self) -> Vec<f64> {
        Vec::new()
    }
    fn end_s(&self) -> f64 {
        0.0
    }
    fn push_off_start_s(&self) -> f64 {
        0.0
    }
}
