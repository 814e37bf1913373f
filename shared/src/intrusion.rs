//! The slow-intrusion program (docs/model.md section 6): with the motor clamped to the bed, drive
//! the rod down at a constant slow speed to a depth, hold, withdraw part of the way, hold,
//! re-intrude to a (usually deeper) depth, hold, and withdraw to the start. Force comes from
//! the motor current and depth from the encoder: this is how `k1`, `k2`, `delta` and the
//! re-intrusion overshoot are measured.
//!
//! Sign: the commanded quantity is still `p = x_m - x_r`. With the motor clamped, the rod
//! going down makes `p` grow, so "depth d below the start" is `p = start_m + d`.

use crate::trajectory::{Kinematics, STROKE_M, TrajectoryError};

/// Fastest intrusion speed accepted, m/s ("slow": quasi-static, far below impact speeds).
pub const MAX_INTRUSION_SPEED_M_S: f64 = 0.05;
/// Longest hold accepted, s.
pub const MAX_HOLD_S: f64 = 60.0;
/// Number of straight segments of the program.
pub const SEGMENTS: usize = 7;

/// A validated slow-intrusion program. Positions in metres, speed m/s, times s.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SlowIntrusion {
    start_m: f64,
    depth_m: f64,
    withdraw_m: f64,
    reintrusion_depth_m: f64,
    speed_m_s: f64,
    hold_s: f64,
}

/// One straight piece of the program: from `(t0_s, p0_m)` at `velocity_m_s` for `duration_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start time, s.
    pub t0_s: f64,
    /// Position at the start, m.
    pub p0_m: f64,
    /// Constant velocity, m/s (0 for holds).
    pub velocity_m_s: f64,
    /// Length, s.
    pub duration_s: f64,
}

impl SlowIntrusion {
    /// * `start_m`: `p` where the program starts and ends (rod at the free surface).
    /// * `depth_m` (> 0): first intrusion depth below the start.
    /// * `withdraw_m` (`0..=depth_m`): how far the rod is pulled back up after the first hold.
    /// * `reintrusion_depth_m` (`> depth_m - withdraw_m`): depth the re-intrusion goes to.
    /// * `speed_m_s`: `0 < v <= 0.05` m/s, for every moving segment.
    /// * `hold_s`: `0..=60` s, each of the three holds.
    ///
    /// Every position must stay within the stroke `+-0.025` m.
    pub fn new(
        start_m: f64,
        depth_m: f64,
        withdraw_m: f64,
        reintrusion_depth_m: f64,
        speed_m_s: f64,
        hold_s: f64,
    ) -> Result<Self, TrajectoryError> {
        let pos = |what, value_m| TrajectoryError::Position {
            what,
            value_m,
            stroke_m: STROKE_M,
        };
        if !(-STROKE_M..=STROKE_M).contains(&start_m) {
            return Err(pos("start_m", start_m));
        }
        if !(depth_m > 0.0 && start_m + depth_m <= STROKE_M) {
            return Err(pos("depth_m", depth_m));
        }
        if !(0.0..=depth_m).contains(&withdraw_m) {
            return Err(pos("withdraw_m", withdraw_m));
        }
        if !(reintrusion_depth_m > depth_m - withdraw_m
            && start_m + reintrusion_depth_m <= STROKE_M)
        {
            return Err(pos("reintrusion_depth_m", reintrusion_depth_m));
        }
        if !(speed_m_s > 0.0 && speed_m_s <= MAX_INTRUSION_SPEED_M_S) {
            return Err(TrajectoryError::Speed {
                speed_m_s,
                max_m_s: MAX_INTRUSION_SPEED_M_S,
            });
        }
        if !(0.0..=MAX_HOLD_S).contains(&hold_s) {
            return Err(TrajectoryError::Duration {
                what: "hold_s",
                value_s: hold_s,
                max_s: MAX_HOLD_S,
            });
        }
        Ok(Self {
            start_m,
            depth_m,
            withdraw_m,
            reintrusion_depth_m,
            speed_m_s,
            hold_s,
        })
    }

    /// `p` at the start and end, m.
    pub fn start_m(&self) -> f64 {
        self.start_m
    }

    /// The speed of every moving segment, m/s.
    pub fn speed_m_s(&self) -> f64 {
        self.speed_m_s
    }

    /// The seven segments: intrude, hold, withdraw, hold, re-intrude, hold, withdraw to start.
    pub fn segments(&self) -> [Segment; SEGMENTS] {
        let v = self.speed_m_s;
        let mut out = [Segment {
            t0_s: 0.0,
            p0_m: 0.0,
            velocity_m_s: 0.0,
            duration_s: 0.0,
        }; SEGMENTS];
        let (mut t, mut d) = (0.0, 0.0);
        for (seg, (target, moving)) in out.iter_mut().zip(self.targets()) {
            let (velocity_m_s, duration_s) = if moving {
                let travel: f64 = target - d;
                (v * travel.signum(), travel.abs() / v)
            } else {
                (0.0, self.hold_s)
            };
            *seg = Segment {
                t0_s: t,
                p0_m: self.start_m + d,
                velocity_m_s,
                duration_s,
            };
            t += duration_s;
            d = target;
        }
        out
    }

