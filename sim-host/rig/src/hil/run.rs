//! One jump through the loop: configure, arm and start the controller over a [`RigLink`], then
//! one lockstep exchange per control period against the [`RigModel`], until docs/model.md's
//! run-length rule ends the run (first touchdown after the trajectory; else its end + 0.5 s,
//! extended while airborne up to 3 s) or a fault has been latched for a few periods.

use std::time::Instant;

use super::link::{LinkError, LinkReport, RigLink};
use super::rig_model::{CameraFrame, EncoderInjection, RigModel, RigModelConfig};
use sandjumper_core::protocol::{ActuatorFrame, FaultReport};
use sandjumper_core::sample::flags;
use sandjumper_core::trajectory::{JumpKind, SineJump};
use sandjumper_core::{
    Command, GainLowering, Gains, JumpConfig, RigConfig, RigState, SampleRecord, TrajectorySpec,
};
use sandjumper_model::error::SimError;
use sandjumper_model::hybrid::GroundMode;
use sandjumper_model::jump::{AIRBORNE_TAIL_S, GROUNDED_TAIL_S, sine_stroke};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params, RobotParams};
use sandjumper_model::record::JumpSummary;
use sandjumper_model::table_stroke::TableStroke;
use sandjumper_model::trajectory::Stroke;

use crate::stroke_table::StrokeTable;

/// Default relative tolerance of the plant in the loop: 1e-6 of a few centimetres is a few
/// hundredths of the encoder's 1 um count, while the period-by-period restarts of the
/// integrator at 1e-8 cost half again as many steps.
pub const DEFAULT_RTOL: f64 = 1e-6;

/// Damping ratio of [`HilSpec::rig_gains`]'s derivative gain on the motor/rod reduced mass
/// (1.25: 38 degrees of phase margin and 10 dB of gain margin on the rig's loop; 1.0 gives
/// 40 degrees, but its delayed stutter on hard ground lands at -14.9 % of the kinematic
/// height instead of -13.7 %, nearer the HIL tests' 15 % tolerance).
pub const RIG_REDUCED_MASS_DAMPING: f64 = 1.25;

/// Periods simulated after a fault is latched (to show the force stays zero).
pub const POST_FAULT_PERIODS: u64 = 20;

/// A fault injected during the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InjectedFault {
    /// Plant side: the encoder reading freezes.
    EncoderFrozen,
    /// Plant side: the encoder reading jumps by `counts`.
    EncoderJump { counts: i64 },
    /// The sensor frame flags a control-deadline overrun (a simulated slow tick).
    Overrun,
    /// Sensor frames stop for good (the host goes silent).
    LinkStops,
    /// `count` consecutive sensor frames are corrupted on the wire.
    CorruptFrames { count: u32 },
    /// The bed apparatus's emergency stop is pressed (and stays pressed); the rig gains the
    /// apparatus (lift down) if it had none.
    EmergencyStop,
}

/// An injection at a time after the trajectory starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Injection {
    /// Seconds after the trajectory's start.
    pub at_s: f64,
    /// What goes wrong.
    pub fault: InjectedFault,
}

/// The jump to run through the loop.
#[derive(Clone, Debug, PartialEq)]
pub struct HilSpec {
    /// Single, stutter or delayed stutter.
    pub kind: JumpKind,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay of the delayed stutter, s.
    pub tau_s: f64,
    /// A stroke table to run instead of the sine (`kind`, `freq_hz` and `tau_s` are then
    /// unused): uploaded into the controller's replay table and replayed.
    pub stroke: Option<StrokeTable>,
    /// Ground model of the plant.
    pub model: ModelName,
    /// Controller gains.
    pub gains: Gains,
    /// Gain-lowering damping during the delay.
    pub gain_lowering: Option<GainLowering>,
    /// Tracking-error bound that faults, m.
    pub tracking_error_limit_m: f32,
    /// Camera frame rate, frames/s (0: none).
    pub camera_fps: u32,
    /// Time the controller holds the start position (Armed) before the trajectory starts, s:
    /// lets the motor settle under its own weight.
    pub settle_s: f64,
    /// Faults to inject.
    pub injections: Vec<Injection>,
    /// Relative tolerance of the plant's Dormand-Prince integration inside each period.
    pub rtol: f64,
    /// The bed apparatus's inputs the simulated rig reports in every sensor frame (None: a
    /// rig without the apparatus). With them the controller's bed interlocks apply (`Arm`
    /// needs the lift down, blower and shaker off).
    pub bed: Option<sandjumper_core::bed::BedInputs>,
}

