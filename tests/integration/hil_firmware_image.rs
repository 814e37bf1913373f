//! `hil --link pil` and `rig --link pil` boot only the emulated board's firmware: the STM32F407
//! image, a file that is not an ELF and a missing file are refused before QEMU starts, with
//! exit status 2 and a message naming the file, what it is, and the command that builds the
//! right one. The two boards' default ELF paths differ, so neither build overwrites the other.

use std::path::Path;

use clap::Parser;
use sandjumper_cli::cli::{Cli, EXIT_BAD_INPUT, execute};
use sandjumper_rig::firmware_image::{Board, EMULATED_BUILD, EMULATED_ELF, F407_ELF, check_elf};

fn run(args: &[&str]) -> Result<(), (u8, String)> {
    let mut all = vec!["sandjumper"];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(all).map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    execute(cli).map_err(|e| (e.exit, e.message))
}

/// `hil --link pil` and `rig jump --link pil` with `firmware`: both refused with exit 2 and a
/// message holding every piece of `expect`.
fn refused(firmware: &str, expect: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("rig-jump");
    let jump = [
        "--link",
        "pil",
        "--kind",
        "single",
        "--freq",
        "10",
        "--firmware",
        firmware,
    ];
    let hil: Vec<&str> = ["hil"].into_iter().chain(jump).collect();
    let out_s = out.to_str().expect("utf-8");
    let rig: Vec<&str> = ["rig", "jump"]
        .into_iter()
        .chain(jump)
        .chain(["--out", out_s])
        .collect();
    for args in [&hil[..], &rig[..]] {
        let (code, message) = run(args).expect_err("refused");
        assert_eq!(code, EXIT_BAD_INPUT, "{args:?}: {message}");
        for piece in expect.iter().chain([&firmware, &EMULATED_BUILD]) {
            assert!(
                message.contains(piece),
                "{args:?}: `{piece}` not in: {message}"
            );
        }
    }
    assert!(!out.exists(), "a refused run leaves no output folder");
}

#[test]
fn a_missing_file_is_refused_with_the_build_command() {
    let dir = tempfile::tempdir().expect("temp dir");
    let missing = dir.path().join("no-such.elf");
    refused(missing.to_str().expect("utf-8"), &["not found"]);
}

#[test]
fn a_file_that_is_not_an_elf_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let junk = dir.path().join("random.bin");
    std::fs::write(&junk, b"not firmware at all, just some bytes to boot").expect("write");
    refused(junk.to_str().expect("utf-8"), &["not an ELF file"]);
}

#[test]
fn the_f407_image_is_refused_for_the_emulated_board() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let elf = root.join(F407_ELF);
    if !elf.is_file() {
        // CI builds the F407 image before the tests (.ci/run); elsewhere it may not exist.
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must build the F407 firmware first: {}",
            elf.display()
        );
        eprintln!(
            "SKIPPED: no F407 image at {} (build it first)",
            elf.display()
        );
        return;
    }
    assert_eq!(check_elf(&elf, Board::F407), Ok(()));
    refused(elf.to_str().expect("utf-8"), &["STM32F407"]);
}

#[test]
fn the_two_boards_build_to_different_paths() {
    assert_ne!(EMULATED_ELF, F407_ELF);
    assert!(EMULATED_BUILD.contains("--target-dir target/firmware"));
    assert!(EMULATED_ELF.starts_with("target/firmware/"));
}

#[test]
fn rig_flash_refuses_the_emulated_boards_image() {
    if sandjumper_rig::hil::emulated_firmware::test_prerequisites("the flash image check")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let elf =
        sandjumper_rig::hil::emulated_firmware::build_once(root).unwrap_or_else(|e| panic!("{e}"));
    let elf_s = elf.to_str().expect("utf-8");
    // A stand-in for probe-rs that exists: the image check comes before any probe-rs call.
    let (code, message) = run(&[
        "rig",
        "flash",
        "--port",
        "/dev/ttyACM0",
        "--firmware",
        elf_s,
        "--probe-rs",
        "/bin/false",
    ])
    .expect_err("refused");
    assert_eq!(code, EXIT_BAD_INPUT, "{message}");
    for piece in [elf_s, "emulated-board build", "STM32F407", F407_BUILD_HINT] {
        assert!(message.contains(piece), "`{piece}` not in: {message}");
    }
}

/// The F407 build command, as the flash refusal names it.
const F407_BUILD_HINT: &str = sandjumper_rig::firmware_image::F407_BUILD;
