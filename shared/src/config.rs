//! Configuration: the rig's fixed hardware facts ([`RigConfig`], given once at start-up) and
//! one jump's configuration ([`JumpConfig`], sent by the host with `Configure`).

use crate::controller::{GainLowering, Gains};
use crate::encoder::CounterWidth;
use crate::intrusion::SlowIntrusion;
use crate::profile::{MAX_TICK_HZ, MIN_TICK_HZ};
use crate::trajectory::{JumpKind, SineJump, TrajectoryError};

pub use crate::config_error::ConfigError;
pub(crate) use crate::config_error::field;

/// Facts about the rig, fixed at start-up (the firmware's board module or the simulator).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RigConfig {
    /// Control tick rate, Hz (1 kHz..=100 kHz; default 10 kHz).
    pub tick_hz: u32,
    /// Width of the hardware encoder counter.
    pub counter_width: CounterWidth,
    /// Encoder resolution, metres per count (default 1 um). Count 0 is `p = 0`.
    pub metres_per_count: f32,
    /// Largest physically possible |count change| in one tick; beyond it is an encoder fault
    /// (default 1000 counts = 10 m/s at 1 um and 10 kHz).
    pub max_counts_per_tick: u32,
    /// Force command saturation (the drive's peak force), N (default 300).
    pub drive_limit_n: f32,
    /// Stroke limit on the measured `|p|`, m (default 0.0255: the 25 mm stroke plus 0.5 mm).
    pub stroke_limit_m: f32,
    /// Host-link watchdog while the drive is enabled, ms (default 500; 0 disables).
    pub watchdog_ms: u32,
    /// Host-link watchdog of the bed apparatus's actuators (lift, shaker, blower), ms: while any
    /// of them is on, a host silent this long latches `BedWatchdog` (everything off), in every
    /// state of the rig (default 500; 1..=60,000: it cannot be disabled).
    pub bed_watchdog_ms: u32,
    /// The board reads an emergency-stop loop of its own every tick
    /// ([`crate::Rig::set_emergency_stop_loop`]): `Arm` is refused until it has read closed
    /// since reset (see [`crate::emergency_stop`]). Default false (the simulated rigs, QEMU).
    pub emergency_stop_input: bool,
    /// Tick deadline in cycles of the glue's cycle counter (0: only the glue's overrun flag).
    pub deadline_cycles: u32,
    /// Cut-off of the velocity estimate's first-order low-pass, Hz (default 2000). The
    /// derivative gain closes the position loop at a few hundred hertz on the motor/rod reduced
    /// mass, where a 500 Hz filter alone takes 30-40 degrees of phase; at 2 kHz it takes ~10
    /// (see `sandjumper-rig`'s `hil::loop_margins`). A 1 um count per 0.1 ms tick is 0.01 m/s of
    /// quantization, 72 % of it through this filter.
    pub velocity_cutoff_hz: f32,
    /// Consecutive rejected frames that latch `LinkCorrupted` (default 10; 0 disables).
    pub corrupted_frame_limit: u32,
    /// In lockstep, control periods in a row without a sensor frame that latch `LinkLost`
    /// (default 2, at least 1).
    pub lockstep_timeout_ticks: u32,
    /// One control period in cycles of the glue's cycle counter, for tick-gap detection
    /// (`Rig::note_tick_start`; 0 disables it, the default).
    pub tick_period_cycles: u32,
}

impl Default for RigConfig {
    fn default() -> Self {
        Self {
            tick_hz: 10_000,
            counter_width: CounterWidth::Bits32,
            metres_per_count: 1e-6,
            max_counts_per_tick: 1000,
            drive_limit_n: 300.0,
            stroke_limit_m: 0.0255,
            watchdog_ms: 500,
            bed_watchdog_ms: 500,
            emergency_stop_input: false,
            deadline_cycles: 0,
            velocity_cutoff_hz: 2000.0,
            corrupted_frame_limit: 10,
            lockstep_timeout_ticks: 2,
            tick_period_cycles: 0,
        }
    }
}

impl RigConfig {
    /// Check every field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        field(
            "tick_hz",
            self.tick_hz as f32,
            (MIN_TICK_HZ..=MAX_TICK_HZ).contains(&self.tick_hz),
            "1000..=100000 Hz",
        )?;
        field(
            "metres_per_count",
            self.metres_per_count,
            self.metres_per_count > 0.0 && self.metres_per_count <= 1e-3,
            "0 < m/count <= 1e-3",
        )?;
        field(
            "max_counts_per_tick",
            self.max_counts_per_tick as f32,
            self.max_counts_per_tick >= 1,
            ">= 1 count",
        )?;
        field(
            "drive_limit_n",
            self.drive_limit_n,
            self.drive_limit_n > 0.0 && self.drive_limit_n <= 1e4,
            "0 < F <= 1e4 N",
        )?;
        field(
            "stroke_limit_m",
            self.stroke_limit_m,
            self.stroke_limit_m > 0.0 && self.stroke_limit_m <= 0.1,
            "0 < limit <= 0.1 m",
        )?;
        field(
            "velocity_cutoff_hz",
            self.velocity_cutoff_hz,
            self.velocity_cutoff_hz > 0.0 && self.velocity_cutoff_hz < self.tick_hz as f32 / 2.0,
            "0 < f_c < tick_hz / 2",
        )?;
        field(
            "bed_watchdog_ms",
            self.bed_watchdog_ms as f32,
            (1..=60_000).contains(&self.bed_watchdog_ms),
            "1..=60000 ms",
        )?;
        field(
            "lockstep_timeout_ticks",
            self.lockstep_timeout_ticks as f32,
            (1..=self.tick_hz).contains(&self.lockstep_timeout_ticks),
            "1..=tick_hz ticks (at most 1 s)",
        )
    }

    /// The bed apparatus's host watchdog in ticks (at least 1).
    pub fn bed_watchdog_ticks(&self) -> u32 {
        ((self.bed_watchdog_ms as u64 * self.tick_hz as u64) / 1000).clamp(1, u32::MAX as u64)
            as u32
    }

    /// Watchdog length in ticks (0 = disabled).
    pub fn watchdog_ticks(&self) -> u32 {
        ((self.watchdog_ms as u64 * self.tick_hz as u64) / 1000).min(u32::MAX as u64) as u32
    }
}

