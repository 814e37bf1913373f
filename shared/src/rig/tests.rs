use super::*;
use crate::command::REPLAY_CHUNK;
use crate::config::TrajectorySpec;
use crate::controller::GainLowering;
use crate::drive_calibration::DriveCalibration;
use crate::replay::replay_checksum;
use crate::reset::ResetCause;
use crate::trajectory::JumpKind;
use proptest::prelude::*;

/// A motor on its rod as a point mass (the reduced mass) with a constant disturbance force,
/// integrated with semi-implicit Euler at the tick rate; the encoder quantizes to 1 um.
struct Plant {
    p: f64,
    v: f64,
    mass_kg: f64,
    disturbance_n: f64,
    metres_per_count: f64,
}

impl Plant {
    fn new(p: f64) -> Self {
        Self {
            p,
            v: 0.0,
            mass_kg: 0.1125,
            disturbance_n: 0.0,
            metres_per_count: 1e-6,
        }
    }
    fn raw(&self) -> u32 {
        (self.p / self.metres_per_count).round() as i64 as u32
    }
    fn step(&mut self, force_n: f32, dt: f64) {
        self.v += (force_n as f64 + self.disturbance_n) / self.mass_kg * dt;
        self.p += self.v * dt;
    }
}

/// Tick with an empty sample queue, so the newest record is this tick's.
fn fresh_tick(r: &mut Rig<64>, inp: TickInput) -> TickOutput {
    while r.samples().pop().is_some() {}
    r.tick(&inp)
}

fn input(raw: u32) -> TickInput {
    TickInput {
        encoder_raw: raw,
        current_a: None,
        timing: TickTiming::Unknown,
    }
}

fn sine(kind: JumpKind, freq_hz: f64, tau_s: f64) -> JumpConfig {
    JumpConfig::new(TrajectorySpec::Sine {
        kind,
        amplitude_m: 0.01875,
        freq_hz,
        tau_s,
    })
}

fn rig() -> Rig<64> {
    Rig::new(RigConfig::default()).unwrap()
}

/// Configure, arm at the start position, start.
fn armed_and_started(jc: JumpConfig, plant: &mut Plant) -> Rig<64> {
    let mut r = Rig::new(RigConfig {
        metres_per_count: plant.metres_per_count as f32,
        max_counts_per_tick: (1e-3 / plant.metres_per_count) as u32,
        ..RigConfig::default()
    })
    .unwrap();
    r.handle(&Command::Configure(jc)).unwrap();
    r.handle(&Command::Arm).unwrap();
    plant.p = r.hold.position_m as f64;
    r.tick(&input(plant.raw()));
    r.handle(&Command::Start).unwrap();
    r
}

/// Run until Done (or a fault), draining samples; returns (max |tracking error|, samples).
fn run_to_end(
    r: &mut Rig<64>,
    plant: &mut Plant,
    max_ticks: u32,
) -> (f64, std::vec::Vec<SampleRecord>) {
    let mut samples = std::vec::Vec::new();
    let mut worst: f64 = 0.0;
    for k in 0..max_ticks {
        let out = r.tick(&input(plant.raw()));
        while let Some(s) = r.samples().pop() {
            samples.push(s);
        }
        if out.state == RigState::Running {
            worst =
                worst.max((samples.last().unwrap().commanded_position_m as f64 - plant.p).abs());
        }
        plant.step(out.force_n, 1e-4);
        if k % 1000 == 0 {
            r.handle(&Command::Heartbeat).unwrap();
        }
        if out.state != RigState::Running {
            break;
        }
    }
    (worst, samples)
}

#[test]
fn delayed_stutter_tracks_runs_to_done_and_films_every_5_ms() {
    let mut plant = Plant::new(0.0);
    let mut r = armed_and_started(sine(JumpKind::DelayedStutter, 8.0, 0.75), &mut plant);
    let (worst, samples) = run_to_end(&mut r, &mut plant, 20_000);
    assert_eq!(r.state(), RigState::Done);
    assert_eq!(r.fault(), None);
    // The trajectory asks at most A w^2 m = 5.3 N of the 300 N. What is left is the 50 Hz
    // loop's answer to the steps in p'' at 0, T/2, T/2+tau and the velocity filter's lag:
    // under 0.2 mm (1 % of the amplitude).
    assert!(worst < 200e-6, "worst tracking error {worst} m");
    // Sequence numbers prove nothing was lost.
    for w in samples.windows(2) {
        assert_eq!(w[1].seq, w[0].seq + 1);
        assert_eq!(w[1].tick, w[0].tick + 1);
    }
    // Camera: it runs from Arm (frame 0 on the armed tick before Start),
    // frame k on the k*50-th tick after the arm; ticks recorded in the samples.
    let first = samples
        .iter()
        .find(|s| s.flags & flags::RUNNING != 0)
        .unwrap()
        .tick;
    let arm_tick = first - 1;
    let frames: std::vec::Vec<(u32, u32)> = samples
        .iter()
        .filter_map(|s| s.camera_frame.map(|f| (f, s.tick - arm_tick)))
        .collect();
    // The run lasts 8750 ticks (T + tau): a frame every 50 of them, numbered on.
    assert!(
        (8750 / 50..=8750 / 50 + 2).contains(&frames.len()),
        "{}",
        frames.len()
    );
    for (k, (f, t)) in frames.into_iter().enumerate() {
        assert_eq!(f as usize, k);
        assert_eq!(t, 50 * f);
    }
    assert!(samples.iter().any(|s| s.flags & flags::DELAY != 0));
}

