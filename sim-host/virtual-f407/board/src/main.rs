//! `virtual-f407`: the rig's F407 firmware ELF on the virtual board.
//!
//! ```text
//! virtual-f407 --elf ELF [--ms N] [--run] [--gdb ADDR [--gdb-wait]] [--bed ready|unwired] [--estop closed|open] [--pace X] [--stdio] [--clock FILE]
//!              [--crystal-stops-at MS]
//!              [--robot PARAMS.toml --model hard|eq4|... [--p0 M]] [--summary FILE.json]
//!              [--intrusion PARAMS.toml --model eq4|... --surface-p M]
//! ```
//! `--run`: as `probe-rs run` runs a board: at real time (unless `--pace`), the firmware's log on
//! stdout line by line as it comes, until Ctrl-C (or `--ms`); what the firmware's `cargo run`
//! does when no debug probe is attached (firmware/runner.sh).
//! `--gdb ADDR`: serve GDB's remote protocol on ADDR (`127.0.0.1:3333`; port 0: any free port)
//! for the ELF as it runs: `gdb-multiarch ELF -ex 'target remote ADDR'` breaks, steps, reads
//! registers and memory while the robot runs on the other side of the pins (virtual time stands
//! still while the debugger holds the core). The address served is the first line on stderr.
//! `--gdb-wait`: the core waits before its first instruction until the debugger continues.
//! `--crystal-stops-at MS`: the 8 MHz crystal stops for good at MS virtual milliseconds (the
//! clock security system's fall-back to the HSI and its NMI, RM0090 6.2.7): rehearse the
//! firmware's handling of it, under GDB if you like.
//! `--stdio`: the USB CDC port's bytes are this process's stdin (host to board) and stdout
//! (board to host), as a serial port would carry them; the run ends when stdin closes (or at
//! `--ms`). The firmware's log goes to stderr. Exit status 2 on bad input.
//! `--clock FILE`: the board's virtual time, ns, written in place at most every 10 ms of wall
//! time and at the end, as a u64 little-endian at offset 0 and its bitwise complement at
//! offset 8 (a read that catches a write half done sees them disagree): a host counts its
//! waits in the board's time with it (stdout carries the USB bytes only).

