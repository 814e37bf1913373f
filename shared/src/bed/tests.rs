use super::*;
use crate::command::{Command, CommandError};
use crate::config::{JumpConfig, RigConfig, TrajectorySpec};
use crate::emergency_stop::EmergencyStopError;
use crate::fault::FaultCode;
use crate::rig::{Rig, RigState, TickInput, TickTiming};
use crate::trajectory::JumpKind;

/// Lift down, nothing pressed.
const READY: BedInputs = BedInputs {
    lift_up_limit: false,
    lift_down_limit: true,
    emergency_stop: false,
    height_raw: 2048,
};

fn input() -> TickInput {
    TickInput {
        encoder_raw: 18_750, // p = +A, a stutter's start
        current_a: None,
        timing: TickTiming::Unknown,
    }
}

fn configured_rig() -> Rig<64> {
    configured_rig_with(RigConfig::default())
}

/// A rig with `config` and a 10 Hz stutter configured.
fn configured_rig_with(config: RigConfig) -> Rig<64> {
    let mut r = Rig::new(config).unwrap();
    r.handle(&Command::Configure(JumpConfig::new(TrajectorySpec::Sine {
        kind: JumpKind::Stutter,
        amplitude_m: 0.01875,
        freq_hz: 10.0,
        tau_s: 0.0,
    })))
    .unwrap();
    r
}

fn tick(r: &mut Rig<64>, inputs: BedInputs) -> crate::rig::TickOutput {
    r.set_bed_inputs(inputs);
    r.tick(&input())
}

fn interlock(r: Result<crate::command::Reply, CommandError>) -> BedError {
    match r {
        Err(CommandError::Interlock(e)) => e,
        other => panic!("expected an interlock refusal, got {other:?}"),
    }
}

#[test]
fn no_arm_unless_the_lift_is_down_and_blower_and_shaker_are_off() {
    let mut r = configured_rig();
    // Lift up: refused.
    tick(
        &mut r,
        BedInputs {
            lift_down_limit: false,
            lift_up_limit: true,
            ..READY
        },
    );
    assert_eq!(interlock(r.handle(&Command::Arm)), BedError::LiftNotDown);
    // Lift down, blower on: refused; off: still the shaker.
    tick(&mut r, READY);
    r.handle(&Command::Bed(BedCommand::Blower { volts: 6.0 }))
        .unwrap();
    r.handle(&Command::Bed(BedCommand::Shaker { duty: 0.5 }))
        .unwrap();
    assert_eq!(interlock(r.handle(&Command::Arm)), BedError::BlowerOn);
    r.handle(&Command::Bed(BedCommand::Blower { volts: 0.0 }))
        .unwrap();
    assert_eq!(interlock(r.handle(&Command::Arm)), BedError::ShakerOn);
    r.handle(&Command::Bed(BedCommand::Shaker { duty: 0.0 }))
        .unwrap();
    assert_eq!(r.state(), RigState::Idle, "refusals change nothing");
    r.handle(&Command::Arm).unwrap();
    assert_eq!(r.state(), RigState::Armed);
}

#[test]
fn a_board_without_the_apparatus_arms_as_before() {
    let mut r = configured_rig();
    r.tick(&input());
    assert!(!r.bed().present());
    r.handle(&Command::Arm).unwrap();
    assert_eq!(r.status().bed, BedStatus::default());
}

