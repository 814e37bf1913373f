//! Per-tick setpoints in f32 for the control loop: the trajectory sampled at control ticks.
//!
//! Everything the tick needs is precomputed at construction (in f64, once): integer tick
//! indices of every breakpoint, the phase step of the sine in `u64` fixed point (`2^64` = one
//! turn, so after any number of ticks the phase is exact to ~`2^-53` of the cycles elapsed),
//! and f32 coefficients. The tick itself does integer arithmetic, one
//! [`sin_cos_turns`] and a few f32 multiplies: no f64, no division.
//!
//! Tick `n` (counted from the start of the trajectory) is time `t = n / tick_hz`. A breakpoint
//! at time `b` belongs to the first tick with `n / tick_hz >= b`. Accuracy against the exact f64
//! curve (property-tested): position within 0.1 micrometre over the whole trajectory.

use crate::intrusion::{SEGMENTS, SlowIntrusion};
use crate::replay::{ReplayError, ReplayTable};
use crate::trajectory::{JumpKind, SineJump, TrajectoryError};
use crate::turns::{sin_cos_turns, turns_to_fixed64};

/// Lowest control tick rate accepted, Hz.
pub const MIN_TICK_HZ: u32 = 1_000;
/// Highest control tick rate accepted, Hz.
pub const MAX_TICK_HZ: u32 = 100_000;

/// Commanded position (m), velocity (m/s) and acceleration (m/s^2) for one tick.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Setpoint {
    /// m.
    pub position_m: f32,
    /// m/s.
    pub velocity_m_s: f32,
    /// m/s^2.
    pub accel_m_s2: f32,
}

/// Which part of the trajectory a tick is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Not running a trajectory (idle, armed, faulted).
    None,
    /// A stutter's first half: the pull-up and preliminary hop.
    Preliminary,
    /// The delayed stutter's hold at the bottom (gain-lowering damping happens here).
    Delay,
    /// The push-off half (all of the single jump).
    PushOff,
    /// Slow intrusion: rod moving down.
    Intrude,
    /// Slow intrusion: holding.
    Hold,
    /// Slow intrusion: rod moving up.
    Withdraw,
    /// Replaying a table.
    Replay,
    /// After the end: holding the final position.
    Finished,
}

/// First tick at or after time `t_s` (the tolerance absorbs f64 rounding of exact products).
fn first_tick_at(t_s: f64, tick_hz: u32) -> Result<u32, TrajectoryError> {
    first_tick_of(t_s * tick_hz as f64, Some(t_s), tick_hz)
}

/// [`first_tick_at`] with the time already in ticks; `t_s` in seconds when the caller has it
/// (otherwise worked out for the error only: a division the control tick can do without).
fn first_tick_of(ticks: f64, t_s: Option<f64>, tick_hz: u32) -> Result<u32, TrajectoryError> {
    let x = libm::ceil(ticks - 1e-6);
    let max = (u32::MAX / 2) as f64;
    if x.is_nan() || x > max {
        return Err(TrajectoryError::TooLong {
            end_s: t_s.unwrap_or(ticks / tick_hz as f64),
            max_s: max / tick_hz as f64,
        });
    }
    Ok(if x > 0.0 { x as u32 } else { 0 })
}

fn check_tick_hz(tick_hz: u32) -> Result<(), TrajectoryError> {
    if (MIN_TICK_HZ..=MAX_TICK_HZ).contains(&tick_hz) {
        Ok(())
    } else {
        Err(TrajectoryError::TickRate {
            tick_hz,
            min_hz: MIN_TICK_HZ,
            max_hz: MAX_TICK_HZ,
        })
    }
}

/// A one-cycle sine jump at control ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SineTicks {
    /// Signed amplitude `a` (`p = a cos`), m.
    a: f32,
    /// `a * w`, m/s.
    aw: f32,
    /// `a * w^2`, m/s^2.
    aww: f32,
    /// Phase advance per tick, `2^64` = one turn.
    step: u64,
    /// Phase offset of the second half of a delayed stutter (`-tau f` turns).
    delay_offset: u64,
    delayed: bool,
    single: bool,
    n_half: u32,
    n_delay_end: u32,
    n_end: u32,
}