use std::io::{Read, Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::{Duration, Instant};

use sandjumper_virtual_f407::rig::{BedWiring, EmergencyStopLoop, Robot};
use sandjumper_virtual_f407::run::{self, HostPort, NoHost, RunConfig, RunReport};

fn fail(msg: impl std::fmt::Display) -> ! {
    eprintln!("virtual-f407: {msg}");
    std::process::exit(2);
}

/// The USB CDC port on stdin/stdout.
struct Stdio {
    rx: Receiver<Vec<u8>>,
    out: std::io::Stdout,
}

impl HostPort for Stdio {
    fn receive(&mut self) -> Option<Vec<u8>> {
        let mut all = Vec::new();
        loop {
            match self.rx.try_recv() {
                Ok(b) => all.extend(b),
                Err(TryRecvError::Empty) => return Some(all),
                Err(TryRecvError::Disconnected) => {
                    return if all.is_empty() { None } else { Some(all) };
                }
            }
        }
    }
    fn send(&mut self, bytes: &[u8]) {
        let mut out = self.out.lock();
        let _ = out.write_all(bytes);
        let _ = out.flush();
    }
}

/// How often `--clock FILE` is rewritten at most, wall time.
const CLOCK_EVERY: Duration = Duration::from_millis(10);

/// `--clock FILE`: the board's virtual time for the host.
struct ClockFile {
    file: std::fs::File,
    path: PathBuf,
    /// Wall time of the last write.
    written: Option<Instant>,
    /// A write failed (reported once).
    failed: bool,
}

impl ClockFile {
    /// Create (or empty) `path`; exit 2 when it cannot be.
    fn create(path: PathBuf) -> Self {
        let file = std::fs::File::create(&path)
            .unwrap_or_else(|e| fail(format!("--clock {}: {e}", path.display())));
        Self {
            file,
            path,
            written: None,
            failed: false,
        }
    }

    /// Write `now_ns` in place (the first failure said on stderr; the host then sees the clock
    /// stand still).
    fn write(&mut self, now_ns: u64) {
        let mut bytes = [0u8; 16];
        bytes[..8].copy_from_slice(&now_ns.to_le_bytes());
        bytes[8..].copy_from_slice(&(!now_ns).to_le_bytes());
        let written = self
            .file
            .seek(SeekFrom::Start(0))
            .and_then(|_| self.file.write_all(&bytes));
        self.written = Some(Instant::now());
        if let Err(e) = written
            && !std::mem::replace(&mut self.failed, true)
        {
            eprintln!("virtual-f407: --clock {}: {e}", self.path.display());
        }
    }
}

/// A host port that also passes the board's clock to `--clock FILE`.
struct Clocked<H> {
    port: H,
    clock: Option<ClockFile>,
}

impl<H: HostPort> HostPort for Clocked<H> {
    fn receive(&mut self) -> Option<Vec<u8>> {
        self.port.receive()
    }
    fn send(&mut self, bytes: &[u8]) {
        self.port.send(bytes);
    }
    fn clock(&mut self, now_ns: u64) {
        if let Some(c) = self.clock.as_mut()
            && c.written.is_none_or(|t| t.elapsed() >= CLOCK_EVERY)
        {
            c.write(now_ns);
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut elf: Option<PathBuf> = None;
    let mut ms: Option<u64> = None;
    let mut bed = BedWiring::READY;
    let mut emergency_stop = EmergencyStopLoop::Closed;
    let mut pace = None;
    let mut stdio = false;
    let mut live = false;
    let mut gdb: Option<String> = None;
    let mut gdb_wait = false;
    let mut robot_params: Option<PathBuf> = None;
    let mut intrusion_params: Option<PathBuf> = None;
    let mut surface_p = 0.0;
    let mut model = "eq4".to_string();
    let mut p0 = 0.0;
    let mut summary: Option<PathBuf> = None;
    let mut clock: Option<PathBuf> = None;
    let mut crystal_stops_at_ns: Option<u64> = None;
    while let Some(a) = args.next() {
        let mut value = |name: &str| {
            args.next()
                .unwrap_or_else(|| fail(format!("{name} needs a value")))
        };
        match a.as_str() {
            "--elf" => elf = Some(value("--elf").into()),
            "--ms" => {
                ms = Some(
                    value("--ms")
                        .parse()
                        .unwrap_or_else(|_| fail("--ms: a whole number of virtual milliseconds")),
                )
            }
            "--bed" => {
                bed = match value("--bed").as_str() {
                    "ready" => BedWiring::READY,
                    "unwired" => BedWiring::Unwired,
                    other => fail(format!("--bed {other}: allowed ready, unwired")),
                }
            }
            "--estop" => {
                emergency_stop = match value("--estop").as_str() {
                    "closed" => EmergencyStopLoop::Closed,
                    "open" => EmergencyStopLoop::Open,
                    other => fail(format!(
                        "--estop {other}: allowed closed (released, or a jumper plug), open (pressed or not wired)"
                    )),
                }
            }
            "--pace" => {
                const PACE: &str = "--pace: a number from 0.001 to 1000 (1 = real time)";
                let x: f64 = value("--pace").parse().unwrap_or_else(|_| fail(PACE));
                if !(1e-3..=1e3).contains(&x) {
                    fail(PACE);
                }
                pace = Some(x);
            }
            "--stdio" => stdio = true,
            "--run" => live = true,
            "--gdb" => gdb = Some(value("--gdb")),
            "--gdb-wait" => gdb_wait = true,
            "--robot" => robot_params = Some(value("--robot").into()),
            "--intrusion" => intrusion_params = Some(value("--intrusion").into()),
            "--surface-p" => {
                surface_p = value("--surface-p")
                    .parse::<f64>()
                    .ok()
                    .filter(|p| p.is_finite())
                    .unwrap_or_else(|| fail("--surface-p: metres, a finite number"))
            }
            "--model" => model = value("--model"),
            "--p0" => {
                p0 = value("--p0")
                    .parse()
                    .unwrap_or_else(|_| fail("--p0: metres"))
            }
            "--summary" => summary = Some(value("--summary").into()),
            "--clock" => clock = Some(value("--clock").into()),
            "--crystal-stops-at" => {
                const MS: &str = "--crystal-stops-at: whole virtual milliseconds, 1 or more";
                let m: u64 = value("--crystal-stops-at")
                    .parse()
                    .unwrap_or_else(|_| fail(MS));
                crystal_stops_at_ns = Some(
                    m.checked_mul(1_000_000)
                        .filter(|&ns| ns > 0)
                        .unwrap_or_else(|| fail(MS)),
                );
            }
            "-h" | "--help" => {
                println!(
                    "{}",
                    include_str!("main.rs")
                        .lines()
                        .skip(2)
                        .take_while(|l| l.starts_with("//!"))
                        .map(|l| l.trim_start_matches("//! "))
                        .collect::<Vec<_>>()
                        .join("\n")
                );
                return;
            }
            other => fail(format!("unknown argument {other} (see --help)")),
        }
    }
    let Some(elf) = elf else {
        fail(
            "--elf ELF is required (the F407 release build: target/thumbv7em-none-eabihf/release/sandjumper-firmware)",
        )
    };
    if !stdio && !live && ms.is_none() {
        fail("give --ms N (virtual milliseconds), --run or --stdio");
    }
    if stdio && live {
        fail(
            "--run and --stdio are exclusive: --run prints the log on stdout, --stdio carries USB there",
        );
    }
    let mut cfg = RunConfig::new(elf.clone());
    cfg.until_ns = ms.map(|m| {
        m.checked_mul(1_000_000)
            .filter(|&ns| ns > 0)
            .unwrap_or_else(|| {
                fail(format!(
                    "--ms {m}: 1 to {} virtual milliseconds",
                    u64::MAX / 1_000_000
                ))
            })
    });
    if let Ok(p) = std::env::var("VIRTUAL_F407_PERIOD_NS") {
        cfg.period_ns = p
            .parse()
            .ok()
            .filter(|ns| (1_000..=1_000_000).contains(ns))
            .unwrap_or_else(|| fail(format!("VIRTUAL_F407_PERIOD_NS={p}: 1000 to 1000000 ns")));
    }
    cfg.bed = bed;
    cfg.emergency_stop = emergency_stop;
    if let Some(at_ns) = crystal_stops_at_ns {
        cfg.actions.push((at_ns, run::Action::CrystalStops));
    }
    cfg.pace = pace.or(live.then_some(1.0));
    cfg.echo_log = live;
    if gdb_wait && gdb.is_none() {
        fail("--gdb-wait needs --gdb ADDR");
    }
    if let Some(addr) = gdb {
        let listener = std::net::TcpListener::bind(&addr).unwrap_or_else(|e| {
            fail(format!(
                "--gdb {addr}: cannot listen there ({e}; allowed: HOST:PORT, e.g. 127.0.0.1:3333)"
            ))
        });
        let served = listener
            .local_addr()
            .map_or(addr.clone(), |a| a.to_string());
        eprintln!(
            "virtual-f407: GDB server on {served}: gdb-multiarch {} -ex 'target remote {served}'{}",
            elf.display(),
            if gdb_wait {
                " (the core waits for it)"
            } else {
                ""
            }
        );
        cfg.debugger = Some(listener);
        cfg.wait_for_debugger = gdb_wait;
    }
    if let Some(path) = robot_params {
        let params = read_params(&path, "--robot");
        let model: sandjumper_model::params::ModelName = model
            .parse()
            .unwrap_or_else(|e| fail(format!("--model {model}: {e}")));
        cfg.robot = Some(
            Robot::new(&params, model, p0).unwrap_or_else(|e| fail(format!("the robot: {e}"))),
        );
    }
    if let Some(path) = intrusion_params {
        if cfg.robot.is_some() {
            fail("--robot and --intrusion are exclusive: the drive moves one or the other");
        }
        let params = read_params(&path, "--intrusion");
        let model: sandjumper_model::params::ModelName = model
            .parse()
            .unwrap_or_else(|e| fail(format!("--model {model}: {e}")));
        cfg.intrusion = Some(
            sandjumper_model::intrusion_rig::IntrusionRig::new(&params, model, surface_p)
                .unwrap_or_else(|e| fail(format!("the intrusion fixture: {e}"))),
        );
    }
    let clock = clock.map(ClockFile::create);
    let report = if stdio {
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut stdin = std::io::stdin();
            let mut buf = [0u8; 4096];
            while let Ok(n @ 1..) = stdin.read(&mut buf) {
                if tx.send(buf[..n].to_vec()).is_err() {
                    break;
                }
            }
        });
        let port = Stdio {
            rx,
            out: std::io::stdout(),
        };
        run::run(cfg, Clocked { port, clock }).map(|(r, h)| (r, h.clock))
    } else {
        let port = NoHost::default();
        run::run(cfg, Clocked { port, clock }).map(|(r, h)| (r, h.clock))
    };
    let (report, clock) = report.unwrap_or_else(|e| fail(e));
    if let Some(mut c) = clock {
        c.write(report.end_ns);
    }
    print_report(&report);
    if let Some(path) = summary {
        std::fs::write(&path, summary_json(&report))
            .unwrap_or_else(|e| fail(format!("--summary {}: {e}", path.display())));
    }
}

/// Resolved parameters (TOML, every field) from `path`, named as `flag` in errors.
fn read_params(path: &std::path::Path, flag: &str) -> sandjumper_model::params::Params {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| fail(format!("{flag} {}: {e}", path.display())));
    toml::from_str(&text).unwrap_or_else(|e| fail(format!("{flag} {}: {e}", path.display())))
}