#[test]
fn the_lift_cannot_move_and_nothing_switches_on_while_a_jump_is_armed_or_running() {
    let mut r = configured_rig();
    tick(&mut r, READY);
    r.handle(&Command::Arm).unwrap();
    for cmd in [
        BedCommand::Lift(LiftMove::Up),
        BedCommand::Blower { volts: 1.0 },
        BedCommand::Shaker { duty: 0.1 },
    ] {
        assert_eq!(
            interlock(r.handle(&Command::Bed(cmd))),
            BedError::JumpActive
        );
    }
    tick(&mut r, READY);
    r.handle(&Command::Start).unwrap();
    let out = tick(&mut r, READY);
    assert_eq!(out.state, RigState::Running);
    assert_eq!(
        interlock(r.handle(&Command::Bed(BedCommand::Lift(LiftMove::Up)))),
        BedError::JumpActive
    );
    assert!(!out.bed.lift_enable);
    // Switching off is always allowed.
    r.handle(&Command::Bed(BedCommand::Lift(LiftMove::Stop)))
        .unwrap();
    r.handle(&Command::Bed(BedCommand::Blower { volts: 0.0 }))
        .unwrap();
    // After the jump (Abort: Idle) the lift may move again.
    r.handle(&Command::Abort).unwrap();
    r.handle(&Command::Bed(BedCommand::Lift(LiftMove::Up)))
        .unwrap();
    let out = tick(&mut r, READY);
    assert!(out.bed.lift_enable && out.bed.lift_up);
}

#[test]
fn the_emergency_stop_turns_everything_off_latches_and_needs_release_to_clear() {
    let mut r = configured_rig();
    tick(&mut r, READY);
    r.handle(&Command::Bed(BedCommand::Blower { volts: 8.0 }))
        .unwrap();
    r.handle(&Command::Bed(BedCommand::Shaker { duty: 1.0 }))
        .unwrap();
    r.handle(&Command::Bed(BedCommand::Lift(LiftMove::Up)))
        .unwrap();
    let out = tick(&mut r, READY);
    assert_eq!(out.bed.blower_v, 8.0);
    assert!(out.bed.lift_enable);
    let pressed = BedInputs {
        emergency_stop: true,
        ..READY
    };
    let out = tick(&mut r, pressed);
    assert_eq!(out.fault, Some(FaultCode::EmergencyStop));
    assert_eq!(out.bed, BedOutputs::default(), "blower, shaker, lift off");
    assert!(!out.drive_enabled && out.force_n == 0.0);
    // Nothing switches on while it is pressed, and the fault cannot be cleared.
    assert_eq!(
        interlock(r.handle(&Command::Bed(BedCommand::Blower { volts: 1.0 }))),
        BedError::EmergencyStop
    );
    assert_eq!(
        interlock(r.handle(&Command::ClearFault)),
        BedError::EmergencyStop
    );
    // Released: still latched (tripped) until the fault is cleared.
    let out = tick(&mut r, READY);
    assert_eq!(out.bed, BedOutputs::default());
    assert_eq!(
        interlock(r.handle(&Command::Bed(BedCommand::Shaker { duty: 0.2 }))),
        BedError::Tripped
    );
    r.handle(&Command::ClearFault).unwrap();
    r.handle(&Command::Bed(BedCommand::Shaker { duty: 0.2 }))
        .unwrap();
    let out = tick(&mut r, READY);
    assert_eq!(out.bed.shaker_duty, 0.2);
    assert_eq!(out.fault, None);
}

#[test]
fn any_fault_turns_the_apparatus_off() {
    let mut r = configured_rig();
    tick(&mut r, READY);
    r.handle(&Command::Bed(BedCommand::Blower { volts: 5.0 }))
        .unwrap();
    r.raise_fault(FaultCode::LinkLost);
    let out = tick(&mut r, READY);
    assert_eq!(out.bed, BedOutputs::default());
    assert!(r.status().bed.tripped);
    r.handle(&Command::ClearFault).unwrap();
    assert!(!r.status().bed.tripped);
}

