//! Commanded motor position `p = x_m - x_r` (docs/model.md section 2): the one-cycle sine jumps.
//!
//! [`SineJump`] is the exact f64 curve used by the simulator (and as the reference the
//! firmware's per-tick f32 evaluation is tested against). All times in seconds, positions in
//! metres, velocities in m/s, accelerations in m/s^2.

use core::f64::consts::PI;
use core::fmt;

pub use crate::stroke::STROKE_M;
/// Lowest forcing frequency accepted, Hz.
pub const MIN_FREQ_HZ: f64 = 0.5;
/// Highest forcing frequency accepted, Hz.
pub const MAX_FREQ_HZ: f64 = 40.0;
/// Longest delay of a delayed stutter, seconds.
pub const MAX_TAU_S: f64 = 5.0;

/// Which one-cycle sine (docs/model.md section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JumpKind {
    /// `p = -A cos(2 pi f t)`: starts low, pushes the rod down, returns; holds `-A` after.
    Single,
    /// `p = +A cos(2 pi f t)`: pull-up half (preliminary hop) then push-off half; holds `+A`.
    Stutter,
    /// Stutter's first half, hold `-A` for `tau`, then the second half; holds `+A`.
    DelayedStutter,
}

/// Commanded position and its first two derivatives at one instant (f64, SI).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Kinematics {
    /// Motor position relative to the rod, m.
    pub position_m: f64,
    /// m/s.
    pub velocity_m_s: f64,
    /// m/s^2.
    pub accel_m_s2: f64,
}

/// Why a trajectory could not be built. Every variant names the value and what is allowed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrajectoryError {
    /// Amplitude must satisfy `0 < A <= max_m` (the stroke).
    Amplitude { amplitude_m: f64, max_m: f64 },
    /// Forcing frequency outside `min_hz..=max_hz`.
    Frequency {
        freq_hz: f64,
        min_hz: f64,
        max_hz: f64,
    },
    /// Delay outside `0..=max_s`.
    Delay { tau_s: f64, max_s: f64 },
    /// A speed outside `(0, max_m_s]`.
    Speed { speed_m_s: f64, max_m_s: f64 },
    /// A position or depth that would leave the stroke `[-stroke_m, stroke_m]`, or is
    /// otherwise inconsistent (`what` names the parameter).
    Position {
        what: &'static str,
        value_m: f64,
        stroke_m: f64,
    },
    /// A duration outside `0..=max_s`.
    Duration {
        what: &'static str,
        value_s: f64,
        max_s: f64,
    },
    /// The control tick rate is outside the supported range.
    TickRate {
        tick_hz: u32,
        min_hz: u32,
        max_hz: u32,
    },
    /// The trajectory is longer than the tick counter can address at this tick rate.
    TooLong { end_s: f64, max_s: f64 },
    /// A replay table that is not (or no longer) committed.
    Replay(crate::replay::ReplayError),
}

impl fmt::Display for TrajectoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Amplitude { amplitude_m, max_m } => write!(
                f,
                "amplitude {amplitude_m} m out of range: must be > 0 and <= {max_m} m (the stroke)"
            ),
            Self::Frequency {
                freq_hz,
                min_hz,
                max_hz,
            } => write!(
                f,
                "frequency {freq_hz} Hz out of range: allowed {min_hz}..={max_hz} Hz"
            ),
            Self::Delay { tau_s, max_s } => {
                write!(f, "delay tau {tau_s} s out of range: allowed 0..={max_s} s")
            }
            Self::Speed { speed_m_s, max_m_s } => write!(
                f,
                "speed {speed_m_s} m/s out of range: must be > 0 and <= {max_m_s} m/s"
            ),
            Self::Position {
                what,
                value_m,
                stroke_m,
            } => write!(
                f,
                "{what} = {value_m} m not allowed: positions must stay within +-{stroke_m} m and be consistent"
            ),
            Self::Duration {
                what,
                value_s,
                max_s,
            } => {
                write!(
                    f,
                    "{what} = {value_s} s out of range: allowed 0..={max_s} s"
                )
            }
            Self::TickRate {
                tick_hz,
                min_hz,
                max_hz,
            } => write!(
                f,
                "control tick rate {tick_hz} Hz out of range: allowed {min_hz}..={max_hz} Hz"
            ),
            Self::TooLong { end_s, max_s } => write!(
                f,
                "trajectory lasts {end_s} s: longer than the {max_s} s the tick counter addresses"
            ),
            Self::Replay(e) => write!(f, "replay table: {e}"),
        }
    }
}

impl core::error::Error for TrajectoryError {}

/// A validated one-cycle sine jump (docs/model.md section 2).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SineJump {
    kind: JumpKind,
    amplitude_m: f64,
    freq_hz: f64,
    tau_s: f64,
}

