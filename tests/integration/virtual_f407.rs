//! The tests on the F407 release binary on the virtual board (`sim-host/virtual-f407`: its own
//! workspace on rustc 1.98.0, see its README) run from here, so that the README's test command
//! runs them: this builds the board (`build.sh`) and runs its test suite. Skipped with a message
//! when toolchain 1.98.0 or the F407 ELF is missing; under `CI` (which installs both) a skip is
//! a failure.

use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::Command;

fn skip(why: &str) {
    let msg = format!("skipped: the virtual F407 board tests: {why}");
    if std::env::var_os("CI").is_some() {
        panic!(
            "{msg} (under CI they must run: .ci/run installs toolchain 1.98.0 and builds the ELF)"
        );
    }
    eprintln!("{msg}");
}

/// A cargo/rustup invocation with the outer cargo's environment removed, so that the board's
/// own `rust-toolchain.toml` (1.98.0) applies.
fn clean(cmd: &mut Command) -> &mut Command {
    for var in [
        "RUSTUP_TOOLCHAIN",
        "CARGO",
        "RUSTC",
        "RUSTDOC",
        "CARGO_TARGET_DIR",
        "CARGO_MANIFEST_DIR",
        "CARGO_PKG_NAME",
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "CARGO_BUILD_TARGET",
    ] {
        cmd.env_remove(var);
    }
    cmd
}

/// `cargo build` of the F407 release firmware in the workspace `root`, into `target_dir` (the
/// workspace's own by default), with the bring-up fault `inject` built in (none by default).
fn firmware_build(
    root: &Path,
    target_dir: Option<&str>,
    inject: Option<&str>,
) -> std::io::Result<std::process::Output> {
    let mut cmd = Command::new(env!("CARGO"));
    cmd.args([
        "build",
        "-p",
        "sandjumper-firmware",
        "--target",
        "thumbv7em-none-eabihf",
        "--release",
    ])
    .current_dir(root);
    if let Some(dir) = target_dir {
        cmd.args(["--target-dir", dir]);
    }
    if let Some(kind) = inject {
        cmd.env("SANDJUMPER_INJECT", kind);
    }
    cmd.output()
}

/// The board's build running beside the test, in a process group of its own: if the test
/// returns or panics before waiting for it, the whole group (the script, cargo, each rustc) is
/// killed, not left building into the board's target directory beside the next run.
struct BackgroundBuild(std::process::Child);

impl Drop for BackgroundBuild {
    fn drop(&mut self) {
        if let Ok(None) = self.0.try_wait() {
            let group = format!("-{}", self.0.id());
            let _ = Command::new("kill").args(["-KILL", "--", &group]).status();
            let _ = self.0.wait();
        }
    }
}

