//! `--live ADDR`: the page, `state.json` and the event stream of a jump while it runs and
//! after it ends, from a real `sandjumper hil` process over HTTP (the `live` feature, on by
//! default).
#![cfg(feature = "live")]

use crate::common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A plain HTTP/1.1 GET: (status line, headers, body).
fn get(addr: &str, path: &str) -> (String, String, String) {
    common::http_get(addr, path).unwrap_or_else(|e| panic!("GET {path} from {addr}: {e}"))
}

/// Start `sandjumper args`, returning the child and its stderr lines as they come.
fn start(args: &[&str]) -> (Child, mpsc::Receiver<String>) {
    common::start_with_stderr_lines(args, Stdio::piped())
}

/// HOST:PORT of the `live view: http://HOST:PORT/ ...` line.
fn addr_of(line: &str) -> String {
    line.trim_start_matches("live view: http://")
        .split('/')
        .next()
        .unwrap()
        .to_string()
}

fn wait_for(rx: &mpsc::Receiver<String>, what: &str) -> String {
    let mut seen = String::new();
    loop {
        match rx.recv_timeout(Duration::from_secs(120)) {
            Ok(l) if l.contains(what) => return l,
            Ok(l) => seen += &format!("{l}\n"),
            Err(_) => panic!("no `{what}` on stderr; it said:\n{seen}"),
        }
    }
}

/// Start `sandjumper args` (a command with `--live` and a linger), give `while_running` the
/// page's address, then wait for the run's end and return the command and the page's final
/// `state.json`.
fn watched_to_end(args: &[&str], while_running: impl FnOnce(&str)) -> (Child, serde_json::Value) {
    let (child, rx) = start(args);
    let url = wait_for(&rx, "live view: http://");
    let addr = addr_of(&url);
    while_running(&addr);
    wait_for(&rx, "the run has ended");
    let (_, _, body) = get(&addr, "/state.json");
    (child, serde_json::from_str(&body).unwrap())
}

#[test]
fn a_jump_is_watched_live_then_kept_until_the_linger_ends() {
    let started = Instant::now();
    let (child, rx) = start(&[
        "hil",
        "--kind",
        "stutter",
        "--freq",
        "10",
        "--live",
        "127.0.0.1:0",
        "--linger",
        "3",
    ]);
    // The URL comes first.
    let first = rx.recv_timeout(Duration::from_secs(60)).unwrap();
    assert!(first.starts_with("live view: http://127.0.0.1:"), "{first}");
    let addr = addr_of(&first);
    // The page: the chart library served by the binary itself, nothing from the internet.
    let (status, _, page) = get(&addr, "/");
    assert!(status.contains("200"), "{status}");
    assert!(page.contains("src=\"/uPlot.js\"") && !page.contains("src=\"http"));
    let (_, headers, js) = get(&addr, "/uPlot.js");
    assert!(headers.contains("text/javascript") && js.contains("uPlot"));
    // A browser's event stream stays open through the run and the linger: it must not keep
    // the command from ending.
    let mut open_stream = TcpStream::connect(&addr).unwrap();
    write!(open_stream, "GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    wait_for(&rx, "the run has ended");
    let elapsed = started.elapsed().as_secs_f64();
    let (status, headers, body) = get(&addr, "/state.json");
    assert!(status.contains("200") && headers.contains("application/json"));
    let st: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(st["title"].as_str().unwrap().contains("stutter"));
    assert_eq!(st["channels"].as_array().unwrap().len(), 6);
    let received = st["samples_received"].as_u64().unwrap();
    assert!(received > 3_000, "{received} samples at 10 kHz");
    assert_eq!(st["samples_dropped"].as_u64(), Some(0));
    // About 1,000 points a second of rig time, not 10,000.
    let points = st["t_s"].as_array().unwrap().len() as u64;
    assert!(
        points * 4 < received && points * 20 > received,
        "{points} of {received}"
    );
    // Paced at real time: the run took at least the rig time it covered.
    let t = st["t_s"].as_array().unwrap();
    let span = t.last().unwrap().as_f64().unwrap() - t[0].as_f64().unwrap();
    assert!(
        span > 0.3 && elapsed > 0.95 * span,
        "{elapsed} s for {span} s of rig time"
    );
    let kinds: Vec<String> = st["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let k = e["kind"].as_str().unwrap().to_string();
            match k.as_str() {
                "state" => format!("state:{}", e["state"].as_str().unwrap()),
                "jump" => format!("jump:{}", e["phase"].as_str().unwrap()),
                _ => k,
            }
        })
        .collect();
    for want in [
        "run_started",
        "state:Armed",
        "jump:start",
        "state:Running",
        "jump:end",
        "state:Done",
        "run_ended",
    ] {
        assert!(kinds.iter().any(|k| k == want), "{want} in {kinds:?}");
    }
    assert!(st["fault"].is_null());
    assert!(st["ended"].as_str().unwrap().contains("jump height"));
    // The stream answers as Server-Sent Events.
    let mut s = TcpStream::connect(&addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(s, "GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut buf = [0u8; 512];
    let n = s.read(&mut buf).unwrap();
    let head = String::from_utf8_lossy(&buf[..n]).to_lowercase();
    assert!(head.contains("text/event-stream"), "{head}");
    drop(s);
    // The linger ends the command with status 0, its summary on stdout, the stream still open.
    let out = child.wait_with_output().unwrap();
    drop(open_stream);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("height"));
}

#[test]
fn a_live_address_that_cannot_be_used_is_refused_before_the_run() {
    fn with<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        [&["hil", "--kind", "single", "--freq", "10"][..], extra].concat()
    }
    for (addr, public, want) in [
        ("nowhere", false, "not an address"),
        ("8.8.8.8:80", false, "--live-public"),
        ("8.8.8.8:80", true, "cannot listen"),
    ] {
        let public: &[&str] = if public { &["--live-public"] } else { &[] };
        common::refused(
            &with(&[&["--live", addr][..], public].concat()),
            &[want, addr],
        );
    }
    // The Foxglove WebSocket obeys the same rule: beyond this machine only with --live-public.
    common::refused(
        &with(&["--live", "127.0.0.1:0", "--foxglove", "0.0.0.0:0"]),
        &["--foxglove 0.0.0.0:0", "--live-public"],
    );
    // A build without the Foxglove server says so (`cargo build --features foxglove` has one;
    // sim-host/live/tests/foxglove.rs tests it).
    if !sandjumper_live::FOXGLOVE {
        common::refused(
            &with(&["--live", "127.0.0.1:0", "--foxglove", "127.0.0.1:0"]),
            &["--features foxglove"],
        );
    }
    // --pace and --linger mean nothing without --live.
    common::refused(&with(&["--pace", "2"]), &[]);
}

