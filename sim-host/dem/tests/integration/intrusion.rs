//! Intrusions as calls (`sandjumper_dem::intrude_run::run`, #23): the same seed gives the
//! same bits on one or two threads and after a resume; the paper's added mass grows then
//! saturates under a foot in a wide bed, with the force resisting it; a jump's trajectory
//! is refused below the surface and its push-off is taken and resumed; and (module
//! `closed_loop`) PIV on the DEM's own frames finds the DEM's velocity field.
//!
//! What `dem intrude` writes, prints and refuses (files, `--json` keys, exit 2) is checked
//! at the command line, in `sim-host/cli/tests/integration/dem.rs`.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use sandjumper_dem::bed_run::{self, BedRequest};
use sandjumper_dem::intrude_run::{self, Episode, IntrudeOutcome, IntrudeRequest};
use sandjumper_dem::outputs::Summary;
use sandjumper_dem::request::ModelRequest;
use sandjumper_output::{Blame, Blamed, Progress, Silent};

#[path = "intrusion/closed_loop.rs"]
mod closed_loop;

/// The text of the file at `p`; panics naming the file when it cannot be read.
fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The notes a run gave.
#[derive(Default)]
struct Notes(Mutex<Vec<String>>);

impl Progress for Notes {
    fn note(&self, line: &str) {
        self.0.lock().unwrap().push(line.to_string());
    }
}

/// Grains and contacts of these runs: the defaults (`dem bed`'s and `dem intrude`'s) at a
/// 2 % overlap.
fn model() -> ModelRequest {
    ModelRequest {
        overlap: 0.02,
        ..ModelRequest::default()
    }
}

/// A packed bed (no gravity) 16 mm wide and 8 mm deep (`dem bed --pack 0.8 --width 0.016
/// --height 0.008 --overlap 0.02`): its folder.
fn bed(dir: &Path) -> PathBuf {
    bed_of(dir.join("bed"), 0.016, 0.008)
}

/// A packed bed (no gravity) 5 cm wide and 1.2 cm deep, wide against an 8 mm foot.
fn wide_bed(dir: &Path) -> PathBuf {
    bed_of(dir.join("wide"), 0.05, 0.012)
}

fn bed_of(out: PathBuf, width_m: f64, height_m: f64) -> PathBuf {
    bed_run::run(
        &BedRequest {
            model: model(),
            width_m,
            height_m,
            pack: Some(0.8),
            out,
            ..BedRequest::default()
        },
        &Silent,
    )
    .unwrap()
    .out
}

/// `dem intrude --bed BED --speed 0.3 --overlap 0.02 --walls --depth 0.002 --foot-width
/// 0.006 --out OUT`.
fn intrusion(bed: &Path, out: &Path) -> IntrudeRequest {
    IntrudeRequest {
        bed: Some(bed.to_path_buf()),
        speed_m_s: Some(0.3),
        depth_m: 0.002,
        foot_width_m: 0.006,
        model: ModelRequest {
            walls: true,
            ..model()
        },
        out: out.to_path_buf(),
        ..IntrudeRequest::default()
    }
}

/// `dem intrude --resume --out OUT` (and `stop_after`, `threads`).
fn resume(out: &Path, stop_after: Option<u64>, threads: usize) -> IntrudeRequest {
    IntrudeRequest {
        resume: true,
        stop_after,
        threads,
        out: out.to_path_buf(),
        ..IntrudeRequest::default()
    }
}

fn finished(outcome: IntrudeOutcome) -> Box<Summary> {
    match outcome {
        IntrudeOutcome::Finished(s) => s,
        stopped => panic!("not finished: {stopped}"),
    }
}