#[test]
fn gain_lowering_ramps_are_bumpless_in_the_loop() {
    let mut jc = sine(JumpKind::DelayedStutter, 8.0, 0.75);
    jc.gain_lowering = Some(GainLowering {
        kp_factor: 0.05,
        kd_factor: 0.5,
        ramp_s: 0.05,
    });
    let mut plant = Plant::new(0.0);
    plant.disturbance_n = -1.0; // a steady load the position loop must hold against
    // A 10 nm encoder, so the D term's count-quantization noise (0.2 N at 1 um) does not
    // hide what is measured here.
    plant.metres_per_count = 1e-8;
    let mut r = armed_and_started(jc, &mut plant);
    let (_, samples) = run_to_end(&mut r, &mut plant, 20_000);
    assert_eq!(r.state(), RigState::Done);
    let delay: std::vec::Vec<&SampleRecord> = samples
        .iter()
        .filter(|s| s.flags & flags::DELAY != 0)
        .collect();
    assert_eq!(delay.len(), 7500);
    assert!(
        delay[1000..6000]
            .iter()
            .all(|s| s.flags & flags::GAINS_LOWERED != 0)
    );
    // The ramp back up (last 500 ticks of the delay), with the loop settled against the 1 N
    // load at 1/20 of kp (error 1.8 mm): a step back to full gains would jump the force by
    // ~19 N; the C2 ramp keeps every tick-to-tick change below 0.05 N.
    let ramp_up = &delay[delay.len() - 600..];
    let max_step = ramp_up
        .windows(2)
        .map(|w| (w[1].force_n - w[0].force_n).abs())
        .fold(0.0, f32::max);
    assert!(
        max_step < 0.05,
        "force step {max_step} N while ramping the gains up"
    );
    // Before the ramp the loop is settled, balancing the load.
    assert!(
        (ramp_up[0].force_n - 1.0).abs() < 0.05,
        "{}",
        ramp_up[0].force_n
    );
    // The gains are back to full on the first push-off tick.
    let push = samples
        .iter()
        .find(|s| s.flags & flags::PUSH_OFF != 0)
        .unwrap();
    assert_eq!(push.flags & flags::GAINS_LOWERED, 0);
}

/// Every fault: zero force and disabled drive on the faulting tick itself, state Faulted, the
/// code reported, the sample of that tick marked; only ClearFault leaves.
fn assert_faults_now(r: &mut Rig<64>, out: TickOutput, code: FaultCode) {
    assert_eq!(out.fault, Some(code));
    assert_eq!(out.force_n.to_bits(), 0.0f32.to_bits());
    assert!(!out.drive_enabled);
    assert_eq!(out.state, RigState::Faulted);
    let mut last = None;
    while let Some(s) = r.samples().pop() {
        last = Some(s);
    }
    let last = last.unwrap();
    assert_eq!(last.tick, out.tick);
    assert_eq!(last.force_n.to_bits(), 0.0f32.to_bits());
    assert_ne!(last.flags & flags::FAULTED, 0);
    assert_eq!(r.status().fault_tick, out.tick);
    // Stays faulted with zero force; Arm/Start/Abort are rejected.
    let again = r.tick(&input(r.encoder_count() as u32));
    assert_eq!((again.force_n, again.state), (0.0, RigState::Faulted));
    for c in [Command::Arm, Command::Start, Command::Abort] {
        assert!(matches!(
            r.handle(&c),
            Err(CommandError::IllegalInState { .. })
        ));
    }
    r.handle(&Command::ClearFault).unwrap();
    assert_eq!(r.state(), RigState::Idle);
    assert_eq!(r.fault(), None);
}

/// An armed rig holding its start position (+A for the stutter).
fn armed() -> (Rig<64>, u32) {
    armed_with(sine(JumpKind::Stutter, 10.0, 0.0))
}

fn armed_with(jc: JumpConfig) -> (Rig<64>, u32) {
    let mut r = rig();
    r.handle(&Command::Configure(jc)).unwrap();
    r.handle(&Command::Arm).unwrap();
    let raw = 18_750u32; // p(0) = +A for a stutter
    let out = r.tick(&input(raw));
    assert!(out.drive_enabled);
    (r, raw)
}

