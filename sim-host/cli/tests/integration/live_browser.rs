//! The live page in a real browser (headless Chromium): it receives the samples and the
//! final state of a sil jump and of the small example campaign, and shows a fault when one
//! is injected. The screenshots it takes go to `target/live-screenshots/` (docs/live.md's
//! picture is one of them). Skipped with a message without Chromium; under `CI` it must run
//! (`.ci/run` installs Debian's `chromium`).
#![cfg(feature = "live")]

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn chromium() -> Option<PathBuf> {
    let candidates = [
        std::env::var("CHROMIUM").unwrap_or_default(),
        "/usr/bin/chromium".into(),
        "/usr/bin/chromium-browser".into(),
    ];
    let found = candidates
        .iter()
        .filter(|c| !c.is_empty())
        .map(PathBuf::from)
        .find(|p| p.is_file());
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "no chromium (CI must have it: .ci/run installs Debian's chromium)"
        );
        eprintln!("skipped: no chromium (install Debian's `chromium`, or set CHROMIUM=PATH)");
    }
    found
}

/// Start `sandjumper args` with `--live 127.0.0.1:0 --linger 60`; returns the child and the
/// page's address once the run has ended.
fn run_live(args: &[&str]) -> (Child, String) {
    let mut all: Vec<&str> = args.to_vec();
    all.extend(["--live", "127.0.0.1:0", "--linger", "60"]);
    let (child, rx) = common::start_with_stderr_lines(&all, Stdio::null());
    let mut url = None;
    loop {
        let line = rx
            .recv_timeout(Duration::from_secs(180))
            .expect("the run ends");
        if let Some(rest) = line.strip_prefix("live view: http") {
            let rest = format!("http{rest}");
            url = rest.split_whitespace().next().map(str::to_string);
        }
        if line.contains("the run has ended") {
            break;
        }
    }
    (child, url.expect("the URL first"))
}

/// The page's DOM once its scripts have shown the run's end (tried up to 30 times: Chromium
/// may dump the page before its first fetch has answered), and a screenshot into `shot`.
fn page(browser: &Path, url: &str, shot: &Path) -> String {
    for _ in 0..30 {
        let dom = page_once(browser, url, shot);
        // The status line, not the script's own text, must say so.
        if dom.contains("id=\"status\">") && text_of(&dom, "status").contains("ENDED") {
            return dom;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    panic!("the page at {url} never showed the run's end");
}

/// Headless Chromium as these machines run it (no sandbox as root, nothing fetched from the
/// network by the browser itself).
const HEADLESS: [&str; 8] = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
];

/// The sample count on the page's status line.
fn samples_in(status: &str) -> u64 {
    status
        .split(" samples")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0)
}

fn page_once(browser: &Path, url: &str, shot: &Path) -> String {
    let profile = tempfile::tempdir().unwrap();
    let flags: Vec<&str> = HEADLESS
        .iter()
        .copied()
        .chain(["--window-size=1400,1000", "--timeout=3000"])
        .collect();
    let user = format!("--user-data-dir={}", profile.path().display());
    let out = Command::new(browser)
        .args(&flags)
        .arg(&user)
        .arg("--dump-dom")
        .arg(url)
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        dom.contains("id=\"status\""),
        "chromium on {url}: exit {:?}, stderr tail: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
            .lines()
            .rev()
            .take(5)
            .collect::<Vec<_>>()
            .join(" | ")
    );
    std::fs::create_dir_all(shot.parent().unwrap()).unwrap();
    let _ = Command::new(browser)
        .args(&flags)
        .arg(&user)
        .arg(format!("--screenshot={}", shot.display()))
        .arg(url)
        .output();
    dom
}

fn shots() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/live-screenshots")
}

/// The text of the element with `id` in `dom` (up to its first tag's end).
fn text_of(dom: &str, id: &str) -> String {
    let at = dom
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("#{id} in the page"));
    let rest = &dom[at..];
    let start = rest.find('>').unwrap() + 1;
    let end = rest[start..].find("</").unwrap() + start;
    rest[start..end].to_string()
}

/// The page opened while a slowed sil jump runs: what it shows at the end came through the
/// event stream (the snapshot it loaded first was taken early in the run).
#[test]
fn a_browser_receives_a_running_jump_through_the_stream() {
    let Some(browser) = chromium() else {
        return;
    };
    let (mut child, rx) = common::start_with_stderr_lines(
        &[
            "hil",
            "--kind",
            "delayed",
            "--tau",
            "0.1",
            "--freq",
            "10",
            "--live",
            "127.0.0.1:0",
            "--pace",
            "0.25",
            "--linger",
            "3",
        ],
        Stdio::null(),
    );
    let first = rx.recv_timeout(Duration::from_secs(60)).unwrap();
    let url = first
        .strip_prefix("live view: ")
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or_else(|| panic!("{first}"))
        .to_string();
    // Chromium keeps the page until the server closes (after the linger), then dumps it.
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(&browser)
        .args(HEADLESS)
        .arg("--virtual-time-budget=60000")
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("--dump-dom")
        .arg(&url)
        .output()
        .unwrap();
    let _ = child.kill();
    let _ = child.wait();
    let dom = String::from_utf8_lossy(&out.stdout);
    let status = text_of(&dom, "status");
    assert!(status.contains("ENDED: jump height"), "{status}");
    // The chart's points (the page sets them on every redraw): every 2 ms bin's two points
    // of the whole run (10 samples a point), most of them streamed.
    let samples = samples_in(&status) as usize;
    let points: usize = dom
        .split("data-points=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(
        samples > 5_000 && points >= samples / 10 - 5,
        "{points} points on the chart; {status}"
    );
    assert!(dom.contains("title=\"Done from"), "the strip");
}

