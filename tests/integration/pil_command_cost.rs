//! On the rig a host command runs inside the control tick that receives it, so no command may
//! cost more than the tick's budget. The emulated firmware (QEMU `-icount`) counts each
//! command's instructions as that tick's cost, as the F407 counts its cycles; the next sensor
//! frame reports it to the core (`max_tick_cycles`).
//!
//! The case the bench review found: `ReplayCommit` of a full 4,096-sample table computed a
//! CRC over 16 KiB inside the tick (~35-40 cycles per sample, several ticks' budget), so the
//! next tick latched `DeadlineOverrun` and `rig replay` could not run. The table now keeps its
//! checksum as chunks arrive.
//!
//! Needs QEMU and the firmware toolchain (skipped with a message without them, except in CI).

use std::path::Path;

use sandjumper_core::command::replay_upload;
use sandjumper_core::replay::REPLAY_CAPACITY;
use sandjumper_core::{Command, Reply, SensorFrame, Status};
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::link::RigLink;
use sandjumper_rig::hil::pil::{self, PilConfig};

/// The F407's tick budget: 80 % of a 10 kHz period at 168 MHz, cycles
/// (`firmware/src/board/f407.rs`, `TICK_BUDGET_CYCLES`).
const F407_TICK_BUDGET_CYCLES: u32 = 13_440;
/// Instructions allowed per command: half the cycle budget, since a Cortex-M4 running from
/// flash with 5 wait states takes more than one cycle per instruction.
const COMMAND_LIMIT_INSTRUCTIONS: u32 = F407_TICK_BUDGET_CYCLES / 2;

/// The emulated firmware, built once (None, saying why, when the test cannot run here).
fn emulated_elf() -> Option<&'static Path> {
    if emulated_firmware::test_prerequisites("the PIL command-cost test")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return None;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Some(emulated_firmware::build_once(root).unwrap_or_else(|e| panic!("{e}")))
}

/// `command` (`what` in messages), then sensor frame `frame`, which reports the command's tick
/// to the core, then the core's status.
fn status_after(link: &mut dyn RigLink, command: &Command, frame: u32, what: &str) -> Status {
    link.command(command)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    link.exchange(&SensorFrame {
        frame,
        encoder_count: 0,
        current_a: None,
        overrun: false,
        bed: None,
    })
    .expect("lockstep answer");
    let Reply::Status(status) = link.command(&Command::StatusQuery).expect("status") else {
        panic!("StatusQuery answered without a status");
    };
    status
}

#[test]
fn a_full_replay_upload_and_commit_fit_the_tick_budget() {
    let Some(elf) = emulated_elf() else {
        return;
    };
    let mut link = pil::start(&PilConfig::new(elf)).expect("QEMU starts and answers");
    let samples: Vec<f32> = (0..REPLAY_CAPACITY)
        .map(|k| 0.01 * (k as f32 * 0.002).sin())
        .collect();
    let mut worst = (0u32, String::new());
    for (frame, command) in (1u32..).zip(replay_upload(&samples, 10)) {
        let what = format!("{:?}", command.kind());
        let status = status_after(&mut link, &command, frame, &what);
        assert_eq!(status.fault, None, "after {what}: {status:?}");
        if status.counters.max_tick_cycles > worst.0 {
            worst = (status.counters.max_tick_cycles, what);
        }
    }
    eprintln!(
        "costliest command of a {}-sample upload: {} ({} instructions)",
        samples.len(),
        worst.1,
        worst.0
    );
    assert!(
        worst.0 <= COMMAND_LIMIT_INSTRUCTIONS,
        "{} took {} instructions (limit {COMMAND_LIMIT_INSTRUCTIONS})",
        worst.1,
        worst.0
    );
    let report = link.finish().expect("the firmware exits");
    assert_eq!(report.exit_code, Some(0));
}

/// The costliest command a rig program sends, `Configure`, fits the budget for every kind of
/// trajectory: a delayed stutter with its gain lowering (the jump `rig jump` configures) and
/// the slow intrusion `rig intrude` configures with its defaults. Found on the virtual F407
/// once its core ran at one instruction a cycle (issue 51): the intrusion's `Configure`, all
/// in software f64 on the Cortex-M4F, overran the tick's 13,440-cycle budget and latched
/// `DeadlineOverrun` before `Arm`.
#[test]
fn every_trajectorys_configure_fits_the_tick_budget() {
    use sandjumper_core::controller::GainLowering;
    use sandjumper_core::trajectory::JumpKind;
    use sandjumper_core::{JumpConfig, TrajectorySpec};
    let Some(elf) = emulated_elf() else {
        return;
    };
    let intrusion = sandjumper_rig::tool::intrude::IntrudeRequest::default();
    let mut jump = JumpConfig::new(TrajectorySpec::Sine {
        kind: JumpKind::DelayedStutter,
        amplitude_m: 0.01875,
        freq_hz: 10.0,
        tau_s: 0.75,
    });
    jump.gain_lowering = Some(GainLowering {
        kp_factor: 0.5,
        kd_factor: 0.5,
        ramp_s: 0.05,
    });
    let configs = [
        ("a delayed stutter", jump),
        (
            "the default slow intrusion",
            JumpConfig::new(TrajectorySpec::SlowIntrusion {
                start_m: intrusion.start_m,
                depth_m: intrusion.depth_m,
                withdraw_m: intrusion.withdraw_m,
                reintrusion_depth_m: intrusion.reintrusion_depth_m,
                speed_m_s: intrusion.speed_m_s,
                hold_s: intrusion.hold_s,
            }),
        ),
    ];
    for (what, config) in configs {
        let mut link = pil::start(&PilConfig::new(elf)).expect("QEMU starts and answers");
        let status = status_after(&mut link, &Command::Configure(config), 1, what);
        let cost = status.counters.max_tick_cycles;
        eprintln!("Configure of {what}: {cost} instructions");
        assert_eq!(status.fault, None, "after configuring {what}: {status:?}");
        assert!(
            cost <= COMMAND_LIMIT_INSTRUCTIONS,
            "Configure of {what} took {cost} instructions (limit {COMMAND_LIMIT_INSTRUCTIONS})"
        );
        let report = link.finish().expect("the firmware exits");
        assert_eq!(report.exit_code, Some(0));
    }
}
