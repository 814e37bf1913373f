//! The `virtual-f407` program's arguments: every bad one exits 2 with what was wrong and what
//! is allowed, never a panic (101).

use std::process::Command;

mod common;

/// Run the program with `args`; its exit status and standard error.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_virtual-f407"))
        .args(args)
        .output()
        .expect("the program starts");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn bad_arguments_exit_2_with_a_message() {
    let not_elf = std::env::temp_dir().join(format!("virtual-f407-cli-{}.txt", std::process::id()));
    std::fs::write(&not_elf, "not an ELF").unwrap();
    let not_elf = not_elf.to_str().unwrap().to_string();
    for (args, says) in [
        (vec!["--ms", "5"], "--elf ELF is required"),
        (vec!["--elf", &not_elf], "give --ms N"),
        (
            vec!["--elf", &not_elf, "--run", "--stdio"],
            "--run and --stdio are exclusive",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--gdb-wait"],
            "--gdb-wait needs --gdb ADDR",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--gdb", "nowhere"],
            "--gdb nowhere: cannot listen there",
        ),
        (vec!["--elf", &not_elf, "--ms", "x"], "--ms: a whole number"),
        (vec!["--elf", &not_elf, "--ms", "0"], "1 to"),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--pace", "1e-300"],
            "0.001 to 1000",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--pace", "NaN"],
            "0.001 to 1000",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--surface-p", "NaN"],
            "a finite number",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--p0", "x"],
            "--p0: metres",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--bed", "wet"],
            "allowed ready, unwired",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--frobnicate"],
            "unknown argument",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--crystal-stops-at", "0"],
            "--crystal-stops-at: whole virtual milliseconds, 1 or more",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--crystal-stops-at", "soon"],
            "--crystal-stops-at: whole virtual milliseconds, 1 or more",
        ),
        (
            vec!["--elf", &not_elf, "--ms", "5", "--clock"],
            "--clock needs a value",
        ),
        (
            vec![
                "--elf",
                &not_elf,
                "--ms",
                "5",
                "--clock",
                "/nonexistent/virtual-f407/clock",
            ],
            "--clock /nonexistent/virtual-f407/clock:",
        ),
        (vec!["--elf", &not_elf, "--ms", "5"], "virtual-f407:"),
        (
            vec!["--elf", "/nonexistent/fw.elf", "--ms", "5"],
            "virtual-f407:",
        ),
    ] {
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let _ = std::fs::remove_file(&not_elf);
}

/// `--clock FILE` holds the virtual time at the end: the run's length, ns, and its complement.
#[test]
fn the_clock_file_holds_the_virtual_time_at_the_end() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("virtual-f407-clock-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let clock = dir.join("clock");
    let (code, err) = run(&[
        "--elf",
        elf.to_str().unwrap(),
        "--ms",
        "30",
        "--clock",
        clock.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let bytes = std::fs::read(&clock).unwrap();
    assert_eq!(bytes.len(), 16, "{bytes:?}");
    let word = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().unwrap());
    // The run ends at the first instruction boundary at or past 30 ms: one instruction is
    // 1/168 us on the PLL, and the boundaries fall where the switch to it left them.
    let end = word(0);
    assert!((30_000_000..30_000_006).contains(&end), "{end}");
    assert_eq!(word(8), !end);
    let _ = std::fs::remove_dir_all(&dir);
}