impl HilSpec {
    /// A jump with [`HilSpec::rig_gains`] for [`RobotParams::MODEL`], no gain lowering, a 5 mm
    /// tracking bound, a 200 fps camera and 0.2 s of settling.
    pub fn new(kind: JumpKind, freq_hz: f64, tau_s: f64, model: ModelName) -> Self {
        Self {
            kind,
            freq_hz,
            tau_s,
            stroke: None,
            model,
            gains: Self::rig_gains(&RobotParams::MODEL),
            gain_lowering: None,
            tracking_error_limit_m: 0.005,
            camera_fps: 200,
            settle_s: 0.2,
            injections: Vec::new(),
            bed: None,
            rtol: DEFAULT_RTOL,
        }
    }

    /// The jump as an acquisition log's metadata records it, with stroke amplitude
    /// `amplitude_m` (kind `stroke` and no sine parameters for a stroke table).
    pub fn log_jump(&self, amplitude_m: f64) -> sandjumper_acqlog::JumpConfig {
        if self.stroke.is_some() {
            return sandjumper_acqlog::JumpConfig {
                kind: "stroke".to_string(),
                amplitude_m: None,
                freq_hz: None,
                tau_s: None,
            };
        }
        sandjumper_acqlog::JumpConfig {
            kind: sandjumper_model::trajectory::kind_name(self.kind).to_string(),
            amplitude_m: Some(amplitude_m),
            freq_hz: Some(self.freq_hz),
            tau_s: Some(self.tau_s),
        }
    }

    /// Gains for the robot's motor carriage `m_m` on its thrust rod `m_r`.
    ///
    /// - `kp = m_m (2 pi 50 Hz)^2`: stiff enough for stance, where the spring holds the rod and
    ///   the drive moves the whole carriage against the push-off's load (the core's own
    ///   defaults, tuned on the reduced mass, lag the stutter's push-off by more than the 5 mm
    ///   tracking bound there).
    /// - `kd = 2 zeta sqrt(kp mu)`, `zeta` [`RIG_REDUCED_MASS_DAMPING`], on the reduced mass
    ///   `mu = m_m m_r / (m_m + m_r)`: above the rod's resonance on the spring (~26 Hz) the drive
    ///   sees `mu`, and the loop crosses over at a few hundred hertz where the tick, the current
    ///   lag and the velocity filter take their phase ([`loop_margins`](super::loop_margins):
    ///   38 degrees and 10 dB with the rig's defaults). Damping chosen on the carriage instead
    ///   (`zeta` 0.7 on `m_m`, the first version) left 4 degrees and 1 dB: the loop rang at
    ///   ~470 Hz, +-50 N, after every step in the feedforward.
    /// - acceleration feedforward with `m_m`, and an integrator (`ki = 10 kp`, clamped at 20 N)
    ///   that takes up the carriage's weight `m_m g`, which the core has no feedforward for.
    pub fn rig_gains(robot: &RobotParams) -> Gains {
        let (motor_mass_kg, rod_mass_kg) = (robot.motor_mass_kg, robot.rod_mass_kg);
        let w = std::f64::consts::TAU * 50.0;
        let kp = motor_mass_kg * w * w;
        let reduced_mass = motor_mass_kg * rod_mass_kg / (motor_mass_kg + rod_mass_kg);
        Gains {
            kp_n_per_m: kp as f32,
            kd_n_s_per_m: (2.0 * RIG_REDUCED_MASS_DAMPING * (kp * reduced_mass).sqrt()) as f32,
            ki_n_per_m_s: (kp * 10.0) as f32,
            integral_limit_n: 20.0,
            feedforward_mass_kg: motor_mass_kg as f32,
        }
    }

