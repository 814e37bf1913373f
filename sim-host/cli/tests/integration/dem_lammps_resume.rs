//! `sandjumper dem lammps` killed with `kill -9` (the whole process group: sandjumper,
//! mpiexec and the LAMMPS ranks, as a node lost or a time limit past its grace leaves them)
//! and run again with the same command: it resumes from the newest restart file and ends
//! where the unbroken run ends, within LAMMPS's own reproducibility.
//!
//! 1. A run killed while its bed settles (at a random step, its seed printed) resumes the
//!    settle from its restart file.
//! 2. That bed is reused (`--bed`) by a second run of the same intrusion, killed at a random
//!    step mid-way and resumed; the first run's intrusion, unbroken on the same bed with the same restart
//!    cadence, is the reference. The foot's path and the clock are the same to the last
//!    digit, the windows before the resume are the unbroken run's to the last digit, and the
//!    force after it stays within what LAMMPS itself gives on another decomposition (the
//!    same run on 1 rank against 2 differs by a median 0.9 % a window here, up to 35 %).
//! 3. While the resume runs, a second writer is refused naming the holder; another run into
//!    an unfinished output of other inputs is refused (exit 2).
//!
//! Scaled down: the small preset in a 40 x 40 x 30 mm bed (about 6,800 grains), the foot at
//! 0.1 m/s to 2 mm then 0.05 m/s to 4 mm (two pieces of `fix move`), on 2 ranks.

use std::io::Write as _;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;
use common::summary_json as summary;

/// The run's arguments into `out` (and `extra`).
fn args(lmp: &Path, trajectory: &Path, out: &Path, extra: &[&str]) -> Vec<String> {
    let mut a: Vec<String> = [
        "dem",
        "lammps",
        "--preset",
        "small",
        "--bed-width",
        "0.04",
        "--bed-depth",
        "0.03",
        "--ranks",
        "2",
        // About every 600 intrusion steps and 1,000 settle steps at the measured rates.
        "--restart-every",
        "0.015",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    a.extend(["--lmp".into(), lmp.display().to_string()]);
    a.extend(["--trajectory".into(), trajectory.display().to_string()]);
    a.extend(["--out".into(), out.display().to_string()]);
    a.extend(extra.iter().map(|s| s.to_string()));
    a
}

/// The restart files of `stage` in the unfinished folder of `out`, as steps.
fn restart_steps(out: &Path, stage: &str) -> Vec<u64> {
    let dir = PathBuf::from(format!("{}.unfinished/lammps/restart", out.display()));
    std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(Result::ok)
                .filter_map(|e| {
                    e.file_name()
                        .to_string_lossy()
                        .strip_prefix(&format!("{stage}."))?
                        .parse::<u64>()
                        .ok()
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The last window `force.txt` of the unfinished run into `out` holds.
fn last_window(out: &Path) -> u64 {
    std::fs::read_to_string(format!("{}.unfinished/lammps/force.txt", out.display()))
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.split_whitespace().next()?.parse::<u64>().ok())
        .max()
        .unwrap_or(0)
}

/// Run `args` in a process group of its own and `kill -9` the group `then` after `stage` has
/// written a restart file at or after `step` (and an older one: one whole file at least),
/// and, in the intrusion, a force window past the newest restart file (what the resume must
/// cut away). The restart files' steps seen just before the kill, oldest first.
fn run_and_kill(args: &[String], out: &Path, stage: &str, step: u64, then: Duration) -> Vec<u64> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let steps = restart_steps(out, stage);
        let newest = steps.iter().copied().max().unwrap_or(0);
        let past = stage != "intrude" || last_window(out) > newest + 100;
        if steps.len() >= 2 && newest >= step && past {
            break;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was killed"
        );
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "no restart file of {stage}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // A random moment after it: mid-interval, or while the next file is being written.
    std::thread::sleep(then);
    let mut seen = restart_steps(out, stage);
    seen.sort_unstable();
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run ended before it was killed"
    );
    let group = child.id().to_string();
    let killed = Command::new("kill")
        .args(["-s", "KILL", "--", &format!("-{group}")])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), None, "killed by a signal");
    // The ranks are gone with the group: nothing writes the folder any more.
    std::thread::sleep(Duration::from_millis(300));
    seen
}

