//! Helpers of the rig tool's library tests: the workspace, the virtual board's and the emulated
//! firmware's prerequisites, an acquisition log's samples, and how far a replay followed the
//! jump it replays.
//!
//! Each test module says `use crate::common;` and uses what it needs; the `dead_code` allowance
//! keeps a helper that only some modules use from warning when those are left out.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use sandjumper_acqlog::AcqLog;
use sandjumper_core::sample::flags;
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::virtual_board::VirtualBoardConfig;
use sandjumper_rig::stroke_table::StrokeTable;
use sandjumper_rig::tool::replay::{ReplayRequest, ReplaySource};
use sandjumper_rig::tool::target::Target;

/// The workspace's root directory (two levels above `sim-host/rig`).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("sim-host/rig sits in the workspace")
}

/// `(flags, encoder_counts)` of every row of an acquisition log.
pub fn log_rows(log: &AcqLog) -> Vec<(u32, i64)> {
    log.rows
        .iter()
        .map(|r| (r.flags.expect("a flags column"), r.encoder_counts))
        .collect()
}

/// How far the replay recorded in `replay` followed the motor of the run recorded in
/// `original`, sample by sample from the replay's first `Running` sample: (max, rms), m.
pub fn replay_error(original: &AcqLog, replay: &AcqLog) -> (f64, f64) {
    let old = log_rows(original);
    let new = log_rows(replay);
    let start = new
        .iter()
        .position(|r| r.0 & u32::from(flags::RUNNING) != 0)
        .expect("a Running sample");
    let n = old.len().min(new.len() - start);
    assert!(
        n + 100 > old.len(),
        "the replay covers the original ({n} of {})",
        old.len()
    );
    let errors: Vec<f64> = (0..n)
        .map(|k| 1e-6 * (new[start + k].1 - old[k].1).abs() as f64)
        .collect();
    let max = errors.iter().cloned().fold(0.0, f64::max);
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
    (max, rms)
}

/// The emulated board's firmware, built once; `None` (skip, or fail in CI) when QEMU or the
/// firmware toolchain is missing or the firmware does not build here.
pub fn qemu_firmware() -> Option<PathBuf> {
    let built = emulated_firmware::test_prerequisites("rig through PIL").and_then(|()| {
        emulated_firmware::build_once(&workspace())
            .map(Path::to_path_buf)
            .map_err(|msg| {
                assert!(std::env::var_os("CI").is_none(), "{msg}");
                format!("SKIPPED: rig through PIL: {msg}")
            })
    });
    built.map_err(|skip| eprintln!("{skip}")).ok()
}

/// The virtual board's program and the F407 ELF at their default places (built by
/// `sim-host/virtual-f407/build.sh` and the firmware build) are there, or `None` with a
/// message; under CI both must be there.
pub fn virtual_board() -> Option<()> {
    let board = VirtualBoardConfig::new(&workspace());
    let missing: Vec<String> = [&board.program, &board.elf]
        .into_iter()
        .filter(|p| !p.is_file())
        .map(|p| p.display().to_string())
        .collect();
    if missing.is_empty() {
        return Some(());
    }
    let msg = format!(
        "skipped: --link f407 needs {} (sim-host/virtual-f407/build.sh; the F407 firmware build)",
        missing.join(" and ")
    );
    assert!(std::env::var_os("CI").is_none(), "{msg}");
    eprintln!("{msg}");
    None
}

/// `rig replay` of the log `log` (named `name` in messages) on `target`, unedited, at the
/// command's defaults (a 1 kHz table, eq4, the phi = 0.57 preset).
pub fn replay_of_log(target: Target, log: &AcqLog, name: &str) -> ReplayRequest {
    // `stroke`'s defaults are a log's; its table is replaced by the log.
    let unused = StrokeTable::resample(&[(0.0, 0.0), (1e-3, 0.0)], 1000);
    ReplayRequest {
        source: ReplaySource::Log(Box::new(log.clone())),
        ..ReplayRequest::stroke(target, unused, name)
    }
}

/// How many PNG files `dir` holds.
pub fn pngs_in(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .expect("a folder")
        .filter_map(Result::ok)
        .filter(|e| e.path().extension() == Some("png".as_ref()))
        .count()
}