    /// Each segment's target depth below the start, m, and whether it moves there (a hold
    /// does not): intrude, hold, withdraw, hold, re-intrude, hold, withdraw to start.
    fn targets(&self) -> [(f64, bool); SEGMENTS] {
        let withdrawn = self.depth_m - self.withdraw_m;
        [
            (self.depth_m, true),
            (self.depth_m, false),
            (withdrawn, true),
            (withdrawn, false),
            (self.reintrusion_depth_m, true),
            (self.reintrusion_depth_m, false),
            (0.0, true),
        ]
    }

    /// The segments as the control tick needs them at `ticks_per_s`: where each starts, in
    /// ticks, its start position, m (f32, as the tick evaluates it), and its direction (-1, 0,
    /// +1), with the end, in ticks.
    /// The same corners as [`SlowIntrusion::segments`], in as few f64 operations as the
    /// firmware can afford inside the tick that receives `Configure` (every one a software
    /// routine on the Cortex-M4F: one division for the whole program).
    pub(crate) fn corners_in_ticks(&self, ticks_per_s: f64) -> ([(f64, f32, f64); SEGMENTS], f64) {
        let ticks_per_m = ticks_per_s / self.speed_m_s;
        let hold = self.hold_s * ticks_per_s;
        let mut out = [(0.0, 0.0, 0.0); SEGMENTS];
        let start = self.start_m as f32;
        let (mut at, mut d) = (0.0, 0.0);
        for (corner, (target, moving)) in out.iter_mut().zip(self.targets()) {
            let (direction, length) = if moving {
                let travel: f64 = target - d;
                (travel.signum(), travel.abs() * ticks_per_m)
            } else {
                (0.0, hold)
            };
            *corner = (at, start + d as f32, direction);
            at += length;
            d = target;
        }
        (out, at)
    }

    /// Total length, s.
    pub fn end_s(&self) -> f64 {
        let last = self.segments()[SEGMENTS - 1];
        last.t0_s + last.duration_s
    }

    /// Exact f64 curve. Holds `start_m` before 0 and after the end; acceleration is 0 (the
    /// velocity steps at the corners). Right-continuous at the corners.
    pub fn eval(&self, t_s: f64) -> Kinematics {
        let hold = |p| Kinematics {
            position_m: p,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        };
        if t_s.is_nan() || t_s < 0.0 || t_s >= self.end_s() {
            return hold(self.start_m);
        }
        let segs = self.segments();
        let seg = segs
            .iter()
            .rev()
            .find(|s| t_s >= s.t0_s)
            .unwrap_or(&segs[0]);
        Kinematics {
            position_m: seg.p0_m + seg.velocity_m_s * (t_s - seg.t0_s),
            velocity_m_s: seg.velocity_m_s,
            accel_m_s2: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn program_goes_down_holds_withdraws_and_reintrudes() {
        let s = SlowIntrusion::new(-0.02, 0.02, 0.005, 0.03, 0.01, 1.0).unwrap();
        // 2 s down, 1 s hold, 0.5 s up, 1 s hold, 1.5 s down, 1 s hold, 3 s up.
        assert!((s.end_s() - 10.0).abs() < 1e-12);
        assert!((s.eval(1.0).position_m - -0.01).abs() < 1e-15);
        assert_eq!(s.eval(1.0).velocity_m_s, 0.01);
        assert!((s.eval(2.5).position_m - 0.0).abs() < 1e-15);
        assert_eq!(s.eval(2.5).velocity_m_s, 0.0);
        assert!((s.eval(3.25).position_m - -0.0025).abs() < 1e-15);
        assert_eq!(s.eval(3.25).velocity_m_s, -0.01);
        assert!((s.eval(6.0).position_m - 0.01).abs() < 1e-15);
        assert!((s.eval(9.999_999).position_m - -0.02).abs() < 1e-8);
        assert_eq!(s.eval(11.0).position_m, -0.02);
        // Continuous at every corner.
        for seg in s.segments() {
            let a = s.eval(seg.t0_s - 1e-9).position_m;
            let b = s.eval(seg.t0_s + 1e-9).position_m;
            assert!((a - b).abs() < 1e-10, "corner at {}", seg.t0_s);
        }
    }

    #[test]
    fn rejects_out_of_stroke_and_bad_speeds() {
        assert!(matches!(
            SlowIntrusion::new(0.0, 0.03, 0.0, 0.01, 0.01, 1.0),
            Err(TrajectoryError::Position {
                what: "depth_m",
                ..
            })
        ));
        assert!(matches!(
            SlowIntrusion::new(0.0, 0.01, 0.02, 0.01, 0.01, 1.0),
            Err(TrajectoryError::Position {
                what: "withdraw_m",
                ..
            })
        ));
        assert!(matches!(
            SlowIntrusion::new(0.0, 0.01, 0.005, 0.004, 0.01, 1.0),
            Err(TrajectoryError::Position {
                what: "reintrusion_depth_m",
                ..
            })
        ));
        assert!(matches!(
            SlowIntrusion::new(0.0, 0.01, 0.0, 0.02, 0.1, 1.0),
            Err(TrajectoryError::Speed { .. })
        ));
        assert!(matches!(
            SlowIntrusion::new(0.0, 0.01, 0.0, 0.02, 0.01, -1.0),
            Err(TrajectoryError::Duration { .. })
        ));
    }
}