#[test]
fn fault_stroke_limit() {
    let mut jc = sine(JumpKind::Stutter, 10.0, 0.0);
    jc.tracking_error_limit_m = 0.02;
    let (mut r, raw) = armed_with(jc);
    // Moving out at 5 m/s (500 counts per tick): faults on the first reading beyond 25.5 mm.
    let mut out = r.tick(&input(raw));
    for k in 1..=20 {
        out = fresh_tick(&mut r, input(raw + 500 * k));
        if out.fault.is_some() {
            assert_eq!(raw + 500 * k, 25_750);
            break;
        }
    }
    assert_faults_now(&mut r, out, FaultCode::StrokeLimit);
}

#[test]
fn fault_tracking_error() {
    let (mut r, raw) = armed();
    let mut out = r.tick(&input(raw));
    for k in 1..=6 {
        out = fresh_tick(&mut r, input(raw - 1000 * k)); // drifting away, 1 mm per tick
        if out.fault.is_some() {
            break;
        }
    }
    assert_faults_now(&mut r, out, FaultCode::TrackingError);
}

#[test]
fn fault_encoder_jump_and_frozen_encoder() {
    let (mut r, raw) = armed();
    let out = fresh_tick(&mut r, input(raw.wrapping_add(1001)));
    assert_faults_now(&mut r, out, FaultCode::EncoderFault);
    // A frozen encoder while the trajectory moves shows up as a tracking error.
    let (mut r, raw) = armed();
    r.handle(&Command::Start).unwrap();
    let mut faulted = None;
    for _ in 0..2000 {
        let out = fresh_tick(&mut r, input(raw));
        if out.fault.is_some() {
            faulted = Some(out);
            break;
        }
    }
    assert_faults_now(&mut r, faulted.unwrap(), FaultCode::TrackingError);
}

#[test]
fn fault_command_watchdog() {
    let (mut r, raw) = armed();
    let wd = r.config().watchdog_ticks();
    let mut out = r.tick(&input(raw));
    for _ in 0..wd {
        out = fresh_tick(&mut r, input(raw));
        if out.fault.is_some() {
            break;
        }
    }
    assert_faults_now(&mut r, out, FaultCode::CommandWatchdog);
    // Idle never trips it.
    for _ in 0..2 * wd {
        assert_eq!(fresh_tick(&mut r, input(raw)).fault, None);
    }
}

#[test]
fn fault_deadline_overrun() {
    let (mut r, raw) = armed();
    let out = fresh_tick(
        &mut r,
        TickInput {
            timing: TickTiming::Overrun,
            ..input(raw)
        },
    );
    assert_faults_now(&mut r, out, FaultCode::DeadlineOverrun);
    let mut r: Rig<64> = Rig::new(RigConfig {
        deadline_cycles: 1000,
        ..RigConfig::default()
    })
    .unwrap();
    assert_eq!(
        r.tick(&TickInput {
            timing: TickTiming::Cycles(1000),
            ..input(0)
        })
        .fault,
        None
    );
    let out = fresh_tick(
        &mut r,
        TickInput {
            timing: TickTiming::Cycles(1001),
            ..input(0)
        },
    );
    assert_faults_now(&mut r, out, FaultCode::DeadlineOverrun);
    assert_eq!(r.counters().max_tick_cycles, 1001);
}

#[test]
fn fault_invalid_configuration() {
    let mut r = rig();
    let bad = JumpConfig::new(TrajectorySpec::Sine {
        kind: JumpKind::Single,
        amplitude_m: 0.03,
        freq_hz: 10.0,
        tau_s: 0.0,
    });
    let e = r.handle(&Command::Configure(bad)).unwrap_err();
    assert!(matches!(
        e,
        CommandError::InvalidConfiguration(ConfigError::Trajectory(
            TrajectoryError::Amplitude { .. }
        ))
    ));
    assert_eq!(r.fault(), Some(FaultCode::InvalidConfiguration));
    let out = fresh_tick(&mut r, input(0));
    // Latched by the command before this tick: the fault tick is the tick count at that time.
    assert_eq!(out.fault, Some(FaultCode::InvalidConfiguration));
    assert_eq!(r.status().fault_tick, 0);
    assert_eq!(out.force_n, 0.0);
    r.handle(&Command::ClearFault).unwrap();
    // The bad configuration was not kept: nothing to arm.
    assert_eq!(r.handle(&Command::Arm), Err(CommandError::NotConfigured));
}

#[test]
fn fault_link_corrupted_burst_and_link_lost() {
    let (mut r, raw) = armed();
    for _ in 0..9 {
        r.note_frame_rejected();
    }
    r.note_frame_ok(); // a good frame resets the burst
    for _ in 0..9 {
        r.note_frame_rejected();
    }
    assert_eq!(r.fault(), None);
    r.note_frame_rejected();
    assert_eq!(r.fault(), Some(FaultCode::LinkCorrupted));
    let out = fresh_tick(&mut r, input(raw));
    assert_eq!((out.force_n, out.drive_enabled), (0.0, false));
    assert_eq!(r.counters().frames_rejected, 19);
    let (mut r, raw) = armed();
    r.raise_fault(FaultCode::LinkLost);
    let out = fresh_tick(&mut r, input(raw));
    assert_eq!(
        (out.force_n, out.drive_enabled, out.fault),
        (0.0, false, Some(FaultCode::LinkLost))
    );
    r.handle(&Command::ClearFault).unwrap();
}