#[test]
fn the_lift_stops_at_its_limit_and_values_out_of_range_are_refused() {
    let mut b = BedApparatus::new();
    b.read_inputs(READY);
    assert_eq!(
        b.command(&BedCommand::Lift(LiftMove::Down), false),
        Err(BedError::LiftAtLimit)
    );
    b.command(&BedCommand::Lift(LiftMove::Up), false).unwrap();
    assert!(b.update(false).lift_enable);
    b.read_inputs(BedInputs {
        lift_down_limit: false,
        lift_up_limit: true,
        ..READY
    });
    let out = b.update(false);
    assert!(!out.lift_enable, "stopped at the upper limit");
    for cmd in [
        BedCommand::Blower { volts: 10.5 },
        BedCommand::Blower { volts: -1.0 },
        BedCommand::Blower { volts: f32::NAN },
        BedCommand::Shaker { duty: 1.5 },
    ] {
        assert_eq!(b.command(&cmd, false), Err(BedError::OutOfRange), "{cmd:?}");
    }
    assert_eq!(b.outputs(), BedOutputs::default());
}

fn estop_rig() -> Rig<64> {
    configured_rig_with(RigConfig {
        emergency_stop_input: true,
        ..RigConfig::default()
    })
}

fn estop_refusal(r: Result<crate::command::Reply, CommandError>) -> EmergencyStopError {
    match r {
        Err(CommandError::EmergencyStop(e)) => e,
        other => panic!("expected an emergency-stop refusal, got {other:?}"),
    }
}

/// Issue 48 item 1: a board with an e-stop input whose loop has never read closed (nothing
/// wired, or the stop pressed from power-up) stays Idle with no fault, and refuses `Arm` and
/// anything that switches the bed on, whatever the apparatus reports.
#[test]
fn a_loop_that_never_read_closed_refuses_arm_and_the_bed_without_a_fault() {
    for apparatus in [None, Some(READY)] {
        let mut r = estop_rig();
        assert_eq!(
            estop_refusal(r.handle(&Command::Arm)),
            EmergencyStopError::NeverClosed,
            "before the first tick"
        );
        for _ in 0..100 {
            if let Some(b) = apparatus {
                r.set_bed_inputs(b);
            }
            r.set_emergency_stop_loop(true);
            let out = r.tick(&input());
            assert_eq!(out.state, RigState::Idle, "never closed: no fault latched");
        }
        assert_eq!(
            estop_refusal(r.handle(&Command::Arm)),
            EmergencyStopError::NeverClosed
        );
        assert_eq!(
            estop_refusal(r.handle(&Command::Bed(BedCommand::Blower { volts: 1.0 }))),
            EmergencyStopError::NeverClosed
        );
        // Switching off is always allowed.
        r.handle(&Command::Bed(BedCommand::Blower { volts: 0.0 }))
            .unwrap();
        let s = r.status();
        assert!(s.emergency_stop.fitted && s.emergency_stop.open);
        assert!(!s.emergency_stop.closed_since_reset);
        assert!(s.emergency_stop_pressed());
        // Closed: Arm goes through.
        if let Some(b) = apparatus {
            r.set_bed_inputs(b);
        }
        r.set_emergency_stop_loop(false);
        r.tick(&input());
        r.handle(&Command::Arm).unwrap();
        assert_eq!(r.state(), RigState::Armed);
    }
}

/// Once it has read closed, the loop opening latches `EmergencyStop` on that tick (force zero,
/// the bed tripped), and the fault cannot be cleared while it stays open.
#[test]
fn the_loop_opening_after_it_closed_latches_the_emergency_stop() {
    let mut r = estop_rig();
    r.set_emergency_stop_loop(false);
    tick(&mut r, READY);
    r.handle(&Command::Bed(BedCommand::Blower { volts: 0.0 }))
        .unwrap();
    r.handle(&Command::Arm).unwrap();
    r.set_emergency_stop_loop(false);
    let out = tick(&mut r, READY);
    assert!(out.drive_enabled);
    r.set_emergency_stop_loop(true);
    let out = tick(&mut r, READY);
    assert_eq!(out.fault, Some(FaultCode::EmergencyStop));
    assert!(!out.drive_enabled && out.force_n == 0.0);
    assert!(r.bed().tripped());
    assert_eq!(
        estop_refusal(r.handle(&Command::ClearFault)),
        EmergencyStopError::Open
    );
    r.set_emergency_stop_loop(false);
    tick(&mut r, READY);
    r.handle(&Command::ClearFault).unwrap();
    assert_eq!(r.state(), RigState::Idle);
}

