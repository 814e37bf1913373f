//! The prescribed motor stroke `p(t)` of kinematic runs: an adapter over the core's
//! trajectories (one implementation shared by firmware and simulator), open to replayed logs.

use sandjumper_core::trajectory::{JumpKind, Kinematics, SineJump};

/// Name of a jump kind as the CLI and files write it.
pub fn kind_name(kind: JumpKind) -> &'static str {
    match kind {
        JumpKind::Single => "single",
        JumpKind::Stutter => "stutter",
        JumpKind::DelayedStutter => "delayed",
    }
}

/// Parse a jump kind name (`single`, `stutter`, `delayed`).
pub fn parse_kind(name: &str) -> Option<JumpKind> {
    match name {
        "single" => Some(JumpKind::Single),
        "stutter" => Some(JumpKind::Stutter),
        "delayed" => Some(JumpKind::DelayedStutter),
        _ => None,
    }
}

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
    /// The piece of `p` containing `t_s` (right-continuous, as [`eval`](Self::eval)) in
    /// closed form, when the stroke is made of cosines and holds; `None` otherwise (then only
    /// `eval` is used). The kinematic drive evaluates such pieces without a libm call per
    /// stage.
    fn cosine_piece(&self, t_s: f64) -> Option<CosinePiece> {
        let _ = t_s;
        None
    }
}

/// One smooth piece of a stroke: on `[start_s, end_s)`,
/// `p(t) = offset_m + amplitude_m cos(angular_freq_rad_s (t - phase_origin_s))`, a hold at
/// `offset_m + amplitude_m` when the angular frequency is 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosinePiece {
    /// Start of the piece (included), s.
    pub start_s: f64,
    /// End of the piece (excluded), s.
    pub end_s: f64,
    /// Amplitude, m (signed).
    pub amplitude_m: f64,
    /// Angular frequency, rad/s.
    pub angular_freq_rad_s: f64,
    /// Time at which the cosine's phase is 0, s.
    pub phase_origin_s: f64,
    /// Centre of the cosine, m (0 for the paper's one-cycle sines).
    pub offset_m: f64,
}

impl CosinePiece {
    /// A hold at `position_m` on `[start_s, end_s)`.
    pub fn hold(start_s: f64, end_s: f64, position_m: f64) -> Self {
        Self {
            start_s,
            end_s,
            amplitude_m: position_m,
            angular_freq_rad_s: 0.0,
            phase_origin_s: 0.0,
            offset_m: 0.0,
        }
    }

    /// Whether `t_s` lies in the piece.
    #[inline]
    pub fn contains(&self, t_s: f64) -> bool {
        t_s >= self.start_s && t_s < self.end_s
    }

    /// The phase `w (t - t0)` at `t_s`, rad.
    #[inline]
    pub fn phase_rad(&self, t_s: f64) -> f64 {
        self.angular_freq_rad_s * (t_s - self.phase_origin_s)
    }

    /// `p`, `p'`, `p''` given `(sin, cos)` of the phase.
    #[inline]
    pub fn kinematics(&self, sin: f64, cos: f64) -> Kinematics {
        let (a, w) = (self.amplitude_m, self.angular_freq_rad_s);
        if w == 0.0 {
            return Kinematics {
                position_m: self.offset_m + a,
                velocity_m_s: 0.0,
                accel_m_s2: 0.0,
            };
        }
        Kinematics {
            position_m: self.offset_m + a * cos,
            velocity_m_s: -a * w * sin,
            accel_m_s2: -a * w * w * cos,
        }
    }

    /// `p`, `p'`, `p''` at `t_s` (one `sin_cos`).
    pub fn eval(&self, t_s: f64) -> Kinematics {
        let (s, c) = self.phase_rad(t_s).sin_cos();
        self.kinematics(s, c)
    }
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
    /// The pieces of [`SineJump::eval`]: hold `p(0)` before 0; the cosine from 0 (to `T/2`
    /// for the delayed stutter, to the end otherwise); the delayed stutter's hold at `-A` and
    /// its second half, phase-shifted by `tau`; the final hold.
    fn cosine_piece(&self, t_s: f64) -> Option<CosinePiece> {
        // Before the start the stroke holds p(0), the signed amplitude.
        let a = self.eval(f64::NAN).position_m;
        let (half, end) = (0.5 * self.period_s(), self.end_s());
        let w = 2.0 * core::f64::consts::PI * self.freq_hz();
        let cosine = |start_s, end_s, phase_origin_s| CosinePiece {
            start_s,
            end_s,
            amplitude_m: a,
            angular_freq_rad_s: w,
            phase_origin_s,
            offset_m: 0.0,
        };
        Some(if t_s.is_nan() || t_s < 0.0 {
            CosinePiece::hold(f64::NEG_INFINITY, 0.0, a)
        } else if t_s >= end {
            CosinePiece::hold(end, f64::INFINITY, a)
        } else if self.kind() != JumpKind::DelayedStutter {
            cosine(0.0, end, 0.0)
        } else if t_s < half {
            cosine(0.0, half, 0.0)
        } else if t_s < half + self.tau_s() {
            CosinePiece::hold(half, half + self.tau_s(), -a)
        } else {
            cosine(half + self.tau_s(), end, self.tau_s())
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_pieces_reproduce_every_sine_jump() {
        let jumps = [
            SineJump::new(JumpKind::Single, 0.01875, 10.0, 0.0).unwrap(),
            SineJump::new(JumpKind::Stutter, 0.01875, 13.0, 0.0).unwrap(),
            SineJump::new(JumpKind::DelayedStutter, 0.02, 7.0, 0.3).unwrap(),
            SineJump::new(JumpKind::DelayedStutter, 0.02, 7.0, 0.0).unwrap(),
        ];
        for jump in jumps {
            let mut times: Vec<f64> = (-10..=1200).map(|i| i as f64 * 1e-3).collect();
            for bp in jump.breakpoints_s() {
                times.extend([bp.next_down(), bp, bp.next_up()]);
            }
            for t in times {
                let piece = jump.cosine_piece(t).unwrap();
                assert!(
                    piece.contains(t) || t < 0.0,
                    "{jump:?}: {t} outside {piece:?}"
                );
                let (k, e) = (piece.eval(t), Stroke::eval(&jump, t));
                for (x, y, scale) in [
                    (k.position_m, e.position_m, 0.02),
                    (k.velocity_m_s, e.velocity_m_s, 1.0),
                    (k.accel_m_s2, e.accel_m_s2, 100.0),
                ] {
                    assert!(
                        (x - y).abs() <= 1e-15 * scale,
                        "{jump:?} at {t}: {x} vs {y}"
                    );
                }
            }
        }
    }
}
