//! A campaign through the real firmware (processor in the loop): two points of the small
//! campaign's kind, run with `--link pil`, give the same beds (the simulated bed is seeded
//! per point) and the same jump heights within 0.5 % as through SIL.
//!
//! Needs `qemu-system-arm` and the `thumbv7em-none-eabihf` target: skipped with a message when
//! QEMU is missing, unless `CI` is set (then it fails).

use std::path::Path;

use clap::Parser;
use sandjumper_cli::cli::{Cli, execute};
use sandjumper_rig::hil::emulated_firmware;

fn run(args: &[&str]) -> Result<(), (u8, String)> {
    let cli = Cli::try_parse_from(args).map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    execute(cli).map_err(|e| (e.exit, e.message))
}

fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|c| *c == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn a_two_point_campaign_through_the_firmware_matches_sil() {
    if emulated_firmware::test_prerequisites("the PIL campaign")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return;
    }
    let ws = Path::new(env!("CARGO_MANIFEST_DIR"));
    let elf = emulated_firmware::build_once(ws).unwrap_or_else(|e| panic!("{e}"));
    let small = std::fs::read_to_string(ws.join("examples/campaign-small.toml")).unwrap();
    let two = small
        .replace("frequencies_hz = [10.0, 14.0]", "frequencies_hz = [10.0]")
        .replace("phis = [0.58, 0.61]", "phis = [0.6]");
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("two.toml");
    std::fs::write(&file, two).unwrap();
    let f = file.to_str().unwrap();
    let (sil, pil) = (tmp.path().join("sil"), tmp.path().join("pil"));
    run(&[
        "sandjumper",
        "campaign",
        "run",
        f,
        "--link",
        "sil",
        "--out",
        sil.to_str().unwrap(),
    ])
    .unwrap();
    run(&[
        "sandjumper",
        "campaign",
        "run",
        f,
        "--link",
        "pil",
        "--firmware",
        elf.to_str().unwrap(),
        "--out",
        pil.to_str().unwrap(),
    ])
    .unwrap();
    let s = std::fs::read_to_string(sil.join("results.csv")).unwrap();
    let p = std::fs::read_to_string(pil.join("results.csv")).unwrap();
    assert_eq!(s.lines().count(), 3, "two points");
    assert_eq!(column(&s, "achieved_phi"), column(&p, "achieved_phi"));
    for name in [
        "plant_jump_height_m",
        "predicted_jump_height_m",
        "measured_jump_height_m",
    ] {
        for (a, b) in column(&s, name).iter().zip(column(&p, name)) {
            assert!((a - b).abs() < 0.005 * a, "{name}: SIL {a} vs PIL {b}");
        }
    }
}