/// A rig without the input (sil, pil, QEMU) ignores the loop: today's behaviour.
#[test]
fn a_board_without_the_loop_ignores_it() {
    let mut r = configured_rig();
    r.set_emergency_stop_loop(true);
    r.tick(&input());
    r.handle(&Command::Arm).unwrap();
    assert!(!r.status().emergency_stop.fitted);
}

/// Issue 48 item 2: the lift, the shaker and the blower have a host watchdog in every state.
/// Idle with all three on, a silent host latches `BedWatchdog` one tick past the timeout and
/// everything goes off on that tick; heartbeats keep it running; with nothing on, silence is
/// no fault.
#[test]
fn a_silent_host_turns_the_bed_off_after_its_watchdog_in_idle() {
    let config = RigConfig::default();
    let limit = config.bed_watchdog_ticks();
    assert_eq!(limit, 5_000, "500 ms at 10 kHz");
    let mut r = configured_rig();
    // Nothing on: an idle board may be left alone.
    for _ in 0..2 * limit {
        assert_eq!(tick(&mut r, READY).fault, None);
    }
    for c in [
        BedCommand::Blower { volts: 5.0 },
        BedCommand::Shaker { duty: 0.5 },
        BedCommand::Lift(LiftMove::Up),
    ] {
        r.handle(&Command::Bed(c)).unwrap();
    }
    // Fed: runs on.
    for k in 0..2 * limit {
        if k % 1000 == 0 {
            r.handle(&Command::Heartbeat).unwrap();
        }
        let out = tick(&mut r, READY);
        assert!(out.fault.is_none() && out.bed.lift_enable && out.bed.blower_v == 5.0);
    }
    r.handle(&Command::Heartbeat).unwrap();
    for _ in 0..limit {
        let out = tick(&mut r, READY);
        assert!(
            out.fault.is_none() && out.bed.shaker_duty == 0.5,
            "too early"
        );
    }
    let out = tick(&mut r, READY);
    assert_eq!(out.fault, Some(FaultCode::BedWatchdog));
    assert_eq!(
        out.bed,
        BedOutputs::default(),
        "all off on the tick it latches"
    );
    assert_eq!(out.state, RigState::Faulted);
    assert!(r.bed().tripped());
    r.handle(&Command::ClearFault).unwrap();
    assert_eq!(tick(&mut r, READY).bed, BedOutputs::default());
}

/// In Done (the drive holding the jump's end, the bed may be switched on) both watchdogs run;
/// the bed's is the one that latches when it is the shorter.
#[test]
fn the_bed_watchdog_runs_while_the_drive_holds_after_a_jump() {
    let mut r = configured_rig_with(RigConfig {
        bed_watchdog_ms: 100,
        ..RigConfig::default()
    });
    tick(&mut r, READY);
    while r.samples().pop().is_some() {}
    r.handle(&Command::Arm).unwrap();
    r.handle(&Command::Start).unwrap();
    // The carriage follows the setpoint exactly (a perfect plant).
    let mut p = 18_750u32;
    let mut n = 0;
    while r.state() != RigState::Done {
        r.set_bed_inputs(READY);
        let out = r.tick(&TickInput {
            encoder_raw: p,
            current_a: None,
            timing: TickTiming::Unknown,
        });
        while let Some(s) = r.samples().pop() {
            p = (s.commanded_position_m * 1e6).round() as i32 as u32;
        }
        assert!(out.fault.is_none(), "{out:?}");
        n += 1;
        if n % 1000 == 0 {
            r.handle(&Command::Heartbeat).unwrap();
        }
        assert!(n < 100_000);
    }
    r.handle(&Command::Bed(BedCommand::Blower { volts: 2.0 }))
        .unwrap();
    let mut latched = None;
    for _ in 0..2_000 {
        r.set_bed_inputs(READY);
        let out = r.tick(&TickInput {
            encoder_raw: p,
            current_a: None,
            timing: TickTiming::Unknown,
        });
        if out.fault.is_some() {
            latched = out.fault;
            assert_eq!(out.bed, BedOutputs::default());
            break;
        }
    }
    assert_eq!(latched, Some(FaultCode::BedWatchdog));
}