#[test]
fn a_resumed_campaign_shows_its_history_then_each_point_live_and_on_the_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("camp");
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/campaign-small.toml"
    );
    let first = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args([
            "campaign",
            "run",
            file,
            "--link",
            "sil",
            "--stop-after",
            "3",
        ])
        .args(["--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(first.status.code(), Some(0));
    // One line per point on the terminal, without --live.
    let lines = String::from_utf8_lossy(&first.stdout)
        .lines()
        .filter(|l| l.starts_with("point "))
        .count();
    assert_eq!(lines, 3);
    let (child, st) = watched_to_end(
        &[
            "campaign",
            "resume",
            out.to_str().unwrap(),
            "--live",
            "127.0.0.1:0",
            "--linger",
            "3",
        ],
        |_| {},
    );
    let c = &st["campaign"];
    assert_eq!(c["points"].as_u64(), Some(8));
    assert_eq!(c["done"].as_u64(), Some(8));
    assert_eq!(c["failed"].as_u64(), Some(0));
    assert_eq!(c["swept"].as_str(), Some("freq_hz"));
    assert_eq!(c["exit_status"].as_i64(), Some(0));
    let records = c["records"].as_array().unwrap();
    let history: Vec<bool> = records
        .iter()
        .map(|r| r["history"].as_bool().unwrap())
        .collect();
    assert_eq!(
        history,
        [true, true, true, false, false, false, false, false]
    );
    for r in records {
        let h = r["height_m"].as_f64().unwrap();
        assert!(h > 0.01 && h < 0.2, "{r}");
        assert_eq!(r["status"].as_str(), Some("ok"));
    }
    let done = child.wait_with_output().unwrap();
    assert_eq!(done.status.code(), Some(0));
    let lines = String::from_utf8_lossy(&done.stdout)
        .lines()
        .filter(|l| l.starts_with("point ") && l.contains("height"))
        .count();
    assert_eq!(lines, 5);
}

/// The count of finite values in column `c` of a `state.json`.
fn finite_in(st: &serde_json::Value, c: usize) -> usize {
    st["columns"][c]
        .as_array()
        .unwrap()
        .iter()
        .filter(|v| v.as_f64().is_some_and(f64::is_finite))
        .count()
}

/// `rig jump --link LINK --live` of a single 10 Hz jump: its page's state once the run has
/// ended, checked as every link must show it (commanded and measured position and the
/// drive's force; completed; exit 0; outputs written). `while_running` sees the page's
/// address before the end.
fn watched_rig_jump(link: &str, while_running: impl FnOnce(&str)) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("jump");
    let (child, st) = watched_to_end(
        &[
            "rig",
            "jump",
            "--link",
            link,
            "--kind",
            "single",
            "--freq",
            "10",
            "--out",
            out.to_str().unwrap(),
            "--live",
            "127.0.0.1:0",
            "--linger",
            "2",
        ],
        while_running,
    );
    assert!(st["title"].as_str().unwrap().starts_with("rig jump on"));
    assert!(
        st["samples_received"].as_u64().unwrap() > 2_000,
        "{:.300}",
        st.to_string()
    );
    assert_eq!(st["samples_dropped"].as_u64(), Some(0));
    // The commanded position is there (finite) and the measured one follows it.
    assert!(finite_in(&st, 0) > 100 && finite_in(&st, 1) > 100 && finite_in(&st, 4) > 100);
    // The rig's own time: never back, from the settle before the start (negative) to the
    // jump's end and tail.
    let t: Vec<f64> = st["t_s"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_f64())
        .collect();
    if let Some(k) = t.windows(2).position(|w| w[1] < w[0]) {
        let around = &t[k.saturating_sub(4)..(k + 6).min(t.len())];
        panic!("time goes back at point {k} of {}: {around:?}", t.len());
    }
    assert!(t[0] < 0.0 && t[0] > -1.0, "starts at {}", t[0]);
    let end = *t.last().unwrap();
    assert!(end > 0.1 && end < 3.0, "ends at {end}");
    assert_eq!(st["ended"].as_str(), Some("completed"));
    assert_eq!(child.wait_with_output().unwrap().status.code(), Some(0));
    assert!(out.join("summary.json").is_file());
    st
}