#[test]
fn first_fault_wins_later_ones_are_counted() {
    let (mut r, raw) = armed();
    let out = r.tick(&TickInput {
        timing: TickTiming::Overrun,
        ..input(raw.wrapping_add(5000))
    });
    assert_eq!(out.fault, Some(FaultCode::DeadlineOverrun));
    assert_eq!(r.counters().faults_after_latch, 1);
}

#[test]
fn lockstep_counts_lost_frames_and_mirrors_the_tick() {
    let (mut r, raw) = armed();
    let f = |frame| SensorFrame {
        frame,
        encoder_count: raw,
        current_a: Some(0.5),
        overrun: false,
        bed: None,
    };
    let a = r.lockstep(&f(10), TickTiming::Unknown);
    assert_eq!(
        (a.frame, a.drive_enabled, a.state),
        (10, true, RigState::Armed)
    );
    r.lockstep(&f(11), TickTiming::Unknown);
    r.lockstep(&f(15), TickTiming::Unknown);
    assert_eq!(r.counters().lockstep_frames_lost, 3);
    let a = r.lockstep(
        &SensorFrame {
            overrun: true,
            ..f(16)
        },
        TickTiming::Unknown,
    );
    assert_eq!(
        (a.force_n, a.fault),
        (0.0, Some(FaultCode::DeadlineOverrun))
    );
}

#[test]
fn replay_uploaded_in_chunks_is_followed() {
    let xs: std::vec::Vec<f32> = (0..300)
        .map(|k| 0.01 * libm::sinf(k as f32 * 0.03))
        .collect();
    let mut r = rig();
    r.handle(&Command::ReplayBegin {
        len: 300,
        period_ticks: 10,
    })
    .unwrap();
    for (k, c) in xs.chunks(REPLAY_CHUNK).enumerate() {
        let samples = heapless::Vec::from_slice(c).unwrap();
        r.handle(&Command::ReplayChunk {
            offset: (k * REPLAY_CHUNK) as u32,
            samples,
        })
        .unwrap();
    }
    let crc = replay_checksum(&xs);
    assert!(matches!(
        r.handle(&Command::ReplayCommit { checksum: crc ^ 1 }),
        Err(CommandError::Replay(ReplayError::Checksum { .. }))
    ));
    r.handle(&Command::ReplayCommit { checksum: crc }).unwrap();
    assert_eq!(r.status().replay_checksum, Some(crc));
    let jc = JumpConfig::new(TrajectorySpec::Replay { checksum: crc });
    let mut plant = Plant::new(0.0);
    r.handle(&Command::Configure(jc)).unwrap();
    r.handle(&Command::Arm).unwrap();
    r.tick(&input(plant.raw()));
    r.handle(&Command::Start).unwrap();
    let (worst, samples) = run_to_end(&mut r, &mut plant, 5000);
    assert_eq!(r.state(), RigState::Done);
    // The table starts moving at 0.15 m/s (Catmull-Rom's end tangent): a velocity step.
    assert!(worst < 200e-6, "{worst}");
    let start = samples
        .iter()
        .position(|s| s.flags & flags::RUNNING != 0)
        .unwrap();
    for k in 0..299 {
        assert_eq!(samples[start + 10 * k].commanded_position_m, xs[k]);
    }
    // Done holds the table's last position at rest: no velocity or acceleration feedforward
    // pushes on after it, and its phase stays Finished.
    assert_eq!(r.hold.position_m, xs[299]);
    assert_eq!((r.hold.velocity_m_s, r.hold.accel_m_s2), (0.0, 0.0));
    assert_eq!(r.status().phase, Phase::Finished);
}

#[test]
fn replay_upload_helper_commits_the_table() {
    let xs: std::vec::Vec<f32> = (0..1000).map(|k| 1e-5 * k as f32).collect();
    let mut r = rig();
    for cmd in crate::command::replay_upload(&xs, 10) {
        r.handle(&cmd).unwrap();
    }
    assert_eq!(r.status().replay_checksum, Some(replay_checksum(&xs)));
    assert_eq!(r.replay_table().samples(), &xs[..]);
}

#[test]
fn stale_replay_configuration_is_refused_at_arm() {
    let mut r = rig();
    let xs = [0.0f32, 0.001, 0.002];
    let upload = |r: &mut Rig<64>, xs: &[f32]| {
        r.handle(&Command::ReplayBegin {
            len: xs.len() as u32,
            period_ticks: 100,
        })
        .unwrap();
        let samples = heapless::Vec::from_slice(xs).unwrap();
        r.handle(&Command::ReplayChunk { offset: 0, samples })
            .unwrap();
        r.handle(&Command::ReplayCommit {
            checksum: replay_checksum(xs),
        })
        .unwrap();
    };
    upload(&mut r, &xs);
    let jc = JumpConfig::new(TrajectorySpec::Replay {
        checksum: replay_checksum(&xs),
    });
    r.handle(&Command::Configure(jc)).unwrap();
    upload(&mut r, &[0.0, 0.001, 0.003]);
    assert!(matches!(
        r.handle(&Command::Arm),
        Err(CommandError::InvalidConfiguration(_))
    ));
    assert_eq!(r.fault(), Some(FaultCode::InvalidConfiguration));
}