#[test]
fn the_f407_binary_passes_its_tests_on_the_virtual_board() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let board = root.join("sim-host/virtual-f407");
    let elf = root.join(sandjumper_rig::firmware_image::F407_ELF);
    let has_toolchain = clean(Command::new("rustup").args(["run", "1.98.0", "rustc", "--version"]))
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_toolchain {
        return skip(
            "rustc 1.98.0 is not installed (`rustup toolchain install 1.98.0 --profile minimal -c clippy,rustfmt`)",
        );
    }
    // The board and its tests build (about 4 min cold, most of it one crate, cranelift, on one
    // core) while the firmware images below build beside it.
    // Its output goes to a file, which no pipe left unread can block.
    let board_log = root.join("target/virtual-f407-build.log");
    std::fs::create_dir_all(root.join("target")).expect("the target folder");
    let log = std::fs::File::create(&board_log).expect("the board build's log");
    let mut board_build = BackgroundBuild(
        clean(Command::new(board.join("build.sh")).arg("--tests"))
            .current_dir(&board)
            .stdout(log.try_clone().expect("the log again"))
            .stderr(log)
            .process_group(0)
            .spawn()
            .expect("run build.sh"),
    );
    // The F407 release ELF, built now so the board never runs a stale one (a no-op when it is
    // up to date); without the target or flip-link it cannot be built: skipped.
    let built = firmware_build(root, None, None);
    if !built.as_ref().is_ok_and(|o| o.status.success()) || !elf.is_file() {
        drop(board_build);
        return skip(&format!(
            "the F407 ELF {} cannot be built here (`rustup target add thumbv7em-none-eabihf`, `cargo install flip-link`): {}",
            elf.display(),
            built
                .map(|o| String::from_utf8_lossy(&o.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
                    .to_string())
                .unwrap_or_else(|e| e.to_string())
        ));
    }
    // The four fault test images (firmware/src/inject_f407.rs; the bring-up scopes three), which the board's
    // injected.rs runs: built one after the other in one target directory (only the firmware
    // crate rebuilds between them), each copied to target/inject-<kind>.
    for kind in [
        "panic",
        "hardfault",
        "stack-overflow",
        "unhandled-interrupt",
    ] {
        let out = firmware_build(root, Some("target/inject-build"), Some(kind))
            .expect("run cargo build for a test image");
        assert!(
            out.status.success(),
            "building the {kind} test image failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let dir = root.join(format!(
            "target/inject-{kind}/thumbv7em-none-eabihf/release"
        ));
        std::fs::create_dir_all(&dir).expect("the test image's folder");
        std::fs::copy(
            root.join("target/inject-build/thumbv7em-none-eabihf/release/sandjumper-firmware"),
            dir.join("sandjumper-firmware"),
        )
        .expect("copy the test image");
    }
    let build = board_build.0.wait().expect("wait for build.sh");
    assert!(
        build.success(),
        "sim-host/virtual-f407/build.sh failed:\n{}",
        std::fs::read_to_string(&board_log).unwrap_or_default()
    );
    let test = clean(Command::new("cargo").args(["test", "--release", "--locked"]))
        .current_dir(&board)
        .env("SANDJUMPER_F407_ELF", &elf)
        .output()
        .expect("run cargo test in sim-host/virtual-f407");
    let out = String::from_utf8_lossy(&test.stdout);
    let err = String::from_utf8_lossy(&test.stderr);
    eprintln!("{out}");
    assert!(
        test.status.success(),
        "the virtual board's tests failed:\n{out}\n{err}"
    );
    assert!(out.contains("test result: ok"), "no test ran:\n{out}");
    cargo_run_without_a_probe_runs_on_the_virtual_board(root);
}

/// `cargo run` of the F407 release firmware with probe-rs installed and no debug probe
/// attached (`PROBE_RS` names a stand-in that lists none, as probe-rs does, and fails if asked
/// to run): the runner says so on its first line and the virtual board prints the firmware's
/// boot line, its log decoded as `probe-rs run` shows a board's. The run goes on until
/// stopped: the test stops it (its process group) once the boot line is in.
fn cargo_run_without_a_probe_runs_on_the_virtual_board(root: &Path) {
    use std::io::BufRead;
    use std::os::unix::fs::PermissionsExt;
    let probe_rs = root.join("target/probe-rs-with-no-probe");
    std::fs::write(
        &probe_rs,
        "#!/bin/sh\ncase $1 in\n  list) echo 'No debug probes were found.' ;;\n  \
         *) echo \"probe-rs stand-in: $1 with no probe\" >&2; exit 3 ;;\nesac\n",
    )
    .expect("the stand-in is written");
    std::fs::set_permissions(&probe_rs, std::fs::Permissions::from_mode(0o755))
        .expect("the stand-in runs");
    let mut child = BackgroundBuild(
        Command::new(env!("CARGO"))
            .args([
                "run",
                "--release",
                "-p",
                "sandjumper-firmware",
                "--target",
                "thumbv7em-none-eabihf",
            ])
            .current_dir(root)
            .env("PROBE_RS", &probe_rs)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .process_group(0)
            .spawn()
            .expect("cargo run"),
    );
    let stdout = child.0.stdout.take().expect("its stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut lines = Vec::new();
    // Wall time, generous: cargo checks the build first; the board boots in 2 virtual ms.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(600);
    while !lines
        .iter()
        .any(|l: &String| l.starts_with("sandjumper firmware: STM32F407"))
    {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        match rx.recv_timeout(left) {
            Ok(line) => lines.push(line),
            Err(_) => panic!("no boot line from `cargo run` without a probe: {lines:?}"),
        }
    }
    assert!(
        lines[0].starts_with("no debug probe attached: running ")
            && lines[0].contains("on the virtual STM32F407 board"),
        "{lines:?}"
    );
    drop(child);
}
