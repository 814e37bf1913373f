//! The soak (#54): `examples/campaign-soak.toml`, 240 points at full speed through the
//! simulated bed and controller, with the live page open and 20 clients polling
//! `/state.json` all the while. Once unbroken, watching the process's memory point by point;
//! once killed (`kill -9`) at random moments and resumed, each session with its page and its
//! 20 clients. Asserted: every client is answered with the whole state while the campaign
//! runs, the memory after the first quarter of the points does not grow with the points, the
//! page's state stays small, and the killed-and-resumed campaign's results equal the
//! unbroken one's. Its speed with and without the clients is a benchmark's
//! (`sim-host/campaign/benches/soak.sh`, docs/performance.md), never asserted here.
#![cfg(feature = "live")]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;

use rand::{RngExt, SeedableRng};

use crate::common::read;

const SOAK: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/campaign-soak.toml"
);

/// Points of the soak's campaign.
const POINTS: usize = 240;

/// Clients polling `/state.json`.
const CLIENTS: usize = 20;

/// How much the process's resident memory may grow from the end of the first quarter of the
/// points to the end, bytes. A point's acquisition log alone is ~0.4 MB (10 kHz, 0.5 s, 10
/// channels of f64): keeping each one would grow it by ~70 MB over the other 180 points.
const MAX_GROWTH_B: u64 = 24 << 20;

/// The most `state.json` may weigh at the end, bytes (240 point records and the events).
const MAX_STATE_B: usize = 2 << 20;

/// What the clients saw.
#[derive(Default)]
struct Polls {
    /// Whole states received (status 200, JSON that parses, a page's state).
    answered: AtomicU64,
    /// Requests that failed while the run was said to be on.
    failed: AtomicU64,
    /// The first failure, for the message.
    first_failure: Mutex<Option<String>>,
}

/// `GET /state.json` with the server's own `Host`: the body of a 200, or why not.
fn state_json(addr: &str) -> Result<String, String> {
    let (status, _, body) = crate::common::http_get(addr, "/state.json")?;
    if !status.starts_with("HTTP/1.1 200") {
        return Err(status);
    }
    Ok(body)
}

/// The page the clients poll: its generation (one per change) and address, `None` while no
/// page should answer.
type Page = Arc<Mutex<(u64, Option<String>)>>;

/// Poll the page in `page` (when there is one) until `stop`; count whole states, and the
/// failures of a page that was up before and after the request (the same generation).
fn client(page: Page, stop: Arc<AtomicBool>, polls: Arc<Polls>) {
    while !stop.load(Ordering::SeqCst) {
        let (generation, Some(a)) = page.lock().unwrap().clone() else {
            std::thread::sleep(Duration::from_millis(5));
            continue;
        };
        let got = state_json(&a).and_then(|body| {
            let v: serde_json::Value =
                serde_json::from_str(&body).map_err(|e| format!("JSON: {e}"))?;
            // `campaign` is null until the session's first record reaches the page.
            if v.get("campaign").is_some() && v["seq"].is_u64() {
                Ok(())
            } else {
                Err(format!("no campaign in {}", &body[..body.len().min(200)]))
            }
        });
        match got {
            Ok(()) => {
                polls.answered.fetch_add(1, Ordering::SeqCst);
            }
            // A page that went away during the request (a kill, the end) is no failure.
            Err(e) if page.lock().unwrap().0 == generation => {
                polls.failed.fetch_add(1, Ordering::SeqCst);
                polls.first_failure.lock().unwrap().get_or_insert(e);
            }
            Err(_) => std::thread::sleep(Duration::from_millis(5)),
        }
    }
}