#[test]
fn slow_intrusion_runs_through_the_loop() {
    let jc = JumpConfig::new(TrajectorySpec::SlowIntrusion {
        start_m: -0.02,
        depth_m: 0.01,
        withdraw_m: 0.002,
        reintrusion_depth_m: 0.015,
        speed_m_s: 0.05,
        hold_s: 0.05,
    });
    let mut plant = Plant::new(0.0);
    let mut r = armed_and_started(jc, &mut plant);
    let (worst, samples) = run_to_end(&mut r, &mut plant, 30_000);
    assert_eq!(r.state(), RigState::Done);
    // Each segment starts with a step of 0.05 m/s in the commanded velocity; the core's
    // default loop on the reduced mass lags it by ~50 um for a moment (55 um behind the 2 kHz
    // velocity filter, 48 um behind the first 500 Hz one, whose lag happened to help here).
    assert!(worst < 60e-6, "{worst}");
    let deepest = samples
        .iter()
        .map(|s| s.commanded_position_m)
        .fold(f32::MIN, f32::max);
    assert!((deepest - -0.005).abs() < 1e-6);
}

fn any_command() -> impl Strategy<Value = Command> {
    prop_oneof![
        Just(Command::Configure(sine(JumpKind::Single, 10.0, 0.0))),
        Just(Command::Configure(sine(JumpKind::Single, 50.0, 0.0))),
        Just(Command::Arm),
        Just(Command::Start),
        Just(Command::Abort),
        Just(Command::ClearFault),
        Just(Command::ReplayBegin {
            len: 2,
            period_ticks: 1
        }),
        Just(Command::SetGains(crate::controller::Gains::default())),
        Just(Command::StatusQuery),
        Just(Command::Heartbeat),
    ]
}

proptest! {
    /// Random command sequences (with ticks between): a command is accepted only if the table
    /// lists it as legal in the current state, an illegal one is rejected with
    /// `IllegalInState` and changes nothing, and every accepted one lands in the documented
    /// state.
    #[test]
    fn state_machine_only_takes_legal_transitions(
        cmds in proptest::collection::vec((any_command(), 0u32..3), 1..60),
    ) {
        let mut r = rig();
        let raw = (-18_750i32) as u32; // single jump: p(0) = -A
        for (cmd, ticks) in cmds {
            let before = r.state();
            let legal = r.legal_commands().contains(&cmd.kind());
            let result = r.handle(&cmd);
            match &result {
                Err(CommandError::IllegalInState { state, .. }) => {
                    prop_assert!(!legal);
                    prop_assert_eq!(*state, before);
                    prop_assert_eq!(r.state(), before);
                }
                Err(CommandError::InvalidConfiguration(_)) => {
                    prop_assert!(legal);
                    prop_assert_eq!(r.state(), RigState::Faulted);
                }
                Err(_) => {
                    prop_assert!(legal);
                    prop_assert_eq!(r.state(), before);
                }
                Ok(_) => {
                    prop_assert!(legal);
                    let expected = match (cmd.kind(), before) {
                        (CommandKind::Configure | CommandKind::Abort | CommandKind::ClearFault, _) => RigState::Idle,
                        (CommandKind::Arm, _) => RigState::Armed,
                        (CommandKind::Start, _) => RigState::Running,
                        (_, s) => s,
                    };
                    prop_assert_eq!(r.state(), expected);
                }
            }
            for _ in 0..ticks {
                let out = r.tick(&input(raw));
                prop_assert_eq!(out.drive_enabled, out.state.drive_enabled());
                if !out.drive_enabled {
                    prop_assert_eq!(out.force_n, 0.0);
                }
            }
        }
    }
}

/// A sensor frame from the host with its own encoder count.
fn host_frame(frame: u32, encoder_count: u32) -> SensorFrame {
    SensorFrame {
        frame,
        encoder_count,
        current_a: None,
        overrun: false,
        bed: None,
    }
}

#[test]
fn lockstep_entered_after_thousands_of_free_running_ticks_arms_cleanly() {
    // On the rig the core has read its own encoder (TIM2) since boot; the host's simulated
    // count starts far from it. Entering lockstep must not read that as a movement.
    let mut r = rig();
    for k in 0..5_000u32 {
        r.tick(&input(2_000_000 + k % 7));
    }
    assert_eq!(r.fault(), None);
    // Not in lockstep before the first sensor frame (cargo mutants: `in_lockstep` as `true`
    // passed every test).
    assert!(!r.in_lockstep());
    r.handle(&Command::Configure(sine(JumpKind::Stutter, 10.0, 0.0)))
        .unwrap();
    let start = 18_750u32; // p(0) = +A for a stutter
    let a = r.lockstep(&host_frame(1, start), TickTiming::Unknown);
    assert_eq!(a.fault, None, "entering lockstep latched {:?}", a.fault);
    assert!(r.in_lockstep());
    r.handle(&Command::Arm).unwrap();
    for k in 2..200 {
        let a = r.lockstep(&host_frame(k, start), TickTiming::Unknown);
        assert_eq!((a.state, a.fault), (RigState::Armed, None), "frame {k}");
        assert!(a.drive_enabled);
    }
    // Holding the start position: no velocity from the switch of counters.
    assert!(r.velocity.velocity_m_s().abs() < 1e-3);
}