/// Which trajectory to run, as plain parameters (validated when the jump is configured).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrajectorySpec {
    /// One-cycle sine (docs/model.md section 2); see [`SineJump::new`].
    Sine {
        kind: JumpKind,
        amplitude_m: f64,
        freq_hz: f64,
        tau_s: f64,
    },
    /// Slow intrusion program; see [`SlowIntrusion::new`].
    SlowIntrusion {
        start_m: f64,
        depth_m: f64,
        withdraw_m: f64,
        reintrusion_depth_m: f64,
        speed_m_s: f64,
        hold_s: f64,
    },
    /// Replay of the committed replay table; `checksum` must be the table's CRC-32.
    Replay { checksum: u32 },
}

/// A validated trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Trajectory {
    /// Single, stutter, delayed stutter.
    Sine(SineJump),
    /// Slow intrusion.
    SlowIntrusion(SlowIntrusion),
    /// Replay of the table with this checksum.
    Replay { checksum: u32 },
}

impl TrajectorySpec {
    /// Validate the parameters.
    pub fn build(&self) -> Result<Trajectory, TrajectoryError> {
        Ok(match *self {
            Self::Sine {
                kind,
                amplitude_m,
                freq_hz,
                tau_s,
            } => Trajectory::Sine(SineJump::new(kind, amplitude_m, freq_hz, tau_s)?),
            Self::SlowIntrusion {
                start_m,
                depth_m,
                withdraw_m,
                reintrusion_depth_m,
                speed_m_s,
                hold_s,
            } => Trajectory::SlowIntrusion(SlowIntrusion::new(
                start_m,
                depth_m,
                withdraw_m,
                reintrusion_depth_m,
                speed_m_s,
                hold_s,
            )?),
            Self::Replay { checksum } => Trajectory::Replay { checksum },
        })
    }
}

/// One jump's configuration (sent with `Configure`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JumpConfig {
    /// The trajectory.
    pub trajectory: TrajectorySpec,
    /// Controller gains.
    pub gains: Gains,
    /// Gain-lowering damping during a delayed stutter's delay (`None`: full gains throughout).
    pub gain_lowering: Option<GainLowering>,
    /// Tracking error `|p_cmd - p|` that latches `TrackingError`, m (default 5 mm).
    pub tracking_error_limit_m: f32,
    /// Camera frame rate, frames/s (0: no camera; at most `tick_hz / 2`). 200 rod tracking,
    /// 500 PIV.
    pub camera_fps: u32,
    /// Trigger pulse length, ticks (at least 1; shortened to fit the frame).
    pub camera_pulse_ticks: u32,
}

impl JumpConfig {
    /// A jump with the default gains, no gain lowering, a 5 mm tracking bound and a 200 fps
    /// camera with 1 ms pulses at 10 kHz.
    pub fn new(trajectory: TrajectorySpec) -> Self {
        Self {
            trajectory,
            gains: Gains::default(),
            gain_lowering: None,
            tracking_error_limit_m: 0.005,
            camera_fps: 200,
            camera_pulse_ticks: 10,
        }
    }

    /// Check everything that does not need the rig (the trajectory itself is validated when
    /// built).
    pub fn validate(&self, tick_hz: u32) -> Result<(), ConfigError> {
        self.gains.validate()?;
        if let Some(g) = &self.gain_lowering {
            g.validate()?;
        }
        field(
            "tracking_error_limit_m",
            self.tracking_error_limit_m,
            self.tracking_error_limit_m > 0.0 && self.tracking_error_limit_m <= 0.1,
            "0 < bound <= 0.1 m",
        )?;
        field(
            "camera_fps",
            self.camera_fps as f32,
            self.camera_fps <= tick_hz / 2,
            "0..=tick_hz/2",
        )?;
        field(
            "camera_pulse_ticks",
            self.camera_pulse_ticks as f32,
            self.camera_pulse_ticks >= 1,
            ">= 1 tick",
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        RigConfig::default().validate().unwrap();
        let j = JumpConfig::new(TrajectorySpec::Replay { checksum: 0 });
        j.validate(10_000).unwrap();
        let bad = RigConfig {
            velocity_cutoff_hz: 6000.0,
            ..RigConfig::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(ConfigError::Field {
                what: "velocity_cutoff_hz",
                ..
            })
        ));
        let bad = JumpConfig {
            camera_fps: 6000,
            ..j
        };
        assert!(matches!(
            bad.validate(10_000),
            Err(ConfigError::Field {
                what: "camera_fps",
                ..
            })
        ));
        assert_eq!(RigConfig::default().watchdog_ticks(), 5000);
    }
}
