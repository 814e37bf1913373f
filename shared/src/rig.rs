//! The sans-IO control loop: [`Rig::tick`] once per control tick, [`Rig::handle`] for host
//! commands, and a sample queue to drain for telemetry.
//!
//! State machine (only these transitions; any other command is rejected with no change):
//!
//! ```text
//!   Idle --Arm--> Armed --Start--> Running --(trajectory ends)--> Done
//!    ^              |                 |                            |
//!    +----Abort-----+------Abort------+-----------Abort------------+
//!   any --fault--> Faulted --ClearFault--> Idle
//!   Idle/Done --Configure--> Idle
//! ```
//!
//! The bed apparatus ([`crate::bed`]) rides along: its inputs arrive with
//! [`Rig::set_bed_inputs`], its commands as [`Command::Bed`] in any state; `Arm` needs its
//! interlock; the emergency stop latches [`FaultCode::EmergencyStop`], and any latched fault
//! turns the apparatus off. A board with an emergency-stop loop of its own reports it every
//! tick ([`Rig::set_emergency_stop_loop`], see [`crate::emergency_stop`]): `Arm` waits for it
//! to read closed. The host's silence is watched in every state: past the command watchdog
//! while the drive is enabled, past the bed watchdog while a bed actuator is on.
//!
//! Per tick, in order: deadline check, encoder extension (and velocity estimate), host-link
//! watchdog, setpoint, camera trigger, position controller, stroke and tracking checks, sample
//! record. Any fault found on a tick makes that same tick's force command exactly 0.

use crate::approach::Approach;
use crate::bed::{BedApparatus, BedInputs, BedOutputs, BedStatus};
use crate::camera::CameraTrigger;
use crate::command::{Command, CommandError, CommandKind, Reply};
use crate::config::{ConfigError, JumpConfig, RigConfig, Trajectory};
use crate::controller::{GainScale, GainSchedule, Gains, PositionController, VelocityEstimator};
use crate::drive_calibration::DriveCalibration;
use crate::emergency_stop::{EmergencyStopError, EmergencyStopLoop};
use crate::encoder::EncoderExtender;
use crate::fault::FaultCode;
use crate::lockstep::LockstepLink;
use crate::profile::{IntrusionTicks, Phase, ReplayTicks, Setpoint, SineTicks, TickProfile};
use crate::protocol::{ActuatorFrame, SensorFrame};
use crate::replay::{ReplayError, ReplayTable};
use crate::reset::ResetCause;
use crate::sample::{SampleQueue, SampleRecord, flags};
pub use crate::status::{Counters, RigState, Status};
use crate::trajectory::TrajectoryError;

/// Default sample-queue capacity, records (25 ms at 10 kHz).
pub const DEFAULT_SAMPLE_QUEUE: usize = 256;

/// How long the previous tick took, as the glue measured it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TickTiming {
    /// Not measured.
    Unknown,
    /// Cycles (or instructions) of the previous tick; compared with `deadline_cycles`.
    Cycles(u32),
    /// The glue detected an overrun itself.
    Overrun,
}

/// Inputs of one control tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TickInput {
    /// Raw hardware encoder counter (wraps; only the low 16 bits for a 16-bit counter).
    pub encoder_raw: u32,
    /// Measured motor current, A, if available.
    pub current_a: Option<f32>,
    /// Duration of the previous tick.
    pub timing: TickTiming,
}

/// Outputs of one control tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TickOutput {
    /// Force command for the drive, N (exactly 0 unless the drive is enabled).
    pub force_n: f32,
    /// Drive enable line.
    pub drive_enabled: bool,
    /// Camera trigger line level.
    pub camera_trigger: bool,
    /// Camera frame that started on this tick, if any.
    pub camera_frame: Option<u32>,
    /// State after this tick.
    pub state: RigState,
    /// Trajectory phase of this tick.
    pub phase: Phase,
    /// The latched fault, if any.
    pub fault: Option<FaultCode>,
    /// This tick's number since start-up.
    pub tick: u32,
    /// The bed apparatus's outputs.
    pub bed: BedOutputs,
}

