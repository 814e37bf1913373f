//! docs/bringup.md's steps that need no scope, run as written against the F407 binary on the
//! virtual board, the host's commands and the board's replies over USB.

mod common;

use std::collections::BTreeMap;

use common::{MS, rig_messages, robot_at_single_start, send, sine, single_sine};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_core::{Command, Reply, ResetCause, RigMessage};
use sandjumper_virtual_f407::run::{Action, NoHost, RunConfig, run};

/// Every reply the board sent, by command id.
fn replies(bytes: &[u8]) -> BTreeMap<u16, String> {
    let mut out = BTreeMap::new();
    for m in rig_messages(bytes) {
        if let RigMessage::Reply { id, result } = m {
            let text = match result {
                Ok(Reply::Ack) => "Ack".to_string(),
                Ok(Reply::Status(s)) => format!("Status {:?} {:?}", s.state, s.reset_cause),
                Err(why) => format!("Rejected {why:?}"),
            };
            out.insert(id, text);
        }
    }
    out
}

/// Step 9: the reset button while Idle; `rig status` shows the pin reset and `Arm` refused until
/// `rig acknowledge-reset`; then it arms.
#[test]
fn step_9_a_reset_needs_an_acknowledgement_before_arm() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(900 * MS);
    cfg.robot = Some(robot_at_single_start());
    let jc = single_sine();
    // The board re-enumerates after the reset (~150 ms), then the host talks to it again.
    cfg.actions = vec![
        (200 * MS, Action::ResetButton),
        (600 * MS, send(1, Command::StatusQuery)),
        (610 * MS, send(2, Command::Configure(jc))),
        (620 * MS, send(3, Command::Arm)),
        (630 * MS, send(4, Command::AcknowledgeReset)),
        (640 * MS, send(5, Command::Arm)),
        (650 * MS, send(6, Command::Heartbeat)),
    ];
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let got = replies(&host.received);
    assert!(
        got.get(&1)
            .is_some_and(|s| s.contains("Idle") && s.contains(&format!("{:?}", ResetCause::Pin))),
        "status after the reset button: {got:?}; resets {:?}",
        r.resets
    );
    assert!(
        got.get(&3).is_some_and(|s| s.starts_with("Rejected")),
        "Arm before the acknowledgement: {got:?}"
    );
    assert_eq!(got.get(&4).map(String::as_str), Some("Ack"), "{got:?}");
    assert_eq!(
        got.get(&5).map(String::as_str),
        Some("Ack"),
        "Arm after the acknowledgement: {got:?}"
    );
}

/// Step 6: with the drive disabled the firmware writes the calibration's zero code, so the
/// multimeter on the force input reads what `rig calibrate-drive --zero-code` sent.
#[test]
fn step_6_the_drive_disabled_holds_the_calibrations_zero_code() {
    use sandjumper_core::drive_calibration::DriveCalibration;
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(300 * MS);
    cfg.trace_every = 1;
    let cal = DriveCalibration {
        zero_code: 2080,
        codes_per_newton: 6.7,
    };
    cfg.actions = vec![(200 * MS, send(1, Command::SetDriveCalibration(cal)))];
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    assert_eq!(
        replies(&host.received).get(&1).map(String::as_str),
        Some("Ack")
    );
    let before = common::at(&r, 190 * MS).out.force_dac_v;
    let after = r.last.expect("ran").out.force_dac_v;
    assert!(
        (before - 2048.0 * 3.3 / 4095.0).abs() < 1e-6,
        "nominal zero before: {before} V"
    );
    assert!(
        (after - 2080.0 * 3.3 / 4095.0).abs() < 1e-6,
        "the calibration's zero after: {after} V"
    );
}

/// Step 7.1: the drive's power stage off, a jump armed: the controller drives a carriage that
/// does not follow and stops on a tracking-error fault within milliseconds, force to zero.
#[test]
fn step_7_1_an_unpowered_drive_ends_on_a_tracking_error() {
    use sandjumper_core::FaultCode;
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(400 * MS);
    cfg.trace_every = 1;
    cfg.drive_powered = false;
    cfg.robot = Some(robot_at_single_start());
    let jc = single_sine();
    cfg.actions = vec![
        (190 * MS, send(1, Command::Configure(jc))),
        (200 * MS, send(2, Command::Arm)),
        (210 * MS, send(3, Command::Start)),
    ];
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let faults: Vec<_> = rig_messages(&host.received)
        .into_iter()
        .filter_map(|m| match m {
            RigMessage::Fault(f) => Some(f),
            _ => None,
        })
        .collect();
    let first = faults
        .first()
        .unwrap_or_else(|| panic!("no fault reported; log {:?}", r.log));
    assert_eq!(first.code, FaultCode::TrackingError, "{faults:?}");
    // Off after it was on: the Arm's enable, then the fault's disable.
    let on = r
        .trace
        .iter()
        .find(|row| row.t_ns >= 200 * MS && row.out.drive_enable)
        .expect("the drive was never enabled");
    let off = r
        .trace
        .iter()
        .find(|row| row.t_ns > on.t_ns && !row.out.drive_enable)
        .expect("the drive never went off");
    assert!(
        off.t_ns < 300 * MS,
        "the drive stayed enabled until {} ns",
        off.t_ns
    );
    assert!((off.out.force_dac_v - 1.65).abs() < 1e-3, "{off:?}");
}

/// Step 3: `rig status` a second apart: `tick` advances by 10,000, `max tick` stays below the
/// 13,440-cycle budget and `ticks missed` at 0, with a configuration sent in between (a command
/// runs in the tick that receives it).
#[test]
fn step_3_the_tick_advances_10000_a_second_within_its_budget() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(1_400 * MS);
    let jc = sine(JumpKind::DelayedStutter, 10.0, 0.1);
    cfg.actions = vec![
        (300 * MS, send(1, Command::StatusQuery)),
        (800 * MS, send(2, Command::Configure(jc))),
        (1_300 * MS, send(3, Command::StatusQuery)),
    ];
    let (_, host) = run(cfg, NoHost::default()).expect("the run");
    let mut status = BTreeMap::new();
    for m in rig_messages(&host.received) {
        if let RigMessage::Reply {
            id,
            result: Ok(Reply::Status(s)),
        } = m
        {
            status.insert(id, s);
        }
    }
    let (a, b) = (
        status.get(&1).expect("the first status"),
        status.get(&3).expect("the second status"),
    );
    let advanced = b.tick.wrapping_sub(a.tick);
    assert!(
        (9_999..=10_001).contains(&advanced),
        "the tick advanced {advanced} in a second"
    );
    assert!(
        b.counters.max_tick_cycles < 13_440,
        "max tick {} cycles",
        b.counters.max_tick_cycles
    );
    assert_eq!(b.counters.ticks_missed, 0);
}