    /// The gain lowering the CLI's `--gain-lowering FACTOR` means: position gain (and
    /// integral) times `factor`, velocity gain times 0.9, 50 ms smootherstep ramps. Keeping
    /// the velocity gain (not lowering it with the position gain) keeps the carriage coupled
    /// to the rod through a damper: that is what dissipates the spring's ringing. With
    /// [`rig_gains`](Self::rig_gains) that is ~250 N s/m (probed at kp factor 0.05 over kd
    /// factors 0.7-1: at 0.8 and below the carriage, held without an integrator, drifts out of
    /// the 5 mm tracking bound; 0.9 damps the ringing 9.5-12x on hard ground and on sand, 1.0
    /// 8-10.5x).
    pub fn gain_lowering_factor(factor: f32) -> GainLowering {
        GainLowering {
            kp_factor: factor,
            kd_factor: 0.9,
            ramp_s: 0.05,
        }
    }
}

/// One control period as the plant saw it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TraceRow {
    /// Period index since the run began.
    pub period: u64,
    /// The controller's tick number for this period (`None`: no frame reached it).
    pub rig_tick: Option<u32>,
    /// Time since the trajectory started, s (negative while settling).
    pub t_s: f64,
    /// Motor position relative to the rod, m (true, not quantized).
    pub p_m: f64,
    /// Rod height above rest, m.
    pub rod_height_m: f64,
    /// Spring force, N.
    pub spring_force_n: f64,
    /// Foot depth below the undisturbed surface, m.
    pub depth_m: f64,
    /// Force command the drive received for this period (after the DAC), N.
    pub drive_command_n: f64,
    /// The controller's answer for this period reported a latched fault.
    pub faulted: bool,
}

/// Everything a run through the loop produced.
#[derive(Clone, Debug)]
pub struct HilOutcome {
    /// The link used.
    pub link_name: String,
    /// Jump metrics, times relative to the trajectory's start.
    pub summary: JumpSummary,
    /// Control periods simulated.
    pub ticks: u64,
    /// Periods of settling before the trajectory started.
    pub start_period: u64,
    /// Sensor frames the controller missed (gaps in the frame counter it saw) plus frames from
    /// the controller the host could not decode.
    pub frames_lost: u32,
    /// Frames the controller rejected (corrupted).
    pub frames_rejected: u32,
    /// Faults the controller reported.
    pub faults: Vec<FaultReport>,
    /// Camera frames the rig model took.
    pub camera_frames: Vec<CameraFrame>,
    /// The controller's sample records, in sequence order.
    pub samples: Vec<SampleRecord>,
    /// The plant, period by period.
    pub trace: Vec<TraceRow>,
    /// Wall-clock time of the loop, s.
    pub wall_time_s: f64,
    /// Simulated time, s.
    pub simulated_time_s: f64,
    /// Simulated time over wall time.
    pub realtime_factor: f64,
    /// What the link reported on closing (PIL: instructions per tick, exit status).
    pub link: LinkReport,
}

/// Why a run through the loop failed.
#[derive(Debug)]
pub enum HilError {
    /// Bad parameters or a plant failure.
    Sim(SimError),
    /// The link failed.
    Link(LinkError),
}