impl SineJump {
    /// Validated constructor.
    ///
    /// * `amplitude_m`: `0 < A <= STROKE_M` (0.025 m), metres.
    /// * `freq_hz`: `0.5..=40` Hz.
    /// * `tau_s`: `0..=5` s; only used by [`JumpKind::DelayedStutter`] (stored as 0 otherwise,
    ///   but still validated so a bad value is reported, not hidden).
    pub fn new(
        kind: JumpKind,
        amplitude_m: f64,
        freq_hz: f64,
        tau_s: f64,
    ) -> Result<Self, TrajectoryError> {
        // `!(a <= x)` forms reject NaN as well.
        if !(amplitude_m > 0.0 && amplitude_m <= STROKE_M) {
            return Err(TrajectoryError::Amplitude {
                amplitude_m,
                max_m: STROKE_M,
            });
        }
        if !(MIN_FREQ_HZ..=MAX_FREQ_HZ).contains(&freq_hz) {
            return Err(TrajectoryError::Frequency {
                freq_hz,
                min_hz: MIN_FREQ_HZ,
                max_hz: MAX_FREQ_HZ,
            });
        }
        if !(0.0..=MAX_TAU_S).contains(&tau_s) {
            return Err(TrajectoryError::Delay {
                tau_s,
                max_s: MAX_TAU_S,
            });
        }
        let tau_s = if kind == JumpKind::DelayedStutter {
            tau_s
        } else {
            0.0
        };
        Ok(Self {
            kind,
            amplitude_m,
            freq_hz,
            tau_s,
        })
    }