#[test]
fn rig_jump_is_watched_live_with_the_commanded_position() {
    let st = watched_rig_jump("sil", |_| {});
    assert!(
        st["events"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "jump")
    );
}

/// A board running free (the F407 binary on the virtual board) streams its samples; the
/// view shows them while the run goes on, on the board's own time.
#[test]
fn a_free_running_board_is_watched_live_with_its_samples() {
    if common::virtual_board().is_none() {
        return;
    }
    watched_rig_jump("f407", |addr| {
        // While it runs: samples arrive before the run ends.
        let deadline = Instant::now() + Duration::from_secs(120);
        loop {
            let (_, _, body) = get(addr, "/state.json");
            let st: serde_json::Value = serde_json::from_str(&body).unwrap();
            let n = st["samples_received"].as_u64().unwrap_or(0);
            if st["ended"].is_null() && n > 0 {
                return;
            }
            assert!(
                st["ended"].is_null() && Instant::now() < deadline,
                "no sample reached the view while the board ran"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    });
}

/// Send SIGINT (Ctrl-C) to `child`.
fn interrupt(child: &Child) {
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -INT {}", child.id());
}

#[test]
fn with_no_terminal_the_page_stays_a_few_seconds_and_the_command_ends() {
    // No --linger, standard input not a terminal (a script, a Slurm job): 5 s, not forever.
    let (child, rx) = start(&[
        "hil",
        "--kind",
        "single",
        "--freq",
        "10",
        "--pace",
        "0",
        "--live",
        "127.0.0.1:0",
    ]);
    wait_for(&rx, "stays up for 5 s");
    let done = child.wait_with_output().unwrap();
    assert_eq!(done.status.code(), Some(0));
}

#[test]
fn ctrl_c_ends_a_kept_page_with_exit_status_0() {
    // A long linger: Ctrl-C ends it sooner.
    let (child, rx) = start(&[
        "hil",
        "--kind",
        "single",
        "--freq",
        "10",
        "--pace",
        "0",
        "--live",
        "127.0.0.1:0",
        "--linger",
        "600",
    ]);
    let url = wait_for(&rx, "live view: http://");
    let addr = addr_of(&url);
    wait_for(&rx, "stays up for 600 s");
    let (status, _, body) = get(&addr, "/state.json");
    assert!(status.contains("200"), "{status}");
    let st: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(
        st["ended"]
            .as_str()
            .is_some_and(|e| e.starts_with("jump height")),
        "{body:.300}"
    );
    interrupt(&child);
    let done = child.wait_with_output().unwrap();
    assert_eq!(done.status.code(), Some(0));
}

#[test]
fn rig_status_is_watched_live_until_ctrl_c() {
    let (child, rx) = start(&[
        "rig",
        "status",
        "--link",
        "sil",
        "--watch",
        "--live",
        "127.0.0.1:0",
    ]);
    let url = wait_for(&rx, "live view: http://");
    let addr = addr_of(&url);
    // The polls reach the page: its title and the controller's state.
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let (_, _, body) = get(&addr, "/state.json");
        let st: serde_json::Value = serde_json::from_str(&body).unwrap();
        let idle = st["events"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "state" && e["state"] == "Idle");
        if idle {
            assert_eq!(st["title"].as_str(), Some("rig status on sil"));
            assert!(st["ended"].is_null());
            break;
        }
        assert!(
            Instant::now() < deadline,
            "no state on the page: {body:.400}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    interrupt(&child);
    let done = child.wait_with_output().unwrap();
    assert_eq!(done.status.code(), Some(0));
    let out = String::from_utf8_lossy(&done.stdout);
    assert!(out.contains("state Idle"), "{out}");
}

#[test]
fn rig_intrude_and_replay_are_watched_live() {
    let dir = tempfile::tempdir().unwrap();
    let jump = dir.path().join("jump");
    common::ok(&[
        "rig",
        "jump",
        "--link",
        "sil",
        "--kind",
        "single",
        "--freq",
        "10",
        "--out",
        jump.to_str().unwrap(),
    ]);
    let log = jump.join("acquisition.csv");
    let intrude = dir.path().join("intrude");
    let replay = dir.path().join("replay");
    let runs: [(&str, Vec<&str>); 2] = [
        (
            "rig intrusion on",
            vec![
                "rig",
                "intrude",
                "--link",
                "sil",
                "--model",
                "eq1",
                "--out",
                intrude.to_str().unwrap(),
            ],
        ),
        (
            "rig replay on",
            vec![
                "rig",
                "replay",
                log.to_str().unwrap(),
                "--link",
                "sil",
                "--out",
                replay.to_str().unwrap(),
            ],
        ),
    ];
    for (title, args) in runs {
        let mut args = args.clone();
        args.extend(["--live", "127.0.0.1:0", "--pace", "0", "--linger", "1"]);
        let (child, st) = watched_to_end(&args, |_| {});
        assert!(
            st["title"].as_str().unwrap().starts_with(title),
            "{:.300}",
            st.to_string()
        );
        assert!(st["samples_received"].as_u64().unwrap() > 1_000, "{title}");
        assert_eq!(st["samples_dropped"].as_u64(), Some(0));
        assert_eq!(st["ended"].as_str(), Some("completed"), "{title}");
        assert!(finite_in(&st, 4) > 100, "{title}: the drive's force");
        assert_eq!(child.wait_with_output().unwrap().status.code(), Some(0));
    }
    assert!(intrude.join("summary.json").is_file());
    assert!(replay.join("summary.json").is_file());
}

#[test]
fn a_failed_campaign_point_shows_its_reason_live() {
    let dir = tempfile::tempdir().unwrap();
    let small = common::read(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/campaign-small.toml"
    )));
    // One bed measurement per point: 0.57 is what fluidizing gives, 0.61 needs compaction
    // doses and more measurements, so that point fails.
    let file = dir.path().join("campaign.toml");
    let text = small
        .replace("kinds = [\"single\", \"delayed\"]", "kinds = [\"single\"]")
        .replace("frequencies_hz = [10.0, 14.0]", "frequencies_hz = [10.0]")
        .replace("phis = [0.58, 0.61]", "phis = [0.57, 0.61]")
        .replace("max_attempts = 12", "max_attempts = 1");
    assert!(text.contains("phis = [0.57, 0.61]") && text.contains("max_attempts = 1 "));
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("camp");
    let (child, st) = watched_to_end(
        &[
            "campaign",
            "run",
            file.to_str().unwrap(),
            "--link",
            "sil",
            "--out",
            out.to_str().unwrap(),
            "--live",
            "127.0.0.1:0",
            "--linger",
            "1",
        ],
        |_| {},
    );
    let c = &st["campaign"];
    assert_eq!(c["points"].as_u64(), Some(2), "{c}");
    assert_eq!(c["failed"].as_u64(), Some(1), "{c}");
    let records = c["records"].as_array().unwrap();
    let failed: Vec<&serde_json::Value> = records
        .iter()
        .filter(|r| r["status"].as_str() != Some("ok"))
        .collect();
    assert_eq!(failed.len(), 1, "{c}");
    let reason = failed[0]["reason"].as_str().unwrap_or("");
    assert!(reason.contains("0.61"), "{reason}");
    // A point whose bed could not be prepared is skipped (on_failed_preparation = "skip"):
    // a failed point, not a failed campaign.
    assert_eq!(child.wait_with_output().unwrap().status.code(), Some(0));
}

#[test]
fn bad_input_is_reported_before_the_page_starts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(["campaign", "run", "nope.toml", "--link", "sil", "--out"])
        .arg(&out)
        .args(["--live", "127.0.0.1:0", "--linger", "600"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("nope.toml"), "{stderr}");
    // No page was started to linger on (600 s): the error comes at once.
    assert!(!stderr.contains("live view:"), "{stderr}");
    // An address beyond this machine without --live-public: refused the same way.
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args([
            "hil",
            "--kind",
            "single",
            "--freq",
            "10",
            "--live",
            "0.0.0.0:0",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--live-public"), "{stderr}");
}