impl std::fmt::Display for HilError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Sim(e) => write!(f, "{e}"),
            Self::Link(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for HilError {}

impl From<SimError> for HilError {
    fn from(e: SimError) -> Self {
        Self::Sim(e)
    }
}

impl From<LinkError> for HilError {
    fn from(e: LinkError) -> Self {
        Self::Link(e)
    }
}

/// The controller's fixed configuration matching a rig model.
pub fn rig_config(model: &RigModelConfig) -> RigConfig {
    RigConfig {
        tick_hz: model.tick_hz,
        metres_per_count: model.metres_per_count as f32,
        drive_limit_n: model.dac.full_scale_n as f32,
        ..RigConfig::default()
    }
}

/// The trajectory of `spec` with the robot's stroke amplitude.
pub fn trajectory(params: &Params, spec: &HilSpec) -> Result<SineJump, SimError> {
    sine_stroke(params, spec.kind, spec.freq_hz, spec.tau_s)
}

/// What the controller runs in a loop run: the sine, or the uploaded stroke table as the
/// controller interpolates it.
#[derive(Clone, Debug, PartialEq)]
pub enum RunTrajectory {
    /// The one-cycle sine.
    Sine(SineJump),
    /// The replayed table.
    Table(TableStroke),
}

impl RunTrajectory {
    /// The trajectory of `spec` (the robot's stroke amplitude for the sine).
    pub fn of(params: &Params, spec: &HilSpec) -> Result<Self, SimError> {
        match &spec.stroke {
            None => trajectory(params, spec).map(Self::Sine),
            Some(t) => t
                .kinematic_stroke()
                .map(Self::Table)
                .map_err(|e| SimError::InvalidInput {
                    field: "stroke",
                    value: format!("{} samples at {} Hz", t.samples_m.len(), t.rate_hz),
                    allowed: e,
                }),
        }
    }

    /// `p`, m, at `t_s` from the trajectory's start.
    pub fn position_m(&self, t_s: f64) -> f64 {
        match self {
            Self::Sine(s) => s.eval(t_s).position_m,
            Self::Table(s) => s.eval(t_s).position_m,
        }
    }

    /// End of the motion, s.
    pub fn end_s(&self) -> f64 {
        match self {
            Self::Sine(s) => s.end_s(),
            Self::Table(s) => Stroke::end_s(s),
        }
    }

    /// Start of the push-off, s.
    pub fn push_off_start_s(&self) -> f64 {
        match self {
            Self::Sine(s) => s.push_off_start_s(),
            Self::Table(s) => Stroke::push_off_start_s(s),
        }
    }
}

/// The jump configuration the host sends with `Configure`.
pub fn jump_config(params: &Params, spec: &HilSpec) -> JumpConfig {
    JumpConfig {
        trajectory: match &spec.stroke {
            None => TrajectorySpec::Sine {
                kind: spec.kind,
                amplitude_m: params.robot.stroke_amplitude_m,
                freq_hz: spec.freq_hz,
                tau_s: spec.tau_s,
            },
            Some(t) => TrajectorySpec::Replay {
                checksum: t.checksum(),
            },
        },
        gains: spec.gains,
        gain_lowering: spec.gain_lowering,
        tracking_error_limit_m: spec.tracking_error_limit_m,
        camera_fps: spec.camera_fps,
        ..JumpConfig::new(TrajectorySpec::Replay { checksum: 0 })
    }
}

/// Run one jump through `link` against a rig model of `params`: plan the periods, open the
/// session (configure, one idle tick, arm), exchange one lockstep frame per period until the
/// run-length rule or a latched fault ends the run, then close the link and report.
pub fn run_jump(
    params: &Params,
    spec: &HilSpec,
    model_config: RigModelConfig,
    link: &mut dyn RigLink,
) -> Result<HilOutcome, HilError> {
    run_jump_observed(params, spec, model_config, link, None)
}

/// One control period as a live view sees it: the plant's row, the commanded motor
/// position, and the controller's answer.
#[derive(Clone, Copy, Debug)]
pub struct PeriodView {
    /// The plant's row.
    pub row: TraceRow,
    /// The trajectory's motor position at this period, m (what the controller follows once
    /// started; its start position before).
    pub p_ref_m: f64,
    /// The controller's state in its answer (`None`: no answer this period).
    pub state: Option<RigState>,
    /// The fault its answer reported.
    pub fault: Option<sandjumper_core::fault::FaultCode>,
    /// Whether the `Start` command went out at this period.
    pub started: bool,
}

/// [`run_jump`], calling `observe` after every control period (a live view; pacing). Without
/// an observer nothing is built for it: the loop costs what [`run_jump`]'s always did.
pub fn run_jump_observed(
    params: &Params,
    spec: &HilSpec,
    model_config: RigModelConfig,
    link: &mut dyn RigLink,
    mut observe: Option<&mut dyn FnMut(&PeriodView)>,
) -> Result<HilOutcome, HilError> {
    let plan = RunPlan::new(params, spec, model_config.tick_hz)?;
    let opts = SimOptions {
        rtol: spec.rtol,
        ..SimOptions::default()
    };
    let mut rig = RigModel::new(
        params,
        spec.model,
        plan.trajectory.position_m(0.0),
        model_config,
        &opts,
    )?;
    rig.set_push_off_start(plan.time_from_start_s(plan.push_off_period));
    rig.bed = spec.bed;
    let wall = Instant::now();
    open_session(params, spec, &mut rig, link, model_config.tick_hz)?;
    let mut run = LockstepRun::new(&plan);
    loop {
        let answer = run.period(&plan, &mut rig, link)?;
        if let (Some(observe), Some(row)) = (observe.as_deref_mut(), run.trace.last()) {
            let t = row.t_s.clamp(0.0, plan.trajectory.end_s());
            observe(&PeriodView {
                row: *row,
                p_ref_m: plan.trajectory.position_m(t),
                state: answer.map(|a| a.state),
                fault: answer.and_then(|a| a.fault),
                started: row.period == plan.start_period,
            });
        }
        if run.is_over(&plan, &rig)? {
            break;
        }
    }
    let link_report = link.finish()?;
    Ok(run.into_outcome(&plan, &rig, link, link_report, wall.elapsed().as_secs_f64()))
}

/// When things happen in a run, in control periods (period 0 is the idle tick before Arm).
struct RunPlan {
    /// The trajectory the controller runs.
    trajectory: RunTrajectory,
    /// Control period, s.
    period_s: f64,
    /// Control periods per second.
    tick_hz: f64,
    /// The period at which `Start` is sent (after the settling time).
    start_period: u64,
    /// The period at which the push-off half begins.
    push_off_period: u64,
    /// The period at which the trajectory ends.
    end_period: u64,
    /// The last period the run-length rule allows.
    last_period: u64,
    /// Injected faults by period, in order.
    injections: Vec<(u64, InjectedFault)>,
}

impl RunPlan {
    fn new(params: &Params, spec: &HilSpec, tick_hz: u32) -> Result<Self, HilError> {
        let trajectory = RunTrajectory::of(params, spec)?;
        if !(spec.settle_s.is_finite() && (0.0..=5.0).contains(&spec.settle_s)) {
            return Err(SimError::InvalidInput {
                field: "settle_s",
                value: spec.settle_s.to_string(),
                allowed: "0..=5 s".into(),
            }
            .into());
        }
        let tick_hz = f64::from(tick_hz);
        let start_period = ((spec.settle_s * tick_hz).round() as u64).max(1);
        let push_off_period =
            start_period + (trajectory.push_off_start_s() * tick_hz).round() as u64;
        let end_period = start_period + (trajectory.end_s() * tick_hz).ceil() as u64;
        let last_period = end_period + (AIRBORNE_TAIL_S * tick_hz).ceil() as u64 + 10;
        let mut injections: Vec<(u64, InjectedFault)> = spec
            .injections
            .iter()
            .map(|i| {
                (
                    start_period + (i.at_s.max(0.0) * tick_hz).round() as u64,
                    i.fault,
                )
            })
            .collect();
        injections.sort_by_key(|i| i.0);
        Ok(Self {
            trajectory,
            period_s: 1.0 / tick_hz,
            tick_hz,
            start_period,
            push_off_period,
            end_period,
            last_period,
            injections,
        })
    }

    /// Time of period `period` since the trajectory's start, s.
    fn time_s(&self, period: u64) -> f64 {
        (period as f64 - self.start_period as f64) * self.period_s
    }

    /// Time of period `period` since the run began (the plant's clock), s.
    fn time_from_start_s(&self, period: u64) -> f64 {
        period as f64 * self.period_s
    }
}

/// Configure the controller, give it one tick in Idle and arm it.
///
/// The idle tick (drive disabled) comes first: the controller's encoder extension takes its
/// first reading there, so the velocity estimate (reset on Arm) never sees the jump from
/// count 0 to the start position.
fn open_session(
    params: &Params,
    spec: &HilSpec,
    rig: &mut RigModel,
    link: &mut dyn RigLink,
    tick_hz: u32,
) -> Result<(), HilError> {
    if let Some(table) = &spec.stroke {
        table.upload(link, tick_hz)?;
    }
    link.command(&Command::Configure(jump_config(params, spec)))?;
    let first = rig.sense(0);
    let idle = link.exchange(&first)?;
    rig.actuate(f64::from(idle.force_n), idle.drive_enabled, idle.trigger)?;
    link.command(&Command::Arm)?;
    Ok(())
}

/// The state of the lockstep loop between periods.
struct LockstepRun {
    trace: Vec<TraceRow>,
    /// Sensor frame number of the next period.
    frame_no: u32,
    /// The controller's tick number of the next answered frame.
    rig_ticks: u32,
    /// Corrupted frames still to send.
    corrupt_left: u32,
    /// The host has gone silent.
    link_stopped: bool,
    /// The next sensor frame flags an overrun.
    overrun_next: bool,
    fault_period: Option<u64>,
    done_period: Option<u64>,
    was_aerial: bool,
    next_injection: usize,
    /// The next period to run.
    period: u64,
}

impl LockstepRun {
    fn new(plan: &RunPlan) -> Self {
        Self {
            trace: Vec::with_capacity((plan.last_period + 1) as usize),
            frame_no: 1,
            rig_ticks: 1,
            corrupt_left: 0,
            link_stopped: false,
            overrun_next: false,
            fault_period: None,
            done_period: None,
            was_aerial: false,
            next_injection: 0,
            period: 1,
        }
    }

    /// One control period: start the trajectory when due, inject what is due, exchange a
    /// frame (or not, as injected), drive the plant and trace it.
    fn period(
        &mut self,
        plan: &RunPlan,
        rig: &mut RigModel,
        link: &mut dyn RigLink,
    ) -> Result<Option<ActuatorFrame>, HilError> {
        if self.period == plan.start_period {
            link.command(&Command::Start)?;
        }
        self.inject_due(plan, rig);
        let state = rig.state();
        let rod_height_m = rig.rod_height_m();
        let (actuator, rig_tick) = self.exchange(rig, link)?;
        match actuator {
            Some(a) => {
                rig.actuate(f64::from(a.force_n), a.drive_enabled, a.trigger)?;
                if a.fault.is_some() && self.fault_period.is_none() {
                    self.fault_period = Some(self.period);
                }
                if a.state == RigState::Done && self.done_period.is_none() {
                    self.done_period = Some(self.period);
                }
            }
            None => rig.hold()?,
        }
        self.trace.push(TraceRow {
            period: self.period,
            rig_tick,
            t_s: plan.time_s(self.period),
            p_m: state.p,
            rod_height_m,
            spring_force_n: state.f_s,
            depth_m: state.depth_m,
            drive_command_n: rig.drive_command_n(),
            faulted: actuator.is_some_and(|a| a.fault.is_some()),
        });
        self.period += 1;
        Ok(actuator)
    }

    /// Apply the injections due at this period.
    fn inject_due(&mut self, plan: &RunPlan, rig: &mut RigModel) {
        while let Some(&(at, fault)) = plan.injections.get(self.next_injection) {
            if at != self.period {
                break;
            }
            match fault {
                InjectedFault::EncoderFrozen => rig.inject(EncoderInjection::Frozen),
                InjectedFault::EncoderJump { counts } => {
                    rig.inject(EncoderInjection::Jump { counts })
                }
                InjectedFault::Overrun => self.overrun_next = true,
                InjectedFault::LinkStops => self.link_stopped = true,
                InjectedFault::CorruptFrames { count } => self.corrupt_left = count,
                InjectedFault::EmergencyStop => {
                    let mut b = rig.bed.unwrap_or(sandjumper_core::bed::BedInputs {
                        lift_down_limit: true,
                        ..Default::default()
                    });
                    b.emergency_stop = true;
                    rig.bed = Some(b);
                }
            }
            self.next_injection += 1;
        }
    }

    /// Send this period's sensor frame (silence or a corrupted frame, if injected) and take
    /// the controller's answer: the actuator frame and the controller's tick number, if any.
    fn exchange(
        &mut self,
        rig: &mut RigModel,
        link: &mut dyn RigLink,
    ) -> Result<(Option<ActuatorFrame>, Option<u32>), HilError> {
        let mut sensor = rig.sense(self.frame_no);
        self.frame_no = self.frame_no.wrapping_add(1);
        sensor.overrun = std::mem::take(&mut self.overrun_next);
        if self.link_stopped {
            return Ok((link.silent_period()?, None));
        }
        if self.corrupt_left > 0 {
            self.corrupt_left -= 1;
            link.send_corrupted(&sensor)?;
            return Ok((None, None));
        }
        let a = link.exchange(&sensor)?;
        if a.frame != sensor.frame {
            return Err(LinkError::Protocol(format!(
                "actuator frame {} answers sensor frame {}",
                a.frame, sensor.frame
            ))
            .into());
        }
        let tick = self.rig_ticks;
        self.rig_ticks = self.rig_ticks.wrapping_add(1);
        Ok((Some(a), Some(tick)))
    }

    /// The run-length rule (docs/model.md): a few periods after a fault; else, once the controller
    /// is done and the trajectory over, at the first touchdown, at the end of the grounded
    /// tail, or at the last period allowed. A controller that never reports done is an error.
    fn is_over(&mut self, plan: &RunPlan, rig: &RigModel) -> Result<bool, HilError> {
        if let Some(f) = self.fault_period
            && self.period >= f + POST_FAULT_PERIODS
        {
            return Ok(true);
        }
        let aerial = rig.state().mode == GroundMode::Aerial;
        if let Some(d) = self.done_period.map(|d| d.max(plan.end_period)) {
            let touchdown = self.was_aerial && !aerial;
            let grounded_tail_over =
                self.period >= d + (GROUNDED_TAIL_S * plan.tick_hz).round() as u64;
            if touchdown || (grounded_tail_over && !aerial) || self.period >= plan.last_period {
                return Ok(true);
            }
        }
        self.was_aerial = aerial;
        if self.period > plan.last_period + plan.start_period + 100_000 {
            return Err(LinkError::Protocol(
                "the controller never reported the trajectory done".into(),
            )
            .into());
        }
        Ok(false)
    }

    /// Collect what the link recorded and the plant's summary, times from the trajectory's
    /// start. The plant located every apex and lift-off exactly and knew when the push-off
    /// began, so its final height, apex and lift-off are those of a kinematic jump.
    fn into_outcome(
        self,
        plan: &RunPlan,
        rig: &RigModel,
        link: &mut dyn RigLink,
        link_report: LinkReport,
        wall_time_s: f64,
    ) -> HilOutcome {
        let mut samples = link.take_samples();
        samples.sort_by_key(|s| s.seq);
        let faults = link.take_faults();
        let t0 = plan.start_period as f64 * plan.period_s;
        let summary = shifted(rig.plant().summary(), t0);
        let counters = link_report.counters().unwrap_or_default();
        let simulated_time_s = self.period as f64 * plan.period_s;
        HilOutcome {
            link_name: link.name(),
            summary,
            ticks: self.period,
            start_period: plan.start_period,
            frames_lost: counters.lockstep_frames_lost + link_report.host_frames_rejected,
            frames_rejected: counters.frames_rejected,
            faults,
            camera_frames: rig.camera_frames().to_vec(),
            samples,
            trace: self.trace,
            wall_time_s,
            simulated_time_s,
            realtime_factor: simulated_time_s / wall_time_s.max(1e-9),
            link: link_report,
        }
    }
}

/// The plant's summary with every time measured from the trajectory's start.
fn shifted(mut s: JumpSummary, t0: f64) -> JumpSummary {
    s.liftoff_time_s = s.liftoff_time_s.map(|t| t - t0);
    s.final_liftoff_time_s = s.final_liftoff_time_s.map(|t| t - t0);
    s.apex_time_s -= t0;
    s.final_apex_time_s -= t0;
    s.end_time_s -= t0;
    for e in &mut s.events {
        e.t_s -= t0;
    }
    s
}

impl HilOutcome {
    /// Largest `|p_cmd - p|` (commanded vs true motor position) from the trajectory's start
    /// until the first tick whose force command saturated (or the end), m, with the tick it
    /// happened on.
    pub fn tracking_error_until_saturation(&self) -> (f64, Option<u32>) {
        let by_tick: std::collections::HashMap<u32, &TraceRow> = self
            .trace
            .iter()
            .filter_map(|r| r.rig_tick.map(|t| (t, r)))
            .collect();
        let mut worst = (0.0, None);
        for s in &self.samples {
            if s.flags & (flags::RUNNING | flags::DONE) == 0 {
                continue;
            }
            if s.flags & flags::SATURATED != 0 {
                break;
            }
            if let Some(row) = by_tick.get(&s.tick) {
                let e = (f64::from(s.commanded_position_m) - row.p_m).abs();
                if e > worst.0 {
                    worst = (e, Some(s.tick));
                }
            }
        }
        worst
    }

    /// The first fault reported, if any.
    pub fn first_fault(&self) -> Option<FaultReport> {
        self.faults.first().copied()
    }

    /// Sample records missing from the sequence (gaps in `seq`).
    pub fn samples_missing(&self) -> u64 {
        self.samples
            .windows(2)
            .map(|w| u64::from(w[1].seq.wrapping_sub(w[0].seq).saturating_sub(1)))
            .sum()
    }
}
