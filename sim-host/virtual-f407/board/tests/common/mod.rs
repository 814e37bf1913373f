//! Shared by the tests on the F407 binary: where the ELF is, and the skip rule.
#![allow(dead_code)]

use std::path::PathBuf;

/// The F407 release ELF (`SANDJUMPER_F407_ELF`, or the main workspace's release build), or
/// `None` with a message (a panic under `CI`: there the ELF must have been built).
pub fn firmware_elf() -> Option<PathBuf> {
    let path = std::env::var_os("SANDJUMPER_F407_ELF")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../target/thumbv7em-none-eabihf/release/sandjumper-firmware")
        });
    if path.is_file() {
        return Some(path);
    }
    let msg = format!(
        "skipped: no F407 firmware at {} (build it with `cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release` in the main workspace)",
        path.display()
    );
    if std::env::var_os("CI").is_some() {
        panic!("{msg}; under CI the tests on the F407 binary must run");
    }
    eprintln!("{msg}");
    None
}

use sandjumper_core::config::{JumpConfig, TrajectorySpec};
use sandjumper_core::protocol::{FrameDecoder, encode_frame_vec};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_core::{Command, HostMessage, RigMessage};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_virtual_f407::rig::Robot;
use sandjumper_virtual_f407::run::{Action, RunReport, TraceRow};

/// A millisecond, ns.
pub const MS: u64 = 1_000_000;
/// The sine's amplitude, m (the robot's stroke amplitude).
pub const AMPLITUDE_M: f64 = 0.01875;

/// The COBS frame of the host's `command` with `id`.
pub fn command_frame(id: u16, command: Command) -> Vec<u8> {
    encode_frame_vec(&HostMessage::Command { id, command })
        .expect("a frame")
        .to_vec()
}

/// The host sends `command` with `id`.
pub fn send(id: u16, command: Command) -> Action {
    Action::HostBytes(command_frame(id, command))
}

/// Every message the board sent in `bytes`, decoded in order (undecodable frames skipped).
pub fn rig_messages(bytes: &[u8]) -> Vec<RigMessage> {
    let mut decoder = FrameDecoder::new();
    bytes
        .iter()
        .filter_map(|&b| decoder.push::<RigMessage>(b).and_then(Result::ok))
        .collect()
}

/// A one-cycle sine of the robot's amplitude.
pub fn sine(kind: JumpKind, freq_hz: f64, tau_s: f64) -> JumpConfig {
    JumpConfig::new(TrajectorySpec::Sine {
        kind,
        amplitude_m: AMPLITUDE_M,
        freq_hz,
        tau_s,
    })
}

/// The single 5 Hz sine the fault tests arm.
pub fn single_sine() -> JumpConfig {
    sine(JumpKind::Single, 5.0, 0.0)
}

/// The robot on hard ground at the single sine's start (-A), as the lockstep rigs start it:
/// no approach after Arm.
pub fn robot_at_single_start() -> Robot {
    let params = Params::preset(0.57).expect("preset");
    Robot::new(&params, ModelName::Hard, -AMPLITUDE_M).expect("robot")
}

/// The host configures [`single_sine`] 10 ms before `arm_at`, arms at `arm_at`, then sends a
/// heartbeat every 20 ms until `heartbeats_until` (the command watchdog stays fed).
pub fn armed_actions(arm_at: u64, heartbeats_until: u64) -> Vec<(u64, Action)> {
    let mut actions = vec![
        (arm_at - 10 * MS, send(1, Command::Configure(single_sine()))),
        (arm_at, send(2, Command::Arm)),
    ];
    actions.extend(heartbeats(arm_at + 20 * MS, heartbeats_until, 3));
    actions
}

/// The host's heartbeats every 20 ms from `from` until `until`, ids from `first_id`.
pub fn heartbeats(from: u64, until: u64, first_id: u16) -> Vec<(u64, Action)> {
    (0u16..)
        .map(|k| (from + u64::from(k) * 20 * MS, first_id + k))
        .take_while(|&(t, _)| t < until)
        .map(|(t, id)| (t, send(id, Command::Heartbeat)))
        .collect()
}

/// The host switches the bed apparatus on at 200-210 ms: blower 5 V, shaker half duty, lift up.
pub fn bed_switched_on() -> Vec<(u64, Action)> {
    use sandjumper_core::bed::{BedCommand, LiftMove};
    vec![
        (
            200 * MS,
            send(1, Command::Bed(BedCommand::Blower { volts: 5.0 })),
        ),
        (
            205 * MS,
            send(2, Command::Bed(BedCommand::Shaker { duty: 0.5 })),
        ),
        (
            210 * MS,
            send(3, Command::Bed(BedCommand::Lift(LiftMove::Up))),
        ),
    ]
}

/// The trace row at virtual time `t` (the first at or after it).
pub fn at(r: &RunReport, t: u64) -> TraceRow {
    *r.trace
        .iter()
        .find(|row| row.t_ns >= t)
        .expect("a trace row")
}