#[test]
fn same_seed_gives_the_same_bits_on_one_or_two_threads_and_after_a_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path());
    let one = tmp.path().join("one");
    let two = tmp.path().join("two");
    let res = tmp.path().join("res");
    // A checkpoint rebuilds the neighbour list (which orders the force sums), so the runs
    // compared share the checkpoint interval.
    let base = |out: &Path, threads: usize| IntrudeRequest {
        threads,
        frames: false,
        checkpoint_every: 1000,
        ..intrusion(&b, out)
    };
    finished(intrude_run::run(&base(&one, 1), &Silent).unwrap());
    // Two threads, pinned to cores of their own where the machine has two.
    let cores = std::thread::available_parallelism().map_or(1, |p| p.get());
    finished(
        intrude_run::run(
            &IntrudeRequest {
                pin_threads: cores >= 2,
                ..base(&two, 2)
            },
            &Silent,
        )
        .unwrap(),
    );
    // Stopped twice (once between checkpoints), resumed twice.
    let stopped = intrude_run::run(
        &IntrudeRequest {
            stop_after: Some(2500),
            ..base(&res, 2)
        },
        &Silent,
    )
    .unwrap();
    assert!(
        matches!(stopped, IntrudeOutcome::Stopped { steps: 2500, .. }),
        "{stopped}"
    );
    assert!(
        stopped.to_string().contains("stopped after 2500"),
        "{stopped}"
    );
    assert!(!res.exists(), "a stopped run must not look finished");
    let again = intrude_run::run(&resume(&res, Some(4000), 0), &Silent).unwrap();
    assert!(
        matches!(again, IntrudeOutcome::Stopped { steps: 4000, .. }),
        "{again}"
    );
    finished(intrude_run::run(&resume(&res, None, 1), &Silent).unwrap());
    for f in ["force_depth.csv", "flow.csv", "fields/0003.csv"] {
        assert_eq!(
            read(&one.join(f)),
            read(&two.join(f)),
            "{f}: 1 vs 2 threads"
        );
        assert_eq!(
            read(&one.join(f)),
            read(&res.join(f)),
            "{f}: straight vs resumed"
        );
    }
    // A resume with nothing to resume is refused.
    let e = intrude_run::run(&resume(&tmp.path().join("none"), None, 0), &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(e.to_string().contains("--resume"), "{e}");
}