fn print_report(r: &RunReport) {
    let mut err = std::io::stderr();
    for line in &r.log {
        let _ = writeln!(err, "firmware: {line}");
    }
    let _ = writeln!(
        err,
        "virtual-f407: {:.3} s virtual in {:.3} s wall ({:.2}x real time); SYSCLK {} Hz, 48 MHz domain {} Hz; stop {}",
        r.end_ns as f64 * 1e-9,
        r.wall_s,
        r.end_ns as f64 * 1e-9 / r.wall_s.max(1e-9),
        r.clocks_hz.0,
        r.clocks_hz.1,
        r.stop
    );
    if let Some(last) = r.last {
        let _ = writeln!(
            err,
            "virtual-f407: outputs at the end {:?}; ticks {}; usb configured {}",
            last.out, last.ticks, last.usb_configured
        );
    }
    for g in &r.gaps {
        let _ = writeln!(err, "virtual-f407: {g}");
    }
    for (t, c) in &r.resets {
        let _ = writeln!(err, "virtual-f407: reset at {t} ns: {c}");
    }
    for v in &r.flash_violations {
        let _ = writeln!(err, "virtual-f407: flash wait states too few {v}");
    }
    for t in &r.told {
        let _ = writeln!(err, "virtual-f407: the part told: {t}");
    }
}

fn summary_json(r: &RunReport) -> String {
    let jump = r
        .robot
        .as_ref()
        .map(|robot| robot.plant().summary().jump_height_m);
    let num = |x: Option<f64>| {
        x.filter(|v| v.is_finite())
            .map_or("null".to_string(), |v| format!("{v}"))
    };
    format!(
        "{{\n  \"virtual_s\": {},\n  \"wall_s\": {},\n  \"jump_height_m\": {},\n  \"plant_error\": {},\n  \"encoder_deferred_counts\": {},\n  \"log_lines\": {},\n  \"flash_violations\": {}\n}}\n",
        r.end_ns as f64 * 1e-9,
        r.wall_s,
        num(jump),
        r.plant_error
            .as_ref()
            .map_or("null".into(), |e| format!("{e:?}")),
        r.encoder_deferred_counts,
        r.log.len(),
        r.flash_violations.len()
    )
}