#[derive(Clone, Copy, Debug)]
struct LoadedJump {
    config: JumpConfig,
    profile: TickProfile,
    schedule: Option<GainSchedule>,
}

/// What one tick aims at: the setpoint, the gain scale and the tracking-error limit.
struct TickTarget {
    setpoint: Setpoint,
    scale: GainScale,
    /// Largest allowed |setpoint - position|, m (infinite with no jump loaded).
    tracking_limit_m: f32,
}

/// The control loop. `Q` is the sample-queue capacity.
#[derive(Debug)]
pub struct Rig<const Q: usize = DEFAULT_SAMPLE_QUEUE> {
    config: RigConfig,
    watchdog_ticks: u32,
    bed_watchdog_ticks: u32,
    state: RigState,
    fault: Option<FaultCode>,
    fault_tick: u32,
    tick: u32,
    run_tick: u32,
    phase: Phase,
    hold: Setpoint,
    /// The move to the start after an Arm away from it (see [`crate::approach`]).
    approach: Option<Approach>,
    /// A Start that arrived during the approach, honoured at its end.
    start_pending: bool,
    /// The position the encoder read last, m.
    last_position_m: f32,
    ticks_since_host: u32,
    consecutive_rejected: u32,
    lockstep_link: LockstepLink,
    reset_cause: ResetCause,
    reset_acknowledged: bool,
    drive_calibration: DriveCalibration,
    /// Cycle count at the start of the previous tick (tick-gap detection).
    last_tick_start: Option<u32>,
    encoder: EncoderExtender,
    velocity: VelocityEstimator,
    controller: PositionController,
    camera: CameraTrigger,
    jump: Option<LoadedJump>,
    replay: ReplayTable,
    samples: SampleQueue<Q>,
    counters: Counters,
    bed: BedApparatus,
    emergency_stop: EmergencyStopLoop,
}