    /// Which jump this is.
    pub fn kind(&self) -> JumpKind {
        self.kind
    }
    /// Stroke amplitude `A`, m.
    pub fn amplitude_m(&self) -> f64 {
        self.amplitude_m
    }
    /// Forcing frequency `f`, Hz.
    pub fn freq_hz(&self) -> f64 {
        self.freq_hz
    }
    /// Delay `tau`, s (0 unless [`JumpKind::DelayedStutter`]).
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
    /// Period `T = 1/f`, s.
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }

    /// `+1` for the stutters (`p = +A cos`), `-1` for the single jump (`p = -A cos`).
    fn sign(&self) -> f64 {
        match self.kind {
            JumpKind::Single => -1.0,
            JumpKind::Stutter | JumpKind::DelayedStutter => 1.0,
        }
    }

    /// Exact f64 curve `p(t)`, `p'(t)`, `p''(t)`. Before `t = 0` it holds `p(0)` with zero
    /// velocity and acceleration; after [`end_s`](Self::end_s) it holds the final value. At a
    /// breakpoint the value of the segment that starts there is returned (right-continuous).
    pub fn eval(&self, t_s: f64) -> Kinematics {
        let a = self.amplitude_m * self.sign();
        let half = 0.5 * self.period_s();
        let hold = |p: f64| Kinematics {
            position_m: p,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        };
        // NaN compares false everywhere: treat it like "before the start".
        if t_s.is_nan() || t_s < 0.0 {
            return hold(a);
        }
        if t_s >= self.end_s() {
            // End of one full cycle: cos(2 pi) = 1.
            return hold(a);
        }
        let phase_t = if self.kind == JumpKind::DelayedStutter && t_s >= half {
            if t_s < half + self.tau_s {
                // The hold at the bottom of the first half: cos(pi) = -1.
                return hold(-a);
            }
            t_s - self.tau_s
        } else {
            t_s
        };
        let w = 2.0 * PI * self.freq_hz;
        let (s, c) = libm::sincos(w * phase_t);
        Kinematics {
            position_m: a * c,
            velocity_m_s: -a * w * s,
            accel_m_s2: -a * w * w * c,
        }
    }

    /// Phase boundaries, ascending: `0, T/2, T/2 + tau, T + tau`, with duplicates removed when
    /// `tau = 0`. `p''` is discontinuous at `0`, at the end and (for `tau > 0`) at both ends of
    /// the delay; `T/2` is where the push-off half starts. An integrator stepping exactly onto
    /// these never straddles a jump in `p''`.
    pub fn breakpoints_s(&self) -> heapless::Vec<f64, 4> {
        let half = 0.5 * self.period_s();
        let mut v = heapless::Vec::new();
        for t in [0.0, half, half + self.tau_s, self.end_s()] {
            if v.last() != Some(&t) {
                // Capacity 4 = number of candidates: cannot fail.
                let _ = v.push(t);
            }
        }
        v
    }

    /// Time the trajectory ends, s: `T + tau` (`T` for single and stutter).
    pub fn end_s(&self) -> f64 {
        self.period_s() + self.tau_s
    }

    /// Start of the push-off half, s: 0 for the single jump, `T/2 + tau` for the stutters.
    pub fn push_off_start_s(&self) -> f64 {
        match self.kind {
            JumpKind::Single => 0.0,
            JumpKind::Stutter | JumpKind::DelayedStutter => 0.5 * self.period_s() + self.tau_s,
        }
    }

    /// Start and end of the delay (the bottom hold), s; `None` unless a delayed stutter with
    /// `tau > 0`. Gain-lowering damping is scheduled inside this window.
    pub fn delay_window_s(&self) -> Option<(f64, f64)> {
        if self.kind == JumpKind::DelayedStutter && self.tau_s > 0.0 {
            let half = 0.5 * self.period_s();
            Some((half, half + self.tau_s))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn rejects_bad_parameters_with_typed_errors() {
        assert!(matches!(
            SineJump::new(JumpKind::Single, 0.03, 10.0, 0.0),
            Err(TrajectoryError::Amplitude { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::Single, 0.0, 10.0, 0.0),
            Err(TrajectoryError::Amplitude { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::Single, f64::NAN, 10.0, 0.0),
            Err(TrajectoryError::Amplitude { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::Stutter, 0.01, 0.4, 0.0),
            Err(TrajectoryError::Frequency { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::Stutter, 0.01, 40.1, 0.0),
            Err(TrajectoryError::Frequency { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::DelayedStutter, 0.01, 10.0, 5.5),
            Err(TrajectoryError::Delay { .. })
        ));
        assert!(matches!(
            SineJump::new(JumpKind::DelayedStutter, 0.01, 10.0, -0.1),
            Err(TrajectoryError::Delay { .. })
        ));
        assert!(SineJump::new(JumpKind::DelayedStutter, 0.025, 40.0, 5.0).is_ok());
        assert!(SineJump::new(JumpKind::Single, 0.01875, 0.5, 0.0).is_ok());
    }

    #[test]
    fn single_starts_low_pushes_down_and_returns() {
        let j = SineJump::new(JumpKind::Single, 0.01875, 10.0, 0.0).unwrap();
        assert_eq!(j.eval(-1.0).position_m, -0.01875);
        assert_eq!(j.eval(0.0).position_m, -0.01875);
        assert!(close(j.eval(0.05).position_m, 0.01875, 1e-15));
        assert!(close(j.eval(0.0999999).position_m, -0.01875, 1e-9));
        assert_eq!(
            j.eval(0.2),
            Kinematics {
                position_m: -0.01875,
                ..Default::default()
            }
        );
        assert_eq!(j.end_s(), 0.1);
        assert_eq!(j.push_off_start_s(), 0.0);
        assert_eq!(j.breakpoints_s().as_slice(), &[0.0, 0.05, 0.1]);
    }

    #[test]
    fn delayed_stutter_holds_bottom_for_tau() {
        let j = SineJump::new(JumpKind::DelayedStutter, 0.01, 10.0, 0.75).unwrap();
        assert_eq!(j.end_s(), 0.85);
        assert_eq!(j.push_off_start_s(), 0.8);
        assert_eq!(j.breakpoints_s().as_slice(), &[0.0, 0.05, 0.8, 0.85]);
        let mid = j.eval(0.4);
        assert_eq!(
            mid,
            Kinematics {
                position_m: -0.01,
                velocity_m_s: 0.0,
                accel_m_s2: 0.0
            }
        );
        // Continuous position and velocity across both ends of the delay.
        for t in [0.05, 0.8] {
            let a = j.eval(t - 1e-9);
            let b = j.eval(t + 1e-9);
            assert!(close(a.position_m, b.position_m, 1e-12));
            assert!(close(a.velocity_m_s, b.velocity_m_s, 1e-6));
        }
        // p'' jumps at the start of the delay: A w^2 on one side, 0 on the other.
        let w = 2.0 * PI * 10.0;
        assert!(close(j.eval(0.05 - 1e-12).accel_m_s2, 0.01 * w * w, 1e-6));
        assert_eq!(j.eval(0.05).accel_m_s2, 0.0);
        assert_eq!(j.eval(0.9).position_m, 0.01);
    }

    #[test]
    fn stutter_velocity_and_accel_are_derivatives() {
        let j = SineJump::new(JumpKind::Stutter, 0.015, 7.0, 0.0).unwrap();
        let h = 1e-6;
        for i in 1..100 {
            let t = i as f64 * j.end_s() / 100.0;
            let d = (j.eval(t + h).position_m - j.eval(t - h).position_m) / (2.0 * h);
            assert!(close(d, j.eval(t).velocity_m_s, 1e-6), "t={t}");
            let dd = (j.eval(t + h).velocity_m_s - j.eval(t - h).velocity_m_s) / (2.0 * h);
            assert!(close(dd, j.eval(t).accel_m_s2, 1e-3), "t={t}");
        }
    }

    #[test]
    fn tau_ignored_except_for_delayed_stutter() {
        let j = SineJump::new(JumpKind::Stutter, 0.01, 10.0, 0.5).unwrap();
        assert_eq!(j.tau_s(), 0.0);
        assert_eq!(j.end_s(), 0.1);
        assert_eq!(j.delay_window_s(), None);
    }
}