impl SineTicks {
    /// Sample `jump` at `tick_hz`.
    pub fn new(jump: &SineJump, tick_hz: u32) -> Result<Self, TrajectoryError> {
        check_tick_hz(tick_hz)?;
        let sign = if jump.kind() == JumpKind::Single {
            -1.0
        } else {
            1.0
        };
        let a = sign * jump.amplitude_m();
        let w = core::f64::consts::TAU * jump.freq_hz();
        let half = 0.5 * jump.period_s();
        Ok(Self {
            a: a as f32,
            aw: (a * w) as f32,
            aww: (a * w * w) as f32,
            step: turns_to_fixed64(jump.freq_hz() / tick_hz as f64),
            delay_offset: turns_to_fixed64(-jump.tau_s() * jump.freq_hz()),
            delayed: jump.kind() == JumpKind::DelayedStutter,
            single: jump.kind() == JumpKind::Single,
            n_half: first_tick_at(half, tick_hz)?,
            n_delay_end: first_tick_at(half + jump.tau_s(), tick_hz)?,
            n_end: first_tick_at(jump.end_s(), tick_hz)?,
        })
    }

    /// The delay `[start, end)` in ticks, for a delayed stutter with a non-empty delay.
    pub fn delay_ticks(&self) -> Option<(u32, u32)> {
        (self.delayed && self.n_delay_end > self.n_half).then_some((self.n_half, self.n_delay_end))
    }

    /// Setpoint at tick `n` of the trajectory.
    #[inline]
    pub fn eval(&self, n: u32) -> (Setpoint, Phase) {
        if n >= self.n_end {
            return (hold(self.a), Phase::Finished);
        }
        let mut phase64 = (n as u64).wrapping_mul(self.step);
        let label = if n < self.n_half {
            if self.single {
                Phase::PushOff
            } else {
                Phase::Preliminary
            }
        } else if self.delayed {
            if n < self.n_delay_end {
                return (hold(-self.a), Phase::Delay);
            }
            phase64 = phase64.wrapping_add(self.delay_offset);
            Phase::PushOff
        } else {
            Phase::PushOff
        };
        let (s, c) = sin_cos_turns((phase64 >> 32) as u32);
        (
            Setpoint {
                position_m: self.a * c,
                velocity_m_s: -self.aw * s,
                accel_m_s2: -self.aww * c,
            },
            label,
        )
    }
}

fn hold(p: f32) -> Setpoint {
    Setpoint {
        position_m: p,
        velocity_m_s: 0.0,
        accel_m_s2: 0.0,
    }
}

/// One straight segment of the slow-intrusion program at ticks.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct LineTicks {
    /// First tick of the segment.
    n0: u32,
    /// Exact position at tick `n0`, m.
    p0: f32,
    /// Metres per tick.
    dp: f32,
    /// m/s.
    v: f32,
}

/// The slow-intrusion program at control ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IntrusionTicks {
    lines: [LineTicks; SEGMENTS],
    start: f32,
    n_end: u32,
}

impl IntrusionTicks {
    /// Sample `program` at `tick_hz`.
    pub fn new(program: &SlowIntrusion, tick_hz: u32) -> Result<Self, TrajectoryError> {
        check_tick_hz(tick_hz)?;
        // The firmware builds this inside the control tick that receives `Configure`, where
        // every f64 operation is a software routine (the Cortex-M4F's FPU is single
        // precision): the corners come in ticks from one pass over the program, each segment's
        // first tick in f64 (exact to the tick whatever the program's length), and what is
        // measured from there in f32, as the tick evaluates it.
        let hz = f64::from(tick_hz);
        let (corners, end) = program.corners_in_ticks(hz);
        // The end is checked; every corner comes before it.
        let n_end = first_tick_of(end, None, tick_hz)?;
        let (speed, dt) = (program.speed_m_s() as f32, 1.0 / tick_hz as f32);
        let mut lines = [LineTicks::default(); SEGMENTS];
        for (line, &(at, p0_m, direction)) in lines.iter_mut().zip(&corners) {
            // ceil(at - 1e-6) as `first_tick_at` takes it, from the whole ticks below (the
            // conversion saturates: a corner at or before 0 starts at tick 0).
            let x = at - 1e-6;
            let below = x as u32;
            let n0 = if f64::from(below) < x {
                below + 1
            } else {
                below
            };
            let v = direction as f32 * speed;
            *line = if v == 0.0 {
                LineTicks {
                    n0,
                    p0: p0_m,
                    dp: 0.0,
                    v,
                }
            } else {
                // From the corner to tick n0: under one tick.
                let late = (f64::from(n0) - at) as f32 * dt;
                LineTicks {
                    n0,
                    p0: p0_m + v * late,
                    dp: v * dt,
                    v,
                }
            };
        }
        Ok(Self {
            lines,
            start: program.start_m() as f32,
            n_end,
        })
    }

