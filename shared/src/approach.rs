//! The move to the trajectory's start when the rig is armed away from it.
//!
//! On a board the encoder's zero is wherever the carriage sat at power-up, so `Arm` generally
//! finds the carriage some millimetres from the start position (the sine's -A or +A). Holding
//! the start setpoint at once is a step of that size: the position loop saturates the drive and
//! overshoots into the stroke limit (found running the F407 binary on the virtual board against
//! a robot at rest at 0). The approach is instead a half-cosine from where the carriage is to
//! the start, at most [`APPROACH_SPEED_M_S`] at its fastest, then a dwell of
//! [`APPROACH_DWELL_S`] at the start so the robot is at rest there when the jump begins, as it
//! is in the simulations that start it there. A `Start` that arrives meanwhile waits for the
//! end of the dwell. Within [`APPROACH_MIN_M`] of the start there is no approach (the lockstep
//! rigs, whose plant starts at the start position, never see one).

use crate::profile::Setpoint;

/// Peak speed of the approach, m/s.
pub const APPROACH_SPEED_M_S: f32 = 0.05;
/// Rest at the start position after the approach, s.
pub const APPROACH_DWELL_S: f32 = 0.3;
/// Closer than this to the start, the start setpoint is held at once, m.
pub const APPROACH_MIN_M: f32 = 0.5e-3;

/// An approach in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Approach {
    from_m: f32,
    to_m: f32,
    /// Ticks of the moving part.
    move_ticks: u32,
    /// Ticks of the moving part and the dwell.
    total_ticks: u32,
    tick: u32,
    tick_hz: f32,
}

impl Approach {
    /// The approach from `from_m` to `to_m` at `tick_hz`, or `None` when they are within
    /// [`APPROACH_MIN_M`] (or either is not finite).
    pub fn new(from_m: f32, to_m: f32, tick_hz: u32) -> Option<Self> {
        let distance = (to_m - from_m).abs();
        if !(distance.is_finite() && distance > APPROACH_MIN_M) || tick_hz == 0 {
            return None;
        }
        let hz = tick_hz as f32;
        // Half-cosine: peak speed pi d / (2 T).
        let move_s = core::f32::consts::PI * distance / (2.0 * APPROACH_SPEED_M_S);
        let move_ticks = (move_s * hz) as u32 + 1;
        let total_ticks = move_ticks + (APPROACH_DWELL_S * hz) as u32;
        Some(Self {
            from_m,
            to_m,
            move_ticks,
            total_ticks,
            tick: 0,
            tick_hz: hz,
        })
    }

    /// This tick's setpoint (then advances); the start setpoint during the dwell.
    pub fn advance(&mut self) -> Setpoint {
        let k = self.tick.min(self.move_ticks);
        self.tick = self.tick.saturating_add(1);
        let t_total = self.move_ticks as f32 / self.tick_hz;
        let w = core::f32::consts::PI / t_total;
        let d = self.to_m - self.from_m;
        let phase = w * (k as f32 / self.tick_hz);
        if k >= self.move_ticks {
            return Setpoint {
                position_m: self.to_m,
                velocity_m_s: 0.0,
                accel_m_s2: 0.0,
            };
        }
        Setpoint {
            position_m: self.from_m + d * 0.5 * (1.0 - libm_cos(phase)),
            velocity_m_s: d * 0.5 * w * libm_sin(phase),
            accel_m_s2: d * 0.5 * w * w * libm_cos(phase),
        }
    }

    /// The move and the dwell are over.
    pub fn done(&self) -> bool {
        self.tick >= self.total_ticks
    }

    /// Ticks the approach takes in all (move and dwell).
    pub fn total_ticks(&self) -> u32 {
        self.total_ticks
    }
}

fn libm_cos(x: f32) -> f32 {
    libm::cosf(x)
}

fn libm_sin(x: f32) -> f32 {
    libm::sinf(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_approach_at_the_start() {
        assert!(Approach::new(-0.01875, -0.01875 + 1e-4, 10_000).is_none());
        assert!(Approach::new(f32::NAN, 0.0, 10_000).is_none());
    }

    #[test]
    fn the_approach_is_smooth_bounded_and_ends_at_rest_at_the_start() {
        let mut a = Approach::new(0.0, -0.01875, 10_000).expect("an approach");
        let mut last = 0.0f32;
        let mut peak_v = 0.0f32;
        let n = a.total_ticks();
        assert!(n > 3000 && n < 10_000, "{n} ticks");
        for _ in 0..n {
            let sp = a.advance();
            assert!(
                (sp.position_m - last).abs() < 1e-5,
                "a step of {}",
                sp.position_m - last
            );
            last = sp.position_m;
            peak_v = peak_v.max(sp.velocity_m_s.abs());
        }
        assert!(a.done());
        assert!((last + 0.01875).abs() < 1e-7);
        assert!(
            peak_v <= APPROACH_SPEED_M_S * 1.001 && peak_v > APPROACH_SPEED_M_S * 0.99,
            "{peak_v}"
        );
    }
}
