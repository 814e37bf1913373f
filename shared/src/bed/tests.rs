use super::*;
use crate::command::{Command, CommandError};
use crate::config::{JumpConfig, RigConfig, TrajectorySpec};
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
    let mut r = Rig::new(RigConfig::default()).unwrap();
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