    /// Setpoint at tick `n` of the program.
    #[inline]
    pub fn eval(&self, n: u32) -> (Setpoint, Phase) {
        if n >= self.n_end {
            return (hold(self.start), Phase::Finished);
        }
        // Last segment that has started (segments are few; zero-length ones are skipped over).
        let mut line = self.lines[0];
        for l in &self.lines[1..] {
            if n >= l.n0 {
                line = *l;
            }
        }
        let label = if line.v > 0.0 {
            Phase::Intrude
        } else if line.v < 0.0 {
            Phase::Withdraw
        } else {
            Phase::Hold
        };
        let sp = Setpoint {
            position_m: line.p0 + (n - line.n0) as f32 * line.dp,
            velocity_m_s: line.v,
            accel_m_s2: 0.0,
        };
        (sp, label)
    }
}

/// Replay of the committed [`ReplayTable`] at control ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReplayTicks {
    /// Samples per second (converts d/du to d/dt).
    samples_per_s: f32,
    n_end: u32,
    /// Checksum of the table this was built for: a new upload invalidates it.
    checksum: u32,
}

impl ReplayTicks {
    /// Replay `table` (must be committed) at `tick_hz`.
    pub fn new(table: &ReplayTable, tick_hz: u32) -> Result<Self, TrajectoryError> {
        check_tick_hz(tick_hz)?;
        let not_committed = TrajectoryError::Replay(ReplayError::NotCommitted);
        let checksum = table.committed_checksum().ok_or(not_committed)?;
        let n_end = table.end_tick().ok_or(not_committed)?;
        Ok(Self {
            samples_per_s: tick_hz as f32 / table.period_ticks() as f32,
            n_end,
            checksum,
        })
    }

    /// The checksum of the table this replay was built for.
    pub fn checksum(&self) -> u32 {
        self.checksum
    }

    /// Setpoint at tick `n` (the table must be the one this was built for).
    #[inline]
    pub fn eval(&self, n: u32, table: &ReplayTable) -> (Setpoint, Phase) {
        let (p, dp, ddp) = table.eval_samples(n);
        let sp = Setpoint {
            position_m: p,
            velocity_m_s: dp * self.samples_per_s,
            accel_m_s2: ddp * self.samples_per_s * self.samples_per_s,
        };
        (
            sp,
            if n >= self.n_end {
                Phase::Finished
            } else {
                Phase::Replay
            },
        )
    }
}

/// Any trajectory at control ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TickProfile {
    /// Single, stutter or delayed stutter.
    Sine(SineTicks),
    /// Slow intrusion program.
    SlowIntrusion(IntrusionTicks),
    /// Replay of the uploaded table.
    Replay(ReplayTicks),
}

impl TickProfile {
    /// Setpoint and phase at tick `n` since the start. `table` is only read for replays.
    #[inline]
    pub fn eval(&self, n: u32, table: &ReplayTable) -> (Setpoint, Phase) {
        match self {
            Self::Sine(s) => s.eval(n),
            Self::SlowIntrusion(s) => s.eval(n),
            Self::Replay(r) => r.eval(n, table),
        }
    }

    /// First tick at which the trajectory is over (holding its final value).
    pub fn end_tick(&self) -> u32 {
        match self {
            Self::Sine(s) => s.n_end,
            Self::SlowIntrusion(s) => s.n_end,
            Self::Replay(r) => r.n_end,
        }
    }