/// Each actuator alone keeps the bed watchdog armed: the shaker left running after the lift
/// stopped at its limit, the blower alone, the lift alone.
#[test]
fn each_actuator_alone_is_watched() {
    let limit = RigConfig::default().bed_watchdog_ticks();
    for cmd in [
        BedCommand::Shaker { duty: 0.3 },
        BedCommand::Blower { volts: 2.0 },
        BedCommand::Lift(LiftMove::Up),
    ] {
        let mut r = configured_rig();
        tick(&mut r, READY);
        r.handle(&Command::Bed(cmd)).unwrap();
        let mut latched_at = None;
        for k in 0..=limit + 1 {
            if tick(&mut r, READY).fault == Some(FaultCode::BedWatchdog) {
                latched_at = Some(k);
                break;
            }
        }
        assert_eq!(latched_at, Some(limit), "{cmd:?} alone");
        assert_eq!(r.bed().outputs(), BedOutputs::default(), "{cmd:?} alone");
    }
}

/// What the apparatus reports of itself (the board's status, the rig's checks and the firmware's
/// outputs read these): absent until its inputs are read, then the inputs as read; the outputs
/// as commanded; tripped, everything off, until cleared. Found by `cargo mutants` (each accessor
/// replaced by a constant passed the core's tests).
#[test]
fn the_apparatus_reports_what_it_read_what_it_drives_and_its_trip() {
    let mut bed = BedApparatus::new();
    assert!(!bed.present() && !bed.tripped());
    assert_eq!(bed.outputs(), BedOutputs::default());
    let lifted = BedInputs {
        lift_down_limit: false,
        height_raw: 1234,
        ..READY
    };
    bed.read_inputs(lifted);
    assert!(bed.present());
    assert_eq!(bed.inputs(), lifted);
    bed.command(&BedCommand::Blower { volts: 5.0 }, false)
        .unwrap();
    bed.command(&BedCommand::Lift(LiftMove::Down), false)
        .unwrap();
    let out = bed.outputs();
    assert_eq!(out.blower_v, 5.0);
    assert!(out.lift_enable && !out.lift_up, "{out:?}");
    assert!(!bed.tripped());
    bed.trip();
    assert!(bed.tripped());
    assert_eq!(bed.outputs(), BedOutputs::default(), "everything off");
    bed.clear().unwrap();
    assert!(!bed.tripped());
}

/// Each refusal says what it is, in its own words (the host prints them).
#[test]
fn each_bed_refusal_has_its_own_message() {
    extern crate std;
    use std::string::{String, ToString};
    use std::vec::Vec;
    let all = [
        BedError::JumpActive,
        BedError::Tripped,
        BedError::EmergencyStop,
        BedError::OutOfRange,
        BedError::LiftNotDown,
        BedError::BlowerOn,
        BedError::ShakerOn,
        BedError::LiftAtLimit,
        BedError::Absent,
    ];
    let texts: Vec<String> = all.iter().map(ToString::to_string).collect();
    for (e, text) in all.iter().zip(&texts) {
        assert!(text.len() > 10, "{e:?}: {text:?}");
    }
    let mut distinct = texts.clone();
    distinct.sort();
    distinct.dedup();
    assert_eq!(distinct.len(), all.len(), "{texts:?}");
    assert!(texts[1].contains("tripped"), "{}", texts[1]);
}