/// `force.txt` as rows of (step, [t, force, zmin] as text).
fn force_rows(dir: &Path) -> Vec<(u64, Vec<String>)> {
    std::fs::read_to_string(dir.join("lammps/force.txt"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let w: Vec<String> = l.split_whitespace().map(str::to_string).collect();
            (w[0].parse().unwrap(), w[1..].to_vec())
        })
        .collect()
}

fn run_toml(dir: &Path) -> toml::Value {
    toml::from_str(&std::fs::read_to_string(dir.join("lammps/run.toml")).unwrap()).unwrap()
}

#[test]
fn a_run_killed_with_kill_9_resumes_from_its_restart_file_to_the_unbroken_result() {
    let Some(lmp) = common::lammps() else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let trajectory = work.path().join("two-speeds.csv");
    let mut f = std::fs::File::create(&trajectory).unwrap();
    writeln!(f, "t_s,depth_m\n0,0\n0.02,0.002\n0.06,0.004").unwrap();
    drop(f);

    // Where each stage is killed: random steps, the seed printed (and taken from
    // SANDJUMPER_KILL_SEED to repeat a failure).
    let seed = std::env::var("SANDJUMPER_KILL_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_nanos() as u64)
        });
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(seed);
    let settle_kill = rand::RngExt::random_range(&mut rng, 3000..=6000u64);
    let intrude_kill = rand::RngExt::random_range(&mut rng, 800..=2400u64);
    let settle_then = Duration::from_millis(rand::RngExt::random_range(&mut rng, 0..1500u64));
    let intrude_then = Duration::from_millis(rand::RngExt::random_range(&mut rng, 0..600u64));
    eprintln!(
        "SANDJUMPER_KILL_SEED={seed}: the settle killed {settle_then:?} after a restart file \
         past step {settle_kill}, the intrusion {intrude_then:?} after one past step {intrude_kill}"
    );

    // 1. Killed while the bed settles, resumed.
    let a = work.path().join("a");
    let seen = run_and_kill(
        &args(&lmp, &trajectory, &a, &[]),
        &a,
        "settle",
        settle_kill,
        settle_then,
    );
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args(&lmp, &trajectory, &a, &[]))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("resuming the unfinished run"), "{e}");
    assert!(
        e.contains("the settle resumed from its restart file of step"),
        "{e}"
    );
    // From the newest restart file seen before the kill, or the one before it (the newest
    // may have been cut mid-write), or one written in the last moment before the kill.
    let settle_from = run_toml(&a)["settle_resumed_from"].as_integer().unwrap() as u64;
    assert!(
        seen.len() >= 2 && settle_from >= seen[seen.len() - 2],
        "resumed from {settle_from}; restart files seen before the kill: {seen:?}"
    );
    assert!(!work.path().join("a.unfinished").exists());
    assert!(!a.join("lammps/restart").exists(), "restart files removed");

    // A periodic bed is refused for a run against a sidewall, before anything is made.
    let walled = work.path().join("walled");
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args(
            &lmp,
            &trajectory,
            &walled,
            &["--bed", a.to_str().unwrap(), "--sidewall"],
        ))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("settled without sidewalls"), "{e}");
    assert!(!work.path().join("walled.unfinished").exists());

    // 2. The same intrusion on that bed, killed mid-way and resumed.
    let b = work.path().join("b");
    let bed = ["--bed", a.to_str().unwrap()];
    let seen = run_and_kill(
        &args(&lmp, &trajectory, &b, &bed),
        &b,
        "intrude",
        intrude_kill,
        intrude_then,
    );
    // Another run into the same output is refused while it is unfinished.
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args(
            &lmp,
            &trajectory,
            &b,
            &["--bed", a.to_str().unwrap(), "--seed", "9"],
        ))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("holds an unfinished run of other inputs"), "{e}");
    // The resume; a second writer while it runs is refused, naming it.
    let resume = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args(&lmp, &trajectory, &b, &bed))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !(b.with_file_name("b.unfinished/lammps/in.intrude").is_file()
        && std::fs::read_to_string(b.with_file_name("b.unfinished/lammps/in.intrude"))
            .unwrap_or_default()
            .contains("# resumed from step"))
    {
        assert!(start.elapsed() < Duration::from_secs(120), "no resume");
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args(&lmp, &trajectory, &b, &bed))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("is locked by process") && e.contains("one run writes this state at a time"),
        "{e}"
    );
    let o = resume.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("the intrusion resumed from its restart file of step"),
        "{e}"
    );
    let from = run_toml(&b)["intrusion_resumed_from"].as_integer().unwrap() as u64;
    assert!(
        seen.len() >= 2 && from >= seen[seen.len() - 2],
        "resumed from {from}; restart files seen before the kill: {seen:?}"
    );

    // 3. The resumed intrusion against the unbroken one on the same bed, and LAMMPS's own
    // reproducibility: the same unbroken run on 1 rank instead of 2.
    let c = work.path().join("c");
    let mut one = args(&lmp, &trajectory, &c, &bed);
    let at = one.iter().position(|w| w == "--ranks").unwrap();
    one[at + 1] = "1".into();
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(&one)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (unbroken, resumed, one_rank) = (force_rows(&a), force_rows(&b), force_rows(&c));
    let steps = |rows: &[(u64, Vec<String>)]| rows.iter().map(|r| r.0).collect::<Vec<_>>();
    assert_eq!(
        steps(&unbroken),
        steps(&resumed),
        "the same windows, none twice"
    );
    assert_eq!(steps(&unbroken), steps(&one_rank));
    let force = |r: &[String]| r[1].parse::<f64>().unwrap();
    let (mut after, mut decomposition) = (Vec::new(), Vec::new());
    for (((step, u), (_, r)), (_, o)) in unbroken.iter().zip(&resumed).zip(&one_rank) {
        // The clock and the foot's path: to the last digit.
        assert_eq!((&u[0], &u[2]), (&r[0], &r[2]), "window ending at {step}");
        if *step <= from {
            assert_eq!(u, r, "before the resume: the unbroken run's own windows");
        } else {
            let scale = force(u).abs().max(1e-9);
            after.push((force(u) - force(r)).abs() / scale);
            decomposition.push((force(u) - force(o)).abs() / scale);
        }
    }
    assert!(
        after[0] < 1e-3,
        "the first window after the resume: {} (the contacts' history kept)",
        after[0]
    );
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (resumed_median, one_rank_median) = (median(after), median(decomposition));
    eprintln!(
        "after step {from}: the resumed run differs from the unbroken one by a median \
         {resumed_median:.4} a window, the same run on 1 rank by {one_rank_median:.4}"
    );
    assert!(
        resumed_median <= 1.5 * one_rank_median + 0.01,
        "resumed {resumed_median}, another decomposition {one_rank_median}"
    );
    // The summary's medians over some thirty windows inherit the windows' drift: within a
    // fifth, or twice what the decomposition alone moves them.
    let (su, sr, so) = (summary(&a), summary(&b), summary(&c));
    assert_eq!(su["frames"], sr["frames"]);
    assert_eq!(su["max_depth_m"], sr["max_depth_m"]);
    for key in [
        "added_mass_vs_eq6_median",
        "force_vs_penetration_force_median",
        "grain_momentum_under_foot_kg_m_s",
    ] {
        let value = |s: &serde_json::Value| s[key].as_f64().unwrap();
        let (u, r, o) = (value(&su), value(&sr), value(&so));
        assert!(
            (u - r).abs() <= (0.2 * u.abs()).max(2.0 * (u - o).abs()),
            "{key}: {u} unbroken, {r} resumed, {o} on 1 rank"
        );
    }
    assert!(!work.path().join("b.unfinished").exists());
}