#[test]
fn frames_that_stop_in_lockstep_latch_link_lost() {
    let mut r = rig();
    r.handle(&Command::Configure(sine(JumpKind::Stutter, 10.0, 0.0)))
        .unwrap();
    assert!(
        !r.lockstep_silent_period(),
        "no lockstep yet: no link to lose"
    );
    r.lockstep(&host_frame(1, 18_750), TickTiming::Unknown);
    r.handle(&Command::Arm).unwrap();
    r.lockstep(&host_frame(2, 18_750), TickTiming::Unknown);
    let timeout = r.config().lockstep_timeout_ticks;
    for k in 1..timeout {
        assert!(!r.lockstep_silent_period(), "silent period {k}");
        assert_eq!(r.fault(), None);
    }
    assert!(r.lockstep_silent_period());
    assert_eq!(r.fault(), Some(FaultCode::LinkLost));
    assert!(!r.state().drive_enabled());
    // Reported once: further silence is no new fault.
    assert!(r.lockstep_silent_period());
    assert_eq!(r.counters().faults_after_latch, 0);
    // A frame that comes back gets zero force from the latched rig.
    let a = r.lockstep(&host_frame(3, 18_750), TickTiming::Unknown);
    assert_eq!((a.force_n, a.drive_enabled), (0.0, false));
}

#[test]
fn a_reset_other_than_power_on_refuses_arm_until_acknowledged() {
    for cause in [
        ResetCause::Watchdog,
        ResetCause::Software,
        ResetCause::Pin,
        ResetCause::BrownOut,
        ResetCause::LowPower,
        ResetCause::Unknown,
    ] {
        let mut r = rig();
        r.set_reset_cause(cause);
        r.handle(&Command::Configure(sine(JumpKind::Single, 10.0, 0.0)))
            .unwrap();
        assert_eq!(
            r.handle(&Command::Arm),
            Err(CommandError::ResetNotAcknowledged { cause })
        );
        assert_eq!(r.state(), RigState::Idle, "{cause:?}: nothing armed");
        let s = r.status();
        assert_eq!((s.reset_cause, s.reset_acknowledged), (cause, false));
        r.handle(&Command::AcknowledgeReset).unwrap();
        assert!(r.status().reset_acknowledged);
        r.handle(&Command::Arm).unwrap();
        assert_eq!(r.state(), RigState::Armed);
    }
    let mut r = rig();
    r.set_reset_cause(ResetCause::PowerOn);
    r.handle(&Command::Configure(sine(JumpKind::Single, 10.0, 0.0)))
        .unwrap();
    r.handle(&Command::Arm).unwrap();
}

#[test]
fn a_missed_or_merged_tick_is_counted_and_latches_deadline_overrun() {
    let period = 16_800u32; // 168 MHz at 10 kHz
    let mut r: Rig<64> = Rig::new(RigConfig {
        tick_period_cycles: period,
        ..RigConfig::default()
    })
    .unwrap();
    // Regular ticks, with jitter, across the counter's wrap: fine.
    let mut t = u32::MAX - 5 * period;
    for k in 0..20u32 {
        r.note_tick_start(t.wrapping_add(k % 3 * 100));
        r.tick(&input(0));
        t = t.wrapping_add(period);
    }
    assert_eq!((r.fault(), r.counters().ticks_missed), (None, 0));
    // Two periods pass between tick starts: one tick never ran.
    t = t.wrapping_add(period);
    r.note_tick_start(t);
    assert_eq!(r.fault(), Some(FaultCode::DeadlineOverrun));
    assert_eq!(r.counters().ticks_missed, 1);
    // Off when the period is not known.
    let mut r = rig();
    r.note_tick_start(0);
    r.note_tick_start(1_000_000);
    assert_eq!((r.fault(), r.counters().ticks_missed), (None, 0));
}

#[test]
fn frames_dropped_by_the_glue_are_counted_in_the_status() {
    let mut r = rig();
    r.note_frames_dropped(3);
    r.note_frames_dropped(2);
    assert_eq!(r.status().counters.frames_dropped, 5);
}