#[test]
fn a_browser_shows_a_jump_a_campaign_and_a_fault() {
    let Some(browser) = chromium() else {
        return;
    };
    // A sil jump: samples and the final state.
    let (mut jump, url) = run_live(&["hil", "--kind", "delayed", "--tau", "0.1", "--freq", "10"]);
    let dom = page(&browser, &url, &shots().join("jump.png"));
    let _ = jump.kill();
    let _ = jump.wait();
    let status = text_of(&dom, "status");
    assert!(status.contains("ENDED: jump height"), "{status}");
    let samples = samples_in(&status);
    assert!(samples > 5_000, "{status}");
    assert!(dom.contains("<canvas"), "the charts are drawn");
    assert!(
        dom.contains("Running") && dom.contains("Done"),
        "the state strip"
    );
    // The small example campaign: every point in the table, the counts.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/campaign-small.toml"
    );
    let (mut camp, url) = run_live(&[
        "campaign",
        "run",
        file,
        "--link",
        "sil",
        "--out",
        out.to_str().unwrap(),
    ]);
    let dom = page(&browser, &url, &shots().join("campaign.png"));
    let _ = camp.kill();
    let _ = camp.wait();
    assert!(text_of(&dom, "c-done").contains("done 8 / 8"), "{dom}");
    assert!(text_of(&dom, "c-failed").contains("failed 0"));
    assert!(dom.matches("<td>").count() >= 8 * 5, "the table of points");
    // A fault (encoder noise beyond the tracking limit): the banner.
    let (mut fault, url) = run_live(&[
        "hil",
        "--kind",
        "single",
        "--freq",
        "10",
        "--encoder-noise",
        "500",
    ]);
    let dom = page(&browser, &url, &shots().join("fault.png"));
    let _ = fault.kill();
    let _ = fault.wait();
    let banner = text_of(&dom, "banner");
    assert!(banner.starts_with("FAULT: "), "{banner}");
    assert!(
        dom.contains("title=\"Faulted from"),
        "the strip shows the Faulted state"
    );
}

/// DNS rebinding as a browser meets it: a site's name resolved to this machine's loopback
/// (`--host-resolver-rules`), its page loaded from the live view's port. The browser sends
/// the site's name as `Host`, and the page, its state and its stream answer 403 with nothing of
/// the run; the same browser on the URL the command printed gets the page.
#[test]
fn a_page_under_a_foreign_host_name_gets_nothing_of_the_run() {
    let Some(browser) = chromium() else {
        return;
    };
    let (mut jump, url) = run_live(&["hil", "--kind", "single", "--freq", "10"]);
    let port = url
        .trim_end_matches('/')
        .rsplit(':')
        .next()
        .expect("a port in the URL")
        .to_string();
    let dump = |target: &str| {
        let profile = tempfile::tempdir().unwrap();
        let out = Command::new(&browser)
            .args(HEADLESS)
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("--host-resolver-rules=MAP rebound.example 127.0.0.1")
            .args(["--timeout=3000", "--dump-dom", target])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    const LEAKS: [&str; 4] = [
        "id=\"status\"",
        "samples_received",
        "jump height",
        "\"seq\"",
    ];
    // Chromium may dump before the answer has come: each URL tried until it shows one; every
    // dump of a foreign name is checked, not only the last.
    let answered = |target: &str, what: &str, foreign: bool| {
        let mut dom = String::new();
        for _ in 0..10 {
            dom = dump(target);
            if foreign {
                for leak in LEAKS {
                    assert!(!dom.contains(leak), "{target} shows `{leak}`: {dom}");
                }
            }
            if dom.contains(what) {
                break;
            }
            std::thread::sleep(Duration::from_millis(300));
        }
        dom
    };
    for path in ["/", "/state.json", "/events"] {
        let foreign = format!("http://rebound.example:{port}{path}");
        let dom = answered(&foreign, "403", true);
        assert!(dom.contains("403"), "{foreign}: {dom}");
    }
    // The control: the printed URL in the same browser.
    let dom = answered(&url, "id=\"status\"", false);
    let _ = jump.kill();
    let _ = jump.wait();
    assert!(dom.contains("id=\"status\""), "{url}: {dom}");
}