    /// Setpoint held while armed, before the start.
    pub fn start_setpoint(&self, table: &ReplayTable) -> Setpoint {
        hold(self.eval(0, table).0.position_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trajectory::Kinematics;
    use proptest::prelude::*;

    fn kind_strategy() -> impl Strategy<Value = JumpKind> {
        prop_oneof![
            Just(JumpKind::Single),
            Just(JumpKind::Stutter),
            Just(JumpKind::DelayedStutter)
        ]
    }

    fn check_against_exact(jump: &SineJump, tick_hz: u32) -> Result<(), TestCaseError> {
        let ticks = SineTicks::new(jump, tick_hz).unwrap();
        let w = core::f64::consts::TAU * jump.freq_hz();
        let (vmax, amax) = (jump.amplitude_m() * w, jump.amplitude_m() * w * w);
        let breaks: heapless::Vec<f64, 4> = jump
            .breakpoints_s()
            .iter()
            .map(|b| b * tick_hz as f64)
            .collect();
        for n in 0..ticks.n_end + 20 {
            let (sp, _) = ticks.eval(n);
            let exact: Kinematics = jump.eval(n as f64 / tick_hz as f64);
            let dp = (sp.position_m as f64 - exact.position_m).abs();
            prop_assert!(dp <= 1e-7, "n={} position off by {} m", n, dp);
            let dv = (sp.velocity_m_s as f64 - exact.velocity_m_s).abs();
            prop_assert!(dv <= 1e-6 * vmax + 1e-9, "n={} velocity off by {}", n, dv);
            // Acceleration is discontinuous at breakpoints: skip ticks sitting on one.
            if breaks.iter().all(|b| (b - n as f64).abs() > 1e-6) {
                let da = (sp.accel_m_s2 as f64 - exact.accel_m_s2).abs();
                prop_assert!(da <= 1e-6 * amax + 1e-9, "n={} accel off by {}", n, da);
            }
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The f32 tick evaluation stays within 0.1 um of the exact f64 curve everywhere.
        #[test]
        fn sine_ticks_match_exact_curve(
            kind in kind_strategy(),
            amplitude_m in 1e-4f64..=0.025,
            freq_hz in 0.5f64..=40.0,
            tau_s in 0.0f64..=5.0,
            tick_hz in prop_oneof![Just(1_000u32), Just(5_000), Just(10_000), Just(20_000), 1_000u32..=100_000],
        ) {
            let jump = SineJump::new(kind, amplitude_m, freq_hz, tau_s).unwrap();
            check_against_exact(&jump, tick_hz)?;
        }

        /// Slow intrusion at ticks matches its exact f64 curve.
        #[test]
        fn intrusion_ticks_match_exact_curve(
            start_m in -0.02f64..0.0,
            depth_frac in 0.1f64..1.0,
            withdraw_frac in 0.0f64..1.0,
            speed_m_s in 0.001f64..=0.05,
            hold_s in 0.0f64..0.3,
        ) {
            let room = 0.025 - start_m;
            let depth = room * depth_frac * 0.9;
            let withdraw = depth * withdraw_frac;
            let prog = SlowIntrusion::new(start_m, depth, withdraw, room * 0.95, speed_m_s, hold_s).unwrap();
            let ticks = IntrusionTicks::new(&prog, 10_000).unwrap();
            // The corners in ticks (the firmware's cheap pass) start where the segments do.
            for (line, seg) in ticks.lines.iter().zip(prog.segments()) {
                prop_assert_eq!(line.n0, first_tick_at(seg.t0_s, 10_000).unwrap());
            }
            prop_assert_eq!(ticks.n_end, first_tick_at(prog.end_s(), 10_000).unwrap());
            for n in (0..ticks.n_end + 20).step_by(7) {
                let (sp, _) = ticks.eval(n);
                let exact = prog.eval(n as f64 / 10_000.0);
                prop_assert!((sp.position_m as f64 - exact.position_m).abs() <= 1e-7, "n={}", n);
            }
        }
    }

    /// A program too long to count in ticks is refused with its length in seconds (worked out
    /// from the ticks only for the error).
    #[test]
    fn an_intrusion_too_long_for_the_tick_counter_is_refused_with_its_length() {
        let prog = SlowIntrusion::new(-0.02, 0.02, 0.0, 0.03, 1e-9, 0.0).unwrap();
        match IntrusionTicks::new(&prog, 10_000) {
            Err(TrajectoryError::TooLong { end_s, .. }) => {
                assert!((end_s / prog.end_s() - 1.0).abs() < 1e-12, "{end_s}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn delayed_stutter_phases_and_exact_breakpoint_ticks() {
        let jump = SineJump::new(JumpKind::DelayedStutter, 0.01875, 10.0, 0.75).unwrap();
        let t = SineTicks::new(&jump, 10_000).unwrap();
        assert_eq!((t.n_half, t.n_delay_end, t.n_end), (500, 8000, 8500));
        assert_eq!(t.eval(0).1, Phase::Preliminary);
        assert_eq!(t.eval(499).1, Phase::Preliminary);
        assert_eq!(t.eval(500), (hold(-0.01875), Phase::Delay));
        assert_eq!(t.eval(7999).1, Phase::Delay);
        assert_eq!(t.eval(8000).1, Phase::PushOff);
        assert_eq!(t.eval(8500), (hold(0.01875), Phase::Finished));
        // Position continuous at the end of the delay (one tick of motion at most).
        let step = t.eval(8001).0.position_m - t.eval(8000).0.position_m;
        assert!(step.abs() < 1e-6);
    }

    #[test]
    fn rejects_bad_tick_rate() {
        let jump = SineJump::new(JumpKind::Single, 0.01, 10.0, 0.0).unwrap();
        assert!(matches!(
            SineTicks::new(&jump, 999),
            Err(TrajectoryError::TickRate { .. })
        ));
    }
}