/// The 20 clients, polling whatever address the session in hand publishes.
struct Clients {
    page: Page,
    stop: Arc<AtomicBool>,
    polls: Arc<Polls>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl Clients {
    fn start() -> Self {
        let page: Page = Arc::new(Mutex::new((0, None)));
        let stop = Arc::new(AtomicBool::new(false));
        let polls = Arc::new(Polls::default());
        let threads = (0..CLIENTS)
            .map(|_| {
                let (g, s, p) = (page.clone(), stop.clone(), polls.clone());
                std::thread::spawn(move || client(g, s, p))
            })
            .collect();
        Self {
            page,
            stop,
            polls,
            threads,
        }
    }

    /// A session's page is up at `addr` (`Some`), or going away (`None`): a new generation.
    fn page(&self, addr: Option<String>) {
        let mut p = self.page.lock().unwrap();
        *p = (p.0 + 1, addr);
    }

    fn stop(self) -> Arc<Polls> {
        self.page(None);
        self.stop.store(true, Ordering::SeqCst);
        for t in self.threads {
            t.join().unwrap();
        }
        self.polls
    }
}

/// A session of the campaign with its page, its stdout and stderr as lines.
struct Session {
    child: Child,
    stdout: mpsc::Receiver<String>,
    stderr: mpsc::Receiver<String>,
}

fn lines_of(r: impl Read + Send + 'static) -> mpsc::Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(r).lines().map_while(Result::ok) {
            let _ = tx.send(l);
        }
    });
    rx
}