#[test]
fn the_drive_calibration_is_checked_set_only_with_the_drive_off_and_reported() {
    let mut r = rig();
    let cal = DriveCalibration {
        zero_code: 2101,
        codes_per_newton: DriveCalibration::NOMINAL.codes_per_newton * 0.95,
    };
    r.handle(&Command::SetDriveCalibration(cal)).unwrap();
    assert_eq!(r.status().drive_calibration, cal);
    assert_eq!(r.drive_calibration().force_to_code(0.0), 2101);
    // Refused while the drive is enabled.
    r.handle(&Command::Configure(sine(JumpKind::Single, 10.0, 0.0)))
        .unwrap();
    r.handle(&Command::Arm).unwrap();
    assert!(matches!(
        r.handle(&Command::SetDriveCalibration(DriveCalibration::NOMINAL)),
        Err(CommandError::IllegalInState { .. })
    ));
    assert_eq!(r.status().drive_calibration, cal);
    // A calibration that fails its check changes nothing.
    r.handle(&Command::Abort).unwrap();
    let bad = DriveCalibration {
        zero_code: 3000,
        ..cal
    };
    assert!(matches!(
        r.handle(&Command::SetDriveCalibration(bad)),
        Err(CommandError::InvalidCalibration(_))
    ));
    assert_eq!(r.status().drive_calibration, cal);
}

#[test]
fn arming_away_from_the_start_approaches_without_a_step_and_start_waits_for_it() {
    // A board powers up with the carriage at its own zero, 18.75 mm from the sine's start.
    let mut plant = Plant::new(0.0);
    let mut r: Rig<64> = Rig::new(RigConfig {
        metres_per_count: plant.metres_per_count as f32,
        max_counts_per_tick: (1e-3 / plant.metres_per_count) as u32,
        ..RigConfig::default()
    })
    .unwrap();
    r.handle(&Command::Configure(sine(JumpKind::Single, 5.0, 0.0)))
        .unwrap();
    // Idle ticks: the encoder's position is known before the Arm.
    for _ in 0..10 {
        let out = r.tick(&input(plant.raw()));
        plant.step(out.force_n, 1e-4);
    }
    r.handle(&Command::Arm).unwrap();
    let start = r.hold.position_m;
    assert!((start.abs() - 0.01875).abs() < 1e-6, "{start}");
    let mut last_sp = 0.0f32;
    let mut started_at = None;
    for k in 0..20_000u32 {
        if k == 100 {
            // The host's Start arrives while the carriage is still on its way.
            r.handle(&Command::Start).unwrap();
        }
        let out = r.tick(&input(plant.raw()));
        if k < 5_000 {
            // Moving to the start: no camera frame counts as the rod's rest before the jump.
            assert!(
                !out.camera_trigger,
                "a camera frame during the approach at tick {k}"
            );
        }
        while let Some(s) = r.samples().pop() {
            if started_at.is_none() {
                assert!(
                    (s.commanded_position_m - last_sp).abs() < 2e-5,
                    "a setpoint step of {} m at tick {k}",
                    s.commanded_position_m - last_sp
                );
            }
            last_sp = s.commanded_position_m;
        }
        assert!(out.fault.is_none(), "fault {:?} at tick {k}", out.fault);
        assert!(out.force_n.abs() < 60.0, "{} N at tick {k}", out.force_n);
        if out.state == RigState::Running && started_at.is_none() {
            started_at = Some(k);
            // At rest at the start when the jump begins.
            assert!(
                (plant.p - start as f64).abs() < 2e-4,
                "{} m from the start",
                plant.p - start as f64
            );
        }
        plant.step(out.force_n, 1e-4);
        if k % 1000 == 0 {
            r.handle(&Command::Heartbeat).unwrap();
        }
    }
    let started_at = started_at.expect("the jump never started");
    // The half-cosine at 0.05 m/s peak takes pi d / 0.1 = 0.59 s, then 0.3 s of rest.
    assert!(
        (8_500..9_500).contains(&started_at),
        "started at tick {started_at}"
    );
}

/// A limit of zero turns its check off: the tick's deadline (0 cycles) and the corrupted-frame
/// burst (0 frames). Found by `cargo mutants` (`> 0` as `>= 0` passed every test).
#[test]
fn a_zero_limit_turns_its_check_off() {
    let mut r: Rig<64> = Rig::new(RigConfig {
        deadline_cycles: 0,
        corrupted_frame_limit: 0,
        ..RigConfig::default()
    })
    .unwrap();
    let out = r.tick(&TickInput {
        timing: TickTiming::Cycles(1_000_000),
        ..input(0)
    });
    assert_eq!(out.fault, None);
    for _ in 0..100 {
        r.note_frame_rejected();
    }
    assert_eq!(r.fault(), None);
    assert_eq!(r.counters().frames_rejected, 100);
}

/// The status the host reads: the jump configured, and the samples produced and dropped (a
/// host that stops reading loses the oldest, counted). Found by `cargo mutants` (each
/// replaced by a constant passed every test).
#[test]
fn the_configuration_and_the_sample_counts_are_reported() {
    let mut r = rig();
    assert!(r.jump_config().is_none());
    let jc = sine(JumpKind::Stutter, 10.0, 0.0);
    r.handle(&Command::Configure(jc)).unwrap();
    assert_eq!(r.jump_config(), Some(&jc));
    for _ in 0..100 {
        r.tick(&input(0));
    }
    let mut kept = 0u32;
    while r.samples().pop().is_some() {
        kept += 1;
    }
    let c = r.counters();
    assert_eq!(c.samples_produced, 100);
    assert!(kept > 0 && kept < 100, "{kept}");
    assert_eq!(c.samples_dropped, 100 - kept);
}