#[test]
fn a_second_writer_is_refused_and_the_live_runs_work_is_left_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path());
    let out = tmp.path().join("out");
    let stopped = intrude_run::run(
        &IntrudeRequest {
            stop_after: Some(500),
            frames: false,
            ..intrusion(&b, &out)
        },
        &Silent,
    )
    .unwrap();
    assert!(
        matches!(stopped, IntrudeOutcome::Stopped { .. }),
        "{stopped}"
    );
    let work = intrude_run::work_dir(&out);
    let ckpt = std::fs::read(work.join("run.ckpt")).unwrap();
    // A live run holds the work folder (here: this test, as a run in another process would).
    let live = sandjumper_output::WriterLock::take_recorded(&work.join(".lock")).unwrap();
    let me = format!("process {} on ", std::process::id());
    for second in [intrusion(&b, &out), resume(&out, None, 0)] {
        let e = intrude_run::run(&second, &Silent).unwrap_err();
        assert_eq!(e.blame(), Blame::Input, "{e}");
        assert!(e.to_string().contains(&me), "{e}");
        // Neither the fresh start nor the resume touched the live run's checkpoint.
        assert_eq!(std::fs::read(work.join("run.ckpt")).unwrap(), ckpt);
    }
    drop(live);
    // A fresh start refused for its input (a foot wider than the bed) leaves it as well.
    let e = intrude_run::run(
        &IntrudeRequest {
            foot_width_m: 0.05,
            ..intrusion(&b, &out)
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert_eq!(std::fs::read(work.join("run.ckpt")).unwrap(), ckpt);
    finished(intrude_run::run(&resume(&out, None, 0), &Silent).unwrap());
    assert!(!work.exists(), "the finished run's work folder is gone");
}

/// CSV rows as numbers (the header skipped; an empty cell is NaN).
fn numbers(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

#[test]
fn the_added_mass_grows_then_saturates_and_the_grains_push_the_intruder_up() {
    // The paper's model: no gravity, no walls, a bed wide against the foot (in a narrow box
    // the displaced grains rise along the walls and, weighted by r, outweigh the cone).
    let tmp = tempfile::tempdir().unwrap();
    let bed = wide_bed(tmp.path());
    let out = tmp.path().join("run");
    let notes = Notes::default();
    let s = finished(
        intrude_run::run(
            &IntrudeRequest {
                bed: Some(bed),
                speed_m_s: Some(0.3),
                depth_m: 0.005,
                foot_width_m: 0.008,
                model: model(),
                // The frames are `dem intrude`'s contract (and the closed loop's).
                frames: false,
                out: out.clone(),
                ..IntrudeRequest::default()
            },
            &notes,
        )
        .unwrap(),
    );
    let notes = notes.0.lock().unwrap().join("\n");
    assert!(
        notes.contains("Froude"),
        "the dimensionless numbers are told: {notes}"
    );
    // The paper's measurement: the column under the foot moves down with it, and its added
    // mass is compared with eq. 6 (C scaled to this foot).
    let line = s.line();
    assert!(s.grain_momentum_under_foot_kg_m_s > 0.0, "{line}");
    let vs_eq6 = s.added_mass_vs_eq6_median;
    assert!(vs_eq6.is_finite() && vs_eq6 > 0.0, "{line}");
    // How much of P lies deeper than the jammed cone: a share, reported.
    let beyond = s.momentum_beyond_cone_depth_share;
    assert!((0.0..1.0).contains(&beyond), "{beyond}");
    // And how much reaches the window's bottom tenth (a warning above 5 %).
    let bottom = s.momentum_in_window_bottom_tenth_share;
    assert!((-0.5..1.0).contains(&bottom), "{bottom}");
    assert_eq!(s.window_depth_warning.is_some(), bottom > 0.05, "{bottom}");
    let flow = read(&out.join("flow.csv"));
    assert!(
        flow.lines()
            .next()
            .unwrap()
            .contains(",momentum_kg_m_s,momentum_under_foot_kg_m_s,momentum_under_foot_to_cone_depth_kg_m_s,momentum_band_r_to_2r_kg_m_s,momentum_band_2r_to_3r_kg_m_s,momentum_elsewhere_kg_m_s,momentum_in_window_bottom_tenth_kg_m_s,added_mass_kg,"),
        "{flow}"
    );
    // Force on the intruder resists it; the added mass is positive, grows, then levels off.
    let f: Vec<f64> = numbers(&read(&out.join("force_depth.csv")))
        .iter()
        .map(|r| r[3])
        .collect();
    let late = &f[f.len() / 2..];
    let peak = f.iter().copied().fold(0.0, f64::max);
    // Only the dashpot's pull at separation is ever negative, and it is small.
    assert!(
        late.iter().all(|&x| x > -0.01 * peak),
        "the grains push the intruder up: {f:?}"
    );
    assert!(late.iter().sum::<f64>() > 0.0, "{f:?}");
    let am: Vec<(f64, f64)> = numbers(&read(&out.join("added_mass.csv")))
        .iter()
        .map(|r| (r[0], r[1]))
        .collect();
    assert!(am.len() >= 6, "{am:?}");
    assert!(am.iter().all(|p| p.1 > 0.0), "{am:?}");
    let n = am.len();
    let early = am[n / 3].1 - am[0].1;
    let late = am[n - 1].1 - am[2 * n / 3].1;
    eprintln!("added mass {am:?}");
    assert!(am[n - 1].1 > am[0].1, "grows: {am:?}");
    assert!(
        late.abs() < early.abs().max(0.1 * am[n - 1].1),
        "saturates: early {early}, late {late}"
    );
}

/// A jump's trajectory starts with the foot at rest below the surface of an intact bed: it
/// is refused as it is, and its push-off episode, shifted to the surface, is accepted, also
/// from a stutter whose preliminary hop lasts longer than its flight (20 Hz), and a stopped
/// run resumes (its slow samples have no added mass: NaN in the checkpoint).
#[test]
fn a_jump_trajectory_is_refused_below_the_surface_and_its_push_off_is_taken() {
    use sandjumper_study::jump::{self, JumpRequest};
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path());
    // `jump --kind stutter --freq 20 --model eq4 --phi 0.57 --out jump`.
    let stutter = JumpRequest {
        kind: sandjumper_core::trajectory::JumpKind::Stutter,
        freq_hz: 20.0,
        model: sandjumper_model::params::ModelName::Eq4,
        phi: 0.57,
        record_series: true,
        ..JumpRequest::default()
    };
    let jump_dir = jump::run(&stutter, &Silent)
        .unwrap()
        .write(&tmp.path().join("jump"))
        .unwrap();
    let out = tmp.path().join("run");
    let request = IntrudeRequest {
        bed: Some(b),
        trajectory: Some(jump_dir.join("trajectory.csv")),
        foot_width_m: 0.006,
        model: model(),
        frames: false,
        out: out.clone(),
        ..IntrudeRequest::default()
    };
    let e = intrude_run::run(&request, &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(e.to_string().contains("below the bed's surface"), "{e}");
    assert!(e.to_string().contains("--episode push-off"), "{e}");
    let stopped = intrude_run::run(
        &IntrudeRequest {
            episode: Some(Episode::PushOff),
            checkpoint_every: 200,
            stop_after: Some(400),
            ..request
        },
        &Silent,
    )
    .unwrap();
    assert!(
        stopped.to_string().contains("stopped after 400"),
        "{stopped}"
    );
    let s = finished(intrude_run::run(&resume(&out, None, 0), &Silent).unwrap());
    assert!(s.grain_momentum_under_foot_kg_m_s > 0.0, "{}", s.line());
    let flow = read(&out.join("flow.csv"));
    let column = flow
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "added_mass_kg")
        .expect("an added_mass_kg column");
    let added: Vec<&str> = flow
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(column).unwrap())
        .collect();
    assert!(
        added.iter().any(|a| a.is_empty() || *a == "NaN"),
        "slow samples: {flow}"
    );
    assert!(
        added
            .iter()
            .any(|a| a.parse::<f64>().is_ok_and(f64::is_finite)),
        "{flow}"
    );
}