impl Session {
    fn start(args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
            .args(args)
            // A long linger: the test ends each session itself once it has what it needs.
            .args(["--live", "127.0.0.1:0", "--linger", "60"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdout = lines_of(child.stdout.take().unwrap());
        let stderr = lines_of(child.stderr.take().unwrap());
        Self {
            child,
            stdout,
            stderr,
        }
    }

    /// The page's HOST:PORT, from the `live view: http://HOST:PORT/ ...` line.
    fn page(&self) -> String {
        let mut seen = String::new();
        loop {
            match self.stderr.recv_timeout(Duration::from_secs(120)) {
                Ok(l) if l.starts_with("live view: http://") => {
                    return l["live view: http://".len()..]
                        .split('/')
                        .next()
                        .unwrap()
                        .to_string();
                }
                Ok(l) => seen += &format!("{l}\n"),
                Err(_) => panic!("no live view line; stderr said:\n{seen}"),
            }
        }
    }

    /// Wait for the campaign's last line on stdout, then for the page to have its end state
    /// (the `the run has ended` line on stderr).
    fn wait_for_the_end(&self) {
        let end = self
            .stdout
            .iter()
            .find(|l| l.starts_with("campaign campaign-soak:"));
        assert!(end.is_some(), "the campaign's last line never came");
        let ended = self.stderr.iter().find(|l| l.contains("the run has ended"));
        assert!(ended.is_some(), "the page never said the run has ended");
    }

    /// The process's resident memory, bytes (`/proc/PID/status`), `None` once it is gone.
    fn rss(&self) -> Option<u64> {
        let s = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).ok()?;
        let kb = s.lines().find_map(|l| l.strip_prefix("VmRSS:"))?;
        Some(
            kb.trim()
                .trim_end_matches("kB")
                .trim()
                .parse::<u64>()
                .ok()?
                * 1024,
        )
    }
}

fn with_suffix(p: &Path, s: &str) -> PathBuf {
    let mut o = p.as_os_str().to_owned();
    o.push(s);
    PathBuf::from(o)
}

#[test]
fn a_long_campaign_watched_by_twenty_clients_and_killed_at_random_resumes_to_the_same_results() {
    let tmp = tempfile::tempdir().unwrap();

    // Unbroken, its memory read as each point is done.
    let straight = tmp.path().join("straight");
    let clients = Clients::start();
    let s = Session::start(&[
        "campaign",
        "run",
        SOAK,
        "--link",
        "sil",
        "--out",
        straight.to_str().unwrap(),
    ]);
    let addr = s.page();
    clients.page(Some(addr.clone()));
    // (points done, resident bytes) at each point's line.
    let mut memory: Vec<(usize, u64)> = Vec::new();
    let mut done = 0;
    for line in s.stdout.iter() {
        if line.starts_with("point ") {
            done += 1;
            if let Some(b) = s.rss() {
                memory.push((done, b));
            }
        }
        if done == POINTS {
            break;
        }
    }
    s.wait_for_the_end();
    let last_state = state_json(&addr).expect("the page lingers with the end state");
    clients.page(None);
    let polls = clients.stop();
    let Session { mut child, .. } = s;
    // Done and lingering: ended here rather than after the linger.
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(done, POINTS, "every point reported");

    let failed = polls.failed.load(Ordering::SeqCst);
    let answered = polls.answered.load(Ordering::SeqCst);
    assert_eq!(
        failed,
        0,
        "{failed} of the clients' requests failed while the page was up; the first: {:?}",
        polls.first_failure.lock().unwrap()
    );
    assert!(
        answered >= CLIENTS as u64,
        "the 20 clients got {answered} states in all"
    );
    let st: serde_json::Value = serde_json::from_str(&last_state).unwrap();
    assert_eq!(
        st["campaign"]["records"].as_array().unwrap().len(),
        POINTS,
        "every point's record, once"
    );
    assert!(
        last_state.len() < MAX_STATE_B,
        "state.json weighs {} bytes at the end",
        last_state.len()
    );
    let quarter = memory
        .iter()
        .find(|(d, _)| *d >= POINTS / 4)
        .map(|&(_, b)| b)
        .expect("memory read at a quarter of the points");
    let peak = memory.iter().map(|&(_, b)| b).max().unwrap();
    eprintln!(
        "unbroken: {answered} states served to {CLIENTS} clients; resident {:.1} MB at point {}, \
         peak {:.1} MB; state.json {} bytes",
        quarter as f64 / 1e6,
        POINTS / 4,
        peak as f64 / 1e6,
        last_state.len()
    );
    assert!(
        peak <= quarter + MAX_GROWTH_B,
        "resident memory grew from {quarter} bytes at point {} to {peak}: more than {MAX_GROWTH_B}",
        POINTS / 4
    );

    // Killed at random moments and resumed, each session watched by the 20 clients.
    let killed = tmp.path().join("killed");
    let k = killed.to_str().unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(54);
    let clients = Clients::start();
    let (mut kills, mut sessions) = (0, 0);
    const KILLS: usize = 6;
    loop {
        if killed.is_dir() {
            break; // finished, and killed while its page lingered
        }
        assert!(sessions <= KILLS, "the campaign never finished");
        let args: Vec<&str> = if with_suffix(&killed, ".incomplete").is_dir() {
            vec!["campaign", "resume", k]
        } else {
            vec!["campaign", "run", SOAK, "--link", "sil", "--out", k]
        };
        let s = Session::start(&args);
        sessions += 1;
        clients.page(Some(s.page()));
        if kills == KILLS {
            s.wait_for_the_end();
            clients.page(None);
            let Session { mut child, .. } = s;
            child.kill().unwrap(); // done and lingering
            child.wait().unwrap();
            break;
        }
        let Session { mut child, .. } = s;
        // A moment within the campaign's first seconds: before, between or inside points.
        std::thread::sleep(Duration::from_millis(rng.random_range(50..1500)));
        clients.page(None);
        match child.try_wait().unwrap() {
            Some(status) => {
                assert!(status.success(), "{args:?}: {status}");
                break;
            }
            None => {
                child.kill().unwrap(); // SIGKILL: no clean-up runs
                child.wait().unwrap();
                // A session killed while its page lingered had finished: no kill of a run.
                kills += usize::from(!killed.is_dir());
            }
        }
    }
    let polls = clients.stop();
    assert!(kills >= 3, "only {kills} kills: the soak proved little");
    assert!(killed.is_dir(), "finished under its own name");
    assert_eq!(
        read(&straight.join("results.csv")),
        read(&killed.join("results.csv")),
        "killed {kills} times and resumed: the same results"
    );
    let journal = read(&killed.join("journal.jsonl"));
    let done = journal
        .lines()
        .filter(|l| l.contains("\"event\":\"done\""))
        .count();
    assert_eq!(done, POINTS, "each point done exactly once");
    assert_eq!(
        polls.failed.load(Ordering::SeqCst),
        0,
        "a client's request failed while a session's page was up: {:?}",
        polls.first_failure.lock().unwrap()
    );
    eprintln!(
        "killed {kills} times over {sessions} sessions; {} states served",
        polls.answered.load(Ordering::SeqCst)
    );
}