/// `GAINS_LOWERED` marks a delay's ticks when either gain is lowered, the position's alone or
/// the velocity's alone, and no tick outside the delay. Found by `cargo mutants` (the flag's
/// condition changed passed every test: the lowering above lowers both).
#[test]
fn gains_lowered_is_flagged_when_either_gain_is_lowered() {
    for (kp_factor, kd_factor) in [(0.5, 1.0), (1.0, 0.5)] {
        let mut jc = sine(JumpKind::DelayedStutter, 8.0, 0.75);
        jc.gain_lowering = Some(GainLowering {
            kp_factor,
            kd_factor,
            ramp_s: 0.05,
        });
        let mut plant = Plant::new(0.0);
        let mut r = armed_and_started(jc, &mut plant);
        let (_, samples) = run_to_end(&mut r, &mut plant, 20_000);
        let lowered = |s: &&SampleRecord| s.flags & flags::GAINS_LOWERED != 0;
        let delay: std::vec::Vec<&SampleRecord> = samples
            .iter()
            .filter(|s| s.flags & flags::DELAY != 0)
            .collect();
        assert!(
            delay[1000..6000].iter().all(&lowered),
            "kp {kp_factor}, kd {kd_factor}"
        );
        assert!(
            !samples
                .iter()
                .filter(|s| s.flags & flags::DELAY == 0)
                .any(|s| lowered(&s)),
            "flagged outside the delay: kp {kp_factor}, kd {kd_factor}"
        );
    }
}

/// A saturated drive and a held integrator reach the tick's sample record, and neither flag is
/// set while the loop is within its limits. Found by `cargo mutants` (both flags' `|=` made
/// `&=` passed every test).
#[test]
fn saturation_and_a_held_integrator_are_flagged_in_the_records() {
    let mut jc = sine(JumpKind::Stutter, 10.0, 0.0);
    // 2 mm of error asks 400 N of a 300 N drive; the integrator winds with it.
    jc.gains.kp_n_per_m = 200_000.0;
    jc.gains.ki_n_per_m_s = 1_000.0;
    let (mut r, raw) = armed_with(jc);
    let mut flags_at = |raw: u32| {
        let out = fresh_tick(&mut r, input(raw));
        assert_eq!(out.fault, None);
        r.samples().pop().expect("a record every tick").flags
    };
    let both = flags::SATURATED | flags::INTEGRATOR_HELD;
    assert_eq!(flags_at(raw) & both, 0, "on the setpoint");
    // Down 2 mm in steps the encoder check takes.
    for k in 1..=4 {
        flags_at(raw - 500 * k);
    }
    assert_eq!(
        flags_at(raw - 2_000) & both,
        both,
        "2 mm below the setpoint"
    );
}

/// New gains reach the loop at once while it holds a position (Armed, Done): the force for the
/// same error changes with them. Found by `cargo mutants` (the state check's three mutants
/// passed every test).
#[test]
fn gains_set_while_armed_or_done_reach_the_loop_at_once() {
    let stiffer = |jc: &JumpConfig| Gains {
        kp_n_per_m: 2.0 * jc.gains.kp_n_per_m,
        ..jc.gains
    };
    // Armed: 1 mm below the start.
    let jc = sine(JumpKind::Stutter, 10.0, 0.0);
    let (mut r, raw) = armed_with(jc);
    let off = raw - 1_000;
    r.tick(&input(raw - 500));
    // Held off until the velocity estimate has settled: kp's 11 N a millimetre alone.
    let steady = (0..500)
        .map(|_| r.tick(&input(off)).force_n)
        .last()
        .unwrap();
    r.handle(&Command::SetGains(stiffer(&jc))).unwrap();
    let after = r.tick(&input(off)).force_n;
    assert!(
        after > steady + 5.0,
        "Armed: {steady} N, then {after} N with kp doubled"
    );
    // Done: the same off its hold.
    let mut plant = Plant::new(0.0);
    let mut r = armed_and_started(jc, &mut plant);
    run_to_end(&mut r, &mut plant, 20_000);
    assert_eq!(r.state(), RigState::Done);
    let hold = (r.hold.position_m as f64 / plant.metres_per_count).round() as u32;
    r.tick(&input(hold - 500));
    let steady = (0..500)
        .map(|_| r.tick(&input(hold - 1_000)).force_n)
        .last()
        .unwrap();
    r.handle(&Command::SetGains(stiffer(&jc))).unwrap();
    let after = r.tick(&input(hold - 1_000)).force_n;
    assert!(
        after > steady + 5.0,
        "Done: {steady} N, then {after} N with kp doubled"
    );
}