impl<const Q: usize> Rig<Q> {
    /// A rig in Idle with nothing configured.
    pub fn new(config: RigConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Self {
            config,
            watchdog_ticks: config.watchdog_ticks(),
            bed_watchdog_ticks: config.bed_watchdog_ticks(),
            state: RigState::Idle,
            fault: None,
            fault_tick: 0,
            tick: 0,
            run_tick: 0,
            phase: Phase::None,
            hold: Setpoint::default(),
            approach: None,
            start_pending: false,
            last_position_m: f32::NAN,
            ticks_since_host: 0,
            consecutive_rejected: 0,
            lockstep_link: LockstepLink::new(),
            reset_cause: ResetCause::PowerOn,
            reset_acknowledged: true,
            drive_calibration: DriveCalibration::NOMINAL,
            last_tick_start: None,
            encoder: EncoderExtender::new(config.counter_width, config.max_counts_per_tick),
            velocity: VelocityEstimator::new(
                config.metres_per_count,
                config.tick_hz,
                config.velocity_cutoff_hz,
            ),
            controller: PositionController::new(
                Gains::default(),
                config.drive_limit_n,
                config.tick_hz,
            ),
            camera: CameraTrigger::new(0, config.tick_hz, 1),
            jump: None,
            replay: ReplayTable::new(),
            samples: SampleQueue::new(),
            counters: Counters::default(),
            bed: BedApparatus::new(),
            emergency_stop: EmergencyStopLoop::new(config.emergency_stop_input),
        })
    }

    /// The rig's fixed configuration.
    pub fn config(&self) -> &RigConfig {
        &self.config
    }
    /// Current state.
    pub fn state(&self) -> RigState {
        self.state
    }
    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultCode> {
        self.fault
    }
    /// The loaded jump configuration, if any.
    pub fn jump_config(&self) -> Option<&JumpConfig> {
        self.jump.as_ref().map(|j| &j.config)
    }
    /// The replay table.
    pub fn replay_table(&self) -> &ReplayTable {
        &self.replay
    }
    /// The sample queue (drain it for telemetry).
    pub fn samples(&mut self) -> &mut SampleQueue<Q> {
        &mut self.samples
    }
    /// Wrap-free encoder count.
    pub fn encoder_count(&self) -> i64 {
        self.encoder.count()
    }

    /// Counters, with the sample queue's figures filled in.
    pub fn counters(&self) -> Counters {
        Counters {
            samples_produced: self.samples.produced(),
            samples_dropped: self.samples.dropped(),
            ..self.counters
        }
    }

    /// A snapshot for the host.
    pub fn status(&self) -> Status {
        Status {
            state: self.state,
            phase: self.phase,
            fault: self.fault,
            fault_tick: self.fault_tick,
            tick: self.tick,
            run_tick: self.run_tick,
            camera_frames: self.camera.frames(),
            configured: self.jump.is_some(),
            replay_checksum: self.replay.committed_checksum(),
            counters: self.counters(),
            reset_cause: self.reset_cause,
            reset_acknowledged: self.reset_acknowledged,
            drive_calibration: self.drive_calibration,
            bed: BedStatus::from(&self.bed),
            emergency_stop: self.emergency_stop.status(),
        }
    }

    /// The bed apparatus's inputs of this tick (the glue calls this before [`Self::tick`] on a
    /// board that has the apparatus).
    pub fn set_bed_inputs(&mut self, inputs: BedInputs) {
        self.bed.read_inputs(inputs);
    }

    /// This tick's reading of the board's emergency-stop loop (`open`: pressed, broken or not
    /// wired), on a board with [`RigConfig::emergency_stop_input`]; the glue calls this before
    /// [`Self::tick`] (or [`Self::lockstep`]) every tick, whatever else is connected.
    pub fn set_emergency_stop_loop(&mut self, open: bool) {
        self.emergency_stop.read(open);
    }

    /// The bed apparatus.
    pub fn bed(&self) -> &BedApparatus {
        &self.bed
    }

    /// Latch `code` (the first fault wins; later ones are counted). Zero force from the current
    /// tick on; use for faults found outside the core (e.g. `LinkLost` from a link timeout).
    pub fn raise_fault(&mut self, code: FaultCode) {
        if self.state == RigState::Faulted {
            self.counters.faults_after_latch = self.counters.faults_after_latch.wrapping_add(1);
            return;
        }
        self.state = RigState::Faulted;
        self.fault = Some(code);
        self.fault_tick = self.tick;
        self.camera.stop();
        self.controller.reset();
    }

    /// A valid frame arrived from the host: counts it and feeds the watchdog.
    pub fn note_frame_ok(&mut self) {
        self.counters.frames_ok = self.counters.frames_ok.wrapping_add(1);
        self.consecutive_rejected = 0;
        self.ticks_since_host = 0;
    }

    /// A frame from the host was rejected by the decoder: counted; a burst of
    /// `corrupted_frame_limit` in a row latches `LinkCorrupted`.
    pub fn note_frame_rejected(&mut self) {
        self.counters.frames_rejected = self.counters.frames_rejected.wrapping_add(1);
        self.consecutive_rejected = self.consecutive_rejected.saturating_add(1);
        let limit = self.config.corrupted_frame_limit;
        if limit > 0 && self.consecutive_rejected >= limit {
            self.raise_fault(FaultCode::LinkCorrupted);
        }
    }

    /// One control tick: check the previous tick's timing, read the encoder, watch the host,
    /// advance the setpoint, fire the camera, run the position loop, record the sample.
    pub fn tick(&mut self, input: &TickInput) -> TickOutput {
        let tick = self.tick;
        self.tick = tick.wrapping_add(1);

        self.check_timing(input.timing, tick);
        if self.bed.emergency_stop() || self.emergency_stop.tripped() {
            self.fault_at(FaultCode::EmergencyStop, tick);
        }
        let (count, position_m) = self.read_encoder(input.encoder_raw, tick);
        self.last_position_m = position_m;
        self.watch_host(tick);
        let target = self.advance_setpoint();
        let trigger = self.camera_tick();
        let (mut force_n, mut record_flags) = self.control(&target, position_m, tick);

        let drive_enabled = self.state.drive_enabled();
        if !drive_enabled {
            // Faulted (possibly on this very tick), Idle: exactly zero.
            force_n = 0.0;
        }
        let camera_trigger = trigger.level && drive_enabled;
        let camera_frame = if drive_enabled { trigger.frame } else { None };
        record_flags |= self.state_flags(drive_enabled, camera_trigger);
        self.samples.push(SampleRecord {
            seq: 0,
            tick,
            encoder_count: count,
            commanded_position_m: target.setpoint.position_m,
            force_n,
            current_a: input.current_a,
            camera_frame,
            flags: record_flags,
        });

        let bed = self.bed.update(self.state == RigState::Faulted);
        TickOutput {
            force_n,
            bed,
            drive_enabled,
            camera_trigger,
            camera_frame,
            state: self.state,
            phase: self.phase,
            fault: self.fault,
            tick,
        }
    }

    /// The previous tick's duration against the deadline: the longest is kept, an overrun
    /// latches [`FaultCode::DeadlineOverrun`].
    fn check_timing(&mut self, timing: TickTiming, tick: u32) {
        match timing {
            TickTiming::Unknown => {}
            TickTiming::Cycles(c) => {
                self.counters.max_tick_cycles = self.counters.max_tick_cycles.max(c);
                if self.config.deadline_cycles > 0 && c > self.config.deadline_cycles {
                    self.fault_at(FaultCode::DeadlineOverrun, tick);
                }
            }
            TickTiming::Overrun => self.fault_at(FaultCode::DeadlineOverrun, tick),
        }
    }

    /// Extend the raw counter to a count and feed the velocity estimate (the first reading
    /// sets the count; it is not a movement). An implausible jump latches
    /// [`FaultCode::EncoderFault`] and keeps the last count. Returns the count and the
    /// position, m.
    fn read_encoder(&mut self, raw: u32, tick: u32) -> (i64, f32) {
        let before = self.encoder.count();
        let started = self.encoder.is_started();
        let count = match self.encoder.update(raw) {
            Ok(c) => {
                if started {
                    let delta = (c - before).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
                    self.velocity.update(delta);
                }
                c
            }
            Err(_) => {
                self.fault_at(FaultCode::EncoderFault, tick);
                before
            }
        };
        let count_i32 = count.clamp(i32::MIN as i64, i32::MAX as i64) as i32;
        (count, count_i32 as f32 * self.config.metres_per_count)
    }

    /// The host's silence is counted in every state. While the drive is enabled, a host silent
    /// past the command watchdog latches [`FaultCode::CommandWatchdog`]; while a bed actuator
    /// is on (lift, shaker, blower), in any state, past the bed watchdog
    /// [`FaultCode::BedWatchdog`] (the latched fault turns the apparatus off this tick).
    fn watch_host(&mut self, tick: u32) {
        self.ticks_since_host = self.ticks_since_host.saturating_add(1);
        if self.state.drive_enabled()
            && self.watchdog_ticks > 0
            && self.ticks_since_host > self.watchdog_ticks
        {
            self.fault_at(FaultCode::CommandWatchdog, tick);
        }
        if self.bed.any_on() && self.ticks_since_host > self.bed_watchdog_ticks {
            self.fault_at(FaultCode::BedWatchdog, tick);
        }
    }

    /// This tick's setpoint, gain scale and tracking limit: the trajectory's next point while
    /// Running (Done when it finishes, holding its last position), else the hold setpoint.
    fn advance_setpoint(&mut self) -> TickTarget {
        let mut target = TickTarget {
            setpoint: self.hold,
            scale: GainScale::FULL,
            tracking_limit_m: f32::INFINITY,
        };
        let Some(j) = &self.jump else {
            return target;
        };
        target.tracking_limit_m = j.config.tracking_error_limit_m;
        match self.state {
            RigState::Running => {
                let (sp, phase) = j.profile.eval(self.run_tick, &self.replay);
                if let Some(s) = &j.schedule {
                    target.scale = s.scale(self.run_tick);
                }
                target.setpoint = sp;
                self.phase = phase;
                self.run_tick = self.run_tick.saturating_add(1);
                if phase == Phase::Finished {
                    self.state = RigState::Done;
                    self.hold = Setpoint {
                        velocity_m_s: 0.0,
                        accel_m_s2: 0.0,
                        ..sp
                    };
                }
            }
            // Done keeps the `Finished` its transition above set: only Arm and a stop change
            // the phase.
            RigState::Armed => {
                if let Some(a) = self.approach.as_mut() {
                    target.setpoint = a.advance();
                    if a.done() {
                        self.approach = None;
                        self.camera.start();
                        if core::mem::take(&mut self.start_pending) {
                            self.run_tick = 0;
                            self.state = RigState::Running;
                        }
                    }
                }
            }
            _ => {}
        }
        target
    }

    /// The camera trigger runs while the trajectory runs and after it (Running, Done).
    fn camera_tick(&mut self) -> crate::camera::TriggerTick {
        if matches!(
            self.state,
            RigState::Armed | RigState::Running | RigState::Done
        ) {
            self.camera.tick()
        } else {
            crate::camera::TriggerTick {
                level: false,
                frame: None,
            }
        }
    }

    /// The position loop while the drive is enabled: the force command and the sample flags
    /// it sets; a position past the stroke limit latches [`FaultCode::StrokeLimit`], a
    /// tracking error past the limit [`FaultCode::TrackingError`].
    fn control(&mut self, target: &TickTarget, position_m: f32, tick: u32) -> (f32, u16) {
        let mut record_flags = 0u16;
        if !self.state.drive_enabled() {
            return (0.0, record_flags);
        }
        let out = self.controller.update(
            &target.setpoint,
            position_m,
            self.velocity.velocity_m_s(),
            target.scale,
        );
        if position_m.abs() > self.config.stroke_limit_m {
            self.fault_at(FaultCode::StrokeLimit, tick);
        } else if out.error_m.abs() > target.tracking_limit_m {
            self.fault_at(FaultCode::TrackingError, tick);
        }
        if out.saturated {
            record_flags |= flags::SATURATED;
        }
        if out.integrator_held {
            record_flags |= flags::INTEGRATOR_HELD;
        }
        if target.scale.position < 1.0 || target.scale.velocity < 1.0 {
            record_flags |= flags::GAINS_LOWERED;
        }
        (out.force_n, record_flags)
    }

    /// The sample flags of the state machine, the drive, the camera line and the phase.
    fn state_flags(&self, drive_enabled: bool, camera_trigger: bool) -> u16 {
        let mut f = match self.state {
            RigState::Idle => 0,
            RigState::Armed => flags::ARMED,
            RigState::Running => flags::RUNNING,
            RigState::Done => flags::DONE,
            RigState::Faulted => flags::FAULTED,
        };
        if drive_enabled {
            f |= flags::DRIVE_ENABLED;
        }
        if camera_trigger {
            f |= flags::CAMERA_HIGH;
        }
        match self.phase {
            Phase::Delay => f |= flags::DELAY,
            Phase::PushOff => f |= flags::PUSH_OFF,
            _ => {}
        }
        f
    }

    /// Latch a fault found during tick `tick` (the tick counter has already advanced).
    fn fault_at(&mut self, code: FaultCode, tick: u32) {
        let was = self.state;
        self.raise_fault(code);
        if was != RigState::Faulted {
            self.fault_tick = tick;
        }
    }

    /// One lockstep hardware-in-the-loop step: a sensor frame in, an actuator frame out. Feeds
    /// the watchdog, counts gaps in the frame counter as lost frames, then runs [`Self::tick`].
    /// `timing` is the glue's own measurement; the frame's `overrun` flag (fault injection)
    /// also counts as an overrun.
    pub fn lockstep(&mut self, frame: &SensorFrame, timing: TickTiming) -> ActuatorFrame {
        let arrival = self.lockstep_link.on_frame(frame.frame);
        if arrival.entered {
            // The host's counter replaces the board's: its first reading is not a movement.
            self.encoder.restart();
            self.velocity.reset();
        }
        self.counters.lockstep_frames_lost = self
            .counters
            .lockstep_frames_lost
            .wrapping_add(arrival.lost);
        self.ticks_since_host = 0;
        let timing = if frame.overrun {
            TickTiming::Overrun
        } else {
            timing
        };
        if let Some(b) = frame.bed {
            self.set_bed_inputs(b);
        }
        let out = self.tick(&TickInput {
            encoder_raw: frame.encoder_count,
            current_a: frame.current_a,
            timing,
        });
        ActuatorFrame {
            frame: frame.frame,
            force_n: out.force_n,
            trigger: out.camera_trigger,
            drive_enabled: out.drive_enabled,
            camera_frame: out.camera_frame,
            state: out.state,
            fault: out.fault,
            bed: out.bed,
        }
    }

    /// In lockstep, a control period passed without a sensor frame (the glue's timer ticked,
    /// or the SIL rig's period ended). After [`RigConfig::lockstep_timeout_ticks`] such
    /// periods in a row latches `LinkLost` (once); returns true from then on, while the
    /// silence lasts. Before lockstep: no effect.
    pub fn lockstep_silent_period(&mut self) -> bool {
        let timeout = self.config.lockstep_timeout_ticks;
        if self.lockstep_link.on_silent_period(timeout) {
            let tick = self.tick;
            self.fault_at(FaultCode::LinkLost, tick);
        }
        self.lockstep_link.silent_periods() >= timeout
    }

    /// The DAC codes of the force command (`SetDriveCalibration`; nominal until set): the glue
    /// turns every force command into a DAC code with them.
    pub fn drive_calibration(&self) -> &DriveCalibration {
        &self.drive_calibration
    }

    /// The board's reset cause, read at start-up: after anything but a power-on reset, `Arm`
    /// is refused until the host sends `AcknowledgeReset` (see [`crate::reset`]).
    pub fn set_reset_cause(&mut self, cause: ResetCause) {
        self.reset_cause = cause;
        self.reset_acknowledged = cause.is_power_on();
    }

    /// A control tick's interrupt started at `cycles` of the glue's free-running cycle
    /// counter. With [`RigConfig::tick_period_cycles`] set, a gap of more than one and a half
    /// periods since the previous start (a tick missed, or two merged into one) is counted in
    /// `ticks_missed` and latches `DeadlineOverrun`: the loop did not run at its rate.
    pub fn note_tick_start(&mut self, cycles: u32) {
        let period = self.config.tick_period_cycles;
        if let Some(previous) = self.last_tick_start
            && period > 0
        {
            let gap = cycles.wrapping_sub(previous);
            if gap > period + period / 2 {
                let missed = (gap / period).saturating_sub(1).max(1);
                self.counters.ticks_missed = self.counters.ticks_missed.saturating_add(missed);
                let tick = self.tick;
                self.fault_at(FaultCode::DeadlineOverrun, tick);
            }
        }
        self.last_tick_start = Some(cycles);
    }

    /// `n` frames from the host were dropped by the glue before reaching the core (counted
    /// in the status, never silent).
    pub fn note_frames_dropped(&mut self, n: u32) {
        self.counters.frames_dropped = self.counters.frames_dropped.saturating_add(n);
    }

    /// Lockstep has been entered (a sensor frame has arrived since start-up).
    pub fn in_lockstep(&self) -> bool {
        self.lockstep_link.is_active()
    }

    /// Handle one host command. Feeds the watchdog. A rejected command changes nothing (except
    /// that an invalid configuration latches `InvalidConfiguration`).
    pub fn handle(&mut self, cmd: &Command) -> Result<Reply, CommandError> {
        self.ticks_since_host = 0;
        let result = self.handle_inner(cmd);
        if result.is_err() {
            self.counters.commands_rejected = self.counters.commands_rejected.wrapping_add(1);
        }
        result
    }

    fn illegal(&self, cmd: &Command) -> CommandError {
        CommandError::IllegalInState {
            command: cmd.kind(),
            state: self.state,
        }
    }

    fn handle_inner(&mut self, cmd: &Command) -> Result<Reply, CommandError> {
        use RigState::*;
        match (cmd, self.state) {
            (Command::StatusQuery, _) => Ok(Reply::Status(self.status())),
            (Command::Heartbeat, _) => Ok(Reply::Ack),
            (Command::Configure(jc), Idle | Done) => match self.load(jc) {
                Ok(j) => {
                    self.jump = Some(j);
                    self.stop_motion();
                    Ok(Reply::Ack)
                }
                Err(e) => {
                    self.jump = None;
                    self.raise_fault(FaultCode::InvalidConfiguration);
                    Err(CommandError::InvalidConfiguration(e))
                }
            },
            (Command::SetDriveCalibration(c), Idle | Faulted) => {
                c.validate().map_err(CommandError::InvalidCalibration)?;
                self.drive_calibration = *c;
                Ok(Reply::Ack)
            }
            (Command::AcknowledgeReset, _) => {
                self.reset_acknowledged = true;
                Ok(Reply::Ack)
            }
            (Command::Arm, Idle) => {
                if !self.reset_acknowledged {
                    return Err(CommandError::ResetNotAcknowledged {
                        cause: self.reset_cause,
                    });
                }
                self.emergency_stop
                    .check()
                    .map_err(CommandError::EmergencyStop)?;
                let Some(j) = self.jump else {
                    return Err(CommandError::NotConfigured);
                };
                self.bed.arm_check().map_err(CommandError::Interlock)?;
                // A replay table re-uploaded since Configure makes the jump stale.
                if let TickProfile::Replay(r) = j.profile
                    && self.replay.committed_checksum() != Some(r.checksum())
                {
                    self.jump = None;
                    self.raise_fault(FaultCode::InvalidConfiguration);
                    return Err(CommandError::InvalidConfiguration(ConfigError::Trajectory(
                        TrajectoryError::Replay(ReplayError::NotCommitted),
                    )));
                }
                self.controller.set_gains(j.config.gains);
                self.controller.reset();
                self.velocity.reset();
                self.hold = j.profile.start_setpoint(&self.replay);
                self.approach = Approach::new(
                    self.last_position_m,
                    self.hold.position_m,
                    self.config.tick_hz,
                );
                self.start_pending = false;
                self.run_tick = 0;
                self.phase = Phase::None;
                // The camera runs from Arm: the frames before Start show the rod at rest,
                // the height every jump height is measured from.
                self.camera = CameraTrigger::new(
                    j.config.camera_fps,
                    self.config.tick_hz,
                    j.config.camera_pulse_ticks,
                );
                // After an approach, from its end: the frames before Start must show the rod at
                // rest, and during the approach it is not.
                if self.approach.is_none() {
                    self.camera.start();
                }
                self.state = Armed;
                Ok(Reply::Ack)
            }
            (Command::Start, Armed) => {
                if self.jump.is_none() {
                    return Err(CommandError::NotConfigured);
                }
                if self.approach.is_some() {
                    // Still moving to the start: the jump begins at the end of the approach.
                    self.start_pending = true;
                    return Ok(Reply::Ack);
                }
                self.run_tick = 0;
                self.state = Running;
                Ok(Reply::Ack)
            }
            (Command::Bed(c), state) => {
                if !c.is_off() {
                    self.emergency_stop
                        .check()
                        .map_err(CommandError::EmergencyStop)?;
                }
                self.bed
                    .command(c, matches!(state, Armed | Running))
                    .map_err(CommandError::Interlock)?;
                Ok(Reply::Ack)
            }
            (Command::Abort, Idle | Armed | Running | Done) => {
                self.stop_motion();
                Ok(Reply::Ack)
            }
            (Command::ClearFault, Faulted) => {
                if self.emergency_stop.status().open {
                    return Err(CommandError::EmergencyStop(EmergencyStopError::Open));
                }
                self.bed.clear().map_err(CommandError::Interlock)?;
                self.fault = None;
                self.stop_motion();
                Ok(Reply::Ack)
            }
            (Command::ReplayBegin { len, period_ticks }, Idle | Done | Faulted) => {
                self.replay
                    .begin(*len, *period_ticks)
                    .map_err(CommandError::Replay)?;
                Ok(Reply::Ack)
            }
            (Command::ReplayChunk { offset, samples }, Idle | Done | Faulted) => {
                self.replay
                    .write_chunk(*offset, samples)
                    .map_err(CommandError::Replay)?;
                Ok(Reply::Ack)
            }
            (Command::ReplayCommit { checksum }, Idle | Done | Faulted) => {
                self.replay
                    .commit(*checksum)
                    .map_err(CommandError::Replay)?;
                Ok(Reply::Ack)
            }
            (Command::SetGains(g), Idle | Armed | Done) => {
                let Some(j) = &mut self.jump else {
                    return Err(CommandError::NotConfigured);
                };
                g.validate().map_err(CommandError::InvalidConfiguration)?;
                j.config.gains = *g;
                if self.state == Armed || self.state == Done {
                    self.controller.set_gains(*g);
                }
                Ok(Reply::Ack)
            }
            _ => Err(self.illegal(cmd)),
        }
    }

    /// To Idle: zero force, drive disabled, camera off.
    fn stop_motion(&mut self) {
        self.approach = None;
        self.start_pending = false;
        self.state = RigState::Idle;
        self.phase = Phase::None;
        self.camera.stop();
        self.controller.reset();
    }

    fn load(&self, jc: &JumpConfig) -> Result<LoadedJump, ConfigError> {
        let tick_hz = self.config.tick_hz;
        jc.validate(tick_hz)?;
        let (profile, delay) = match jc.trajectory.build()? {
            Trajectory::Sine(s) => {
                let ticks = SineTicks::new(&s, tick_hz)?;
                (TickProfile::Sine(ticks), ticks.delay_ticks())
            }
            Trajectory::SlowIntrusion(p) => (
                TickProfile::SlowIntrusion(IntrusionTicks::new(&p, tick_hz)?),
                None,
            ),
            Trajectory::Replay { checksum } => {
                let r = ReplayTicks::new(&self.replay, tick_hz)?;
                if r.checksum() != checksum {
                    return Err(TrajectoryError::Replay(ReplayError::Checksum {
                        expected: checksum,
                        actual: r.checksum(),
                    })
                    .into());
                }
                (TickProfile::Replay(r), None)
            }
        };
        let schedule = match (jc.gain_lowering, delay) {
            (Some(g), Some((n0, n1))) => Some(GainSchedule::new(&g, n0, n1, tick_hz)),
            _ => None,
        };
        Ok(LoadedJump {
            config: *jc,
            profile,
            schedule,
        })
    }

    /// Commands that are legal in the current state (for hosts and tests).
    pub fn legal_commands(&self) -> &'static [CommandKind] {
        use CommandKind as K;
        match self.state {
            RigState::Idle => &[
                K::Configure,
                K::Arm,
                K::Abort,
                K::ReplayBegin,
                K::ReplayChunk,
                K::ReplayCommit,
                K::SetGains,
                K::StatusQuery,
                K::Heartbeat,
                K::Bed,
            ],
            RigState::Armed => &[
                K::Start,
                K::Abort,
                K::SetGains,
                K::StatusQuery,
                K::Heartbeat,
                K::Bed,
            ],
            RigState::Running => &[K::Abort, K::StatusQuery, K::Heartbeat, K::Bed],
            RigState::Done => &[
                K::Configure,
                K::Abort,
                K::ReplayBegin,
                K::ReplayChunk,
                K::ReplayCommit,
                K::SetGains,
                K::StatusQuery,
                K::Heartbeat,
                K::Bed,
            ],
            RigState::Faulted => &[
                K::ClearFault,
                K::ReplayBegin,
                K::ReplayChunk,
                K::ReplayCommit,
                K::StatusQuery,
                K::Heartbeat,
                K::Bed,
            ],
        }
    }
}

#[cfg(test)]
mod tests;
