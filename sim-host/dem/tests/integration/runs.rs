//! The commands as library calls: `dem bed`, `dem intrude` and `dem collide` through their
//! typed requests, checked on their typed outcomes in memory.

use std::sync::Mutex;

use sandjumper_dem::bed_run::{self, BedRequest};
use sandjumper_dem::collide::{self, CollideRequest};
use sandjumper_dem::intrude_run::{self, IntrudeOutcome, IntrudeRequest};
use sandjumper_dem::request::ModelRequest;
use sandjumper_dem::world::Integrator;
use sandjumper_output::{Blame, Blamed, Progress, Silent};

/// Notes and steps a run reported.
#[derive(Default)]
struct Recorder {
    notes: Mutex<Vec<String>>,
    steps: Mutex<u64>,
}

impl Progress for Recorder {
    fn advance(&self, n: u64) {
        *self.steps.lock().unwrap() += n;
    }
    fn note(&self, line: &str) {
        self.notes.lock().unwrap().push(line.to_string());
    }
}

fn model() -> ModelRequest {
    ModelRequest {
        overlap: 0.02,
        ..ModelRequest::default()
    }
}

/// A small packed bed into `out`.
fn small_bed_request(out: std::path::PathBuf) -> BedRequest {
    BedRequest {
        model: model(),
        width_m: 0.016,
        height_m: 0.008,
        pack: Some(0.8),
        threads: 1,
        out,
        ..BedRequest::default()
    }
}

fn small_bed(dir: &std::path::Path) -> bed_run::BedOutcome {
    bed_run::run(&small_bed_request(dir.join("bed")), &Silent).unwrap()
}

#[test]
fn a_bed_and_an_intrusion_into_it_as_calls() {
    let dir = tempfile::tempdir().unwrap();
    let bed = small_bed(dir.path());
    assert!(
        bed.report.grains > 50 && bed.report.area_fraction > 0.75,
        "{bed}"
    );
    assert!(bed.out.join("bed.ckpt").is_file());
    assert!(bed.to_string().starts_with("dem bed: "), "{bed}");
    let progress = Recorder::default();
    let request = IntrudeRequest {
        bed: Some(bed.out.clone()),
        speed_m_s: Some(0.3),
        depth_m: 0.002,
        foot_width_m: 0.006,
        model: ModelRequest {
            walls: true,
            ..model()
        },
        frames: false,
        threads: 1,
        out: dir.path().join("run"),
        ..IntrudeRequest::default()
    };
    let IntrudeOutcome::Finished(s) = intrude_run::run(&request, &progress).unwrap() else {
        panic!("the run stopped early");
    };
    assert!(s.max_force_n > 0.0, "{}", s.line());
    assert!((s.max_depth_m - 0.002).abs() < 1e-9, "{}", s.max_depth_m);
    assert_eq!(*progress.steps.lock().unwrap(), s.steps);
    assert!(progress.notes.lock().unwrap()[0].starts_with("dem intrude: "));
    assert!(dir.path().join("run/summary.json").is_file());
    // Stopped early: resumable, and the outcome says from where.
    let stopped = intrude_run::run(
        &IntrudeRequest {
            stop_after: Some(10),
            checkpoint_every: 4,
            out: dir.path().join("stopped"),
            ..request
        },
        &Silent,
    )
    .unwrap();
    match stopped {
        IntrudeOutcome::Stopped {
            steps,
            resumes_from,
            ..
        } => assert_eq!((steps, resumes_from), (10, 8)),
        IntrudeOutcome::Finished(_) => panic!("ran past --stop-after"),
    }
}

#[test]
fn an_intrusion_without_a_bed_or_a_motion_is_the_callers_fault() {
    let none = IntrudeRequest::default();
    let e = none.validate().unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert_eq!(e.to_string(), "--bed BED is required (or --resume)");
    let e = intrude_run::run(&none, &Silent).unwrap_err();
    assert_eq!(e.to_string(), "--bed BED is required (or --resume)");
}

#[test]
fn a_collision_matches_the_analytic_restitution() {
    let r = collide::run(
        &CollideRequest {
            d1_m: 1e-3,
            d2_m: Some(1e-3),
            kn_n_per_m: 1e4,
            damping_n_s_per_m: 1e-3,
            speed_m_s: 0.3,
            integrator: Integrator::VelocityVerlet,
            ..CollideRequest::default()
        },
        &Silent,
    )
    .unwrap();
    assert!(r.restitution_error.abs() < 1e-2, "{r}");
    assert!(r.to_string().starts_with("restitution "), "{r}");
    // A step above t_c / 10 is refused unless forced.
    let e = collide::run(
        &CollideRequest {
            d1_m: 1e-3,
            kn_n_per_m: 1e4,
            damping_n_s_per_m: 1e-3,
            speed_m_s: 0.3,
            dt_s: Some(1e-3),
            ..CollideRequest::default()
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
}

#[test]
fn a_collisions_json_has_the_keys_dem_collide_prints_and_a_share_is_0_to_1() {
    let r = collide::run(
        &CollideRequest {
            d1_m: 1e-3,
            wall: true,
            kn_n_per_m: 2e4,
            damping_n_s_per_m: 2e-3,
            speed_m_s: 0.3,
            ..CollideRequest::default()
        },
        &Silent,
    )
    .unwrap();
    let text = r.json().unwrap();
    assert!(text.starts_with("{\n  \"restitution\": "), "{text}");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["dt_s"], r.dt_s);
    assert_eq!(json["contact_time_s"], r.contact_time_s);
    assert_eq!(intrude_run::parse_share("0.3"), Ok(0.3));
    assert_eq!(
        intrude_run::parse_share("1.1"),
        Err("`1.1` not allowed (allowed: 0 to 1)".into())
    );
}

/// A progress whose caller stops the run at its `after`-th step report.
struct StopAfter {
    after: u64,
    reports: Mutex<u64>,
}

impl Progress for StopAfter {
    fn advance(&self, _: u64) {
        *self.reports.lock().unwrap() += 1;
    }
    fn cancelled(&self) -> bool {
        *self.reports.lock().unwrap() >= self.after
    }
}

#[test]
fn a_bed_and_an_intrusion_stopped_by_their_caller_stop_there() {
    let dir = tempfile::tempdir().unwrap();
    // The bed: stopped at its second report, an error and no folder.
    let stop = StopAfter {
        after: 2,
        reports: Mutex::new(0),
    };
    let out = dir.path().join("stopped-bed");
    let e = bed_run::run(&small_bed_request(out.clone()), &stop).unwrap_err();
    assert!(e.to_string().contains("stopped by its caller"), "{e}");
    assert_eq!(e.blame(), Blame::Internal);
    assert_eq!(*stop.reports.lock().unwrap(), 2, "no step after the stop");
    assert!(!out.exists());

    // The intrusion: stopped at its third sample, resumable from its checkpoint.
    let bed = small_bed(dir.path());
    let stop = StopAfter {
        after: 3,
        reports: Mutex::new(0),
    };
    let request = IntrudeRequest {
        bed: Some(bed.out.clone()),
        speed_m_s: Some(0.3),
        depth_m: 0.002,
        foot_width_m: 0.006,
        model: model(),
        frames: false,
        threads: 1,
        out: dir.path().join("run"),
        ..IntrudeRequest::default()
    };
    let e = intrude_run::run(&request, &stop).unwrap_err();
    assert!(e.to_string().contains("interrupted at sample"), "{e}");
    assert!(*stop.reports.lock().unwrap() <= 4);
    assert!(!request.out.join("summary.json").exists());
}
