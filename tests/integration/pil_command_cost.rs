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
use sandjumper_core::{Command, Reply, SensorFrame};
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::link::RigLink;
use sandjumper_rig::hil::pil::{self, PilConfig};

/// The F407's tick budget: 80 % of a 10 kHz period at 168 MHz, cycles
/// (`firmware/src/board/f407.rs`, `TICK_BUDGET_CYCLES`).
const F407_TICK_BUDGET_CYCLES: u32 = 13_440;
/// Instructions allowed per command: half the cycle budget, since a Cortex-M4 running from
/// flash with 5 wait states takes more than one cycle per instruction.
const COMMAND_LIMIT_INSTRUCTIONS: u32 = F407_TICK_BUDGET_CYCLES / 2;

#[test]
fn a_full_replay_upload_and_commit_fit_the_tick_budget() {
    if emulated_firmware::test_prerequisites("the PIL command-cost test")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let elf = emulated_firmware::build_once(root).unwrap_or_else(|e| panic!("{e}"));
    let mut link = pil::start(&PilConfig::new(elf)).expect("QEMU starts and answers");
    let samples: Vec<f32> = (0..REPLAY_CAPACITY)
        .map(|k| 0.01 * (k as f32 * 0.002).sin())
        .collect();
    let mut worst = (0u32, String::new());
    for (frame, command) in (1u32..).zip(replay_upload(&samples, 10)) {
        let what = format!("{:?}", command.kind());
        link.command(&command)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        // One sensor frame reports the command's tick to the core.
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
