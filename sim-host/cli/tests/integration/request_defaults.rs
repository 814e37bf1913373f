//! The command line's defaults are the library requests' `Default`s: each command parsed with
//! only its required arguments gives the request `Default` gives (those arguments set). A
//! `default_value` changed in one place and not the other fails here.

use clap::Parser;
use sandjumper_cli::cli::Cli;
use sandjumper_cli::cli::args::Command;
use sandjumper_cli::dem::command::DemCommand;
use std::path::{Path, PathBuf};

fn parse(argv: &[&str]) -> Command {
    match Cli::try_parse_from(std::iter::once("sandjumper").chain(argv.iter().copied())) {
        Ok(cli) => cli.command,
        Err(e) => panic!("does not parse: {e}"),
    }
}

#[test]
fn jump_defaults_are_the_jump_requests() {
    let Command::Jump(a) = parse(&["jump", "--kind", "single", "--freq", "10"]) else {
        panic!("not a jump");
    };
    assert_eq!(
        a.request(None, false),
        sandjumper_study::jump::JumpRequest::default()
    );
}

#[test]
fn dem_defaults_are_the_dem_requests() {
    let collide = [
        "dem",
        "collide",
        "--d1",
        "0.002",
        "--kn",
        "1e5",
        "--damping",
        "0.1",
        "--speed",
        "1",
        "--d2",
        "0.003",
    ];
    let Command::Dem(d) = parse(&collide) else {
        panic!("not dem");
    };
    let DemCommand::Collide(c) = d.command else {
        panic!("not collide");
    };
    let collide = sandjumper_dem::collide::CollideRequest {
        d1_m: 0.002,
        kn_n_per_m: 1e5,
        damping_n_s_per_m: 0.1,
        speed_m_s: 1.0,
        d2_m: Some(0.003),
        ..Default::default()
    };
    assert_eq!(c.request, collide);

    let Command::Dem(d) = parse(&["dem", "bed", "--out", "bed"]) else {
        panic!("not dem");
    };
    let DemCommand::Bed(b) = d.command else {
        panic!("not bed");
    };
    let bed = sandjumper_dem::bed_run::BedRequest {
        out: PathBuf::from("bed"),
        ..Default::default()
    };
    assert_eq!(*b, bed);

    let Command::Dem(d) = parse(&["dem", "intrude", "--bed", "b", "--out", "i"]) else {
        panic!("not dem");
    };
    let DemCommand::Intrude(i) = d.command else {
        panic!("not intrude");
    };
    let intrude = sandjumper_dem::intrude_run::IntrudeRequest {
        bed: Some(PathBuf::from("b")),
        out: PathBuf::from("i"),
        ..Default::default()
    };
    assert_eq!(i.request, intrude);

    let Command::Dem(d) = parse(&["dem", "lammps", "--out", "l"]) else {
        panic!("not dem");
    };
    let DemCommand::Lammps(l) = d.command else {
        panic!("not lammps");
    };
    let lammps = sandjumper_lammps::run::LammpsRequest {
        out: PathBuf::from("l"),
        ..Default::default()
    };
    assert_eq!(l.request(), lammps);
}

#[test]
fn analysis_defaults_are_the_analysis_requests() {
    let Command::Piv(p) = parse(&["piv", "frames/"]) else {
        panic!("not piv");
    };
    let piv = sandjumper_flow::run::PivRequest {
        frames: "frames/".into(),
        ..Default::default()
    };
    assert_eq!(p.request().expect("a request"), piv);

    let Command::Track(t) = parse(&["track", "frames/", "--m-per-px", "1e-4", "--fps", "200"])
    else {
        panic!("not track");
    };
    let track = sandjumper_imaging::run::TrackRequest {
        frames: "frames/".into(),
        m_per_px: 1e-4,
        fps: Some(200.0),
        ..Default::default()
    };
    assert_eq!(t.request(), track);
}

/// A Slurm job runs the binary again with the words its library request gives: parsed back,
/// they ask for the same run. A flag renamed on one side fails here, not on the cluster.
#[test]
fn a_slurm_jobs_words_parse_back_to_the_request_that_made_them() {
    let lammps = |argv: Vec<String>| {
        let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
        let Command::Dem(d) = parse(&argv) else {
            panic!("not dem");
        };
        let DemCommand::Lammps(l) = d.command else {
            panic!("not lammps");
        };
        l.request()
    };
    let given: Vec<String> = [
        "dem",
        "lammps",
        "--preset",
        "small",
        "--trajectory",
        "run/t.csv",
        "--episode",
        "push-off",
        "--depth",
        "0.013",
        "--foot-diameter",
        "0.021",
        "--grain-diameter",
        "0.0021",
        "--bed-width",
        "0.04",
        "--bed-depth",
        "0.03",
        "--phi",
        "0.6",
        "--youngs-modulus",
        "5e6",
        "--friction",
        "0.45",
        "--restitution",
        "0.3",
        "--fps",
        "500",
        "--seed",
        "7",
        "--min-speed-ratio",
        "0.25",
        "--lmp",
        "/opt/lmp",
        "--mpiexec",
        "/opt/mpx",
        "--ranks",
        "3",
        "--out",
        "o",
    ]
    .map(String::from)
    .into();
    let request = lammps(given);
    let mut words = request.job_arguments().unwrap();
    words.extend(["--ranks", "3", "--out", "o"].map(String::from));
    assert_eq!(lammps(words), request);
    let speed = lammps(
        ["dem", "lammps", "--speed", "0.1", "--out", "o"]
            .map(String::from)
            .into(),
    );
    let mut words = speed.job_arguments().unwrap();
    words.extend(["--out", "o"].map(String::from));
    assert_eq!(lammps(words), speed);

    let sweep = |argv: &[&str]| {
        let Command::Sweep(a) = parse(argv) else {
            panic!("not a sweep");
        };
        a
    };
    let a = sweep(&[
        "sweep",
        "--kind",
        "single,delayed",
        "--freq",
        "8:14:0.5",
        "--phi",
        "0.57:0.62:0.01",
        "--tau",
        "0:0.2:0.05",
        "--model",
        "eq1,eq4",
        "--rtol",
        "1e-9",
        "--link",
        "sil",
        "--gain-lowering",
        "0.05",
        "--params",
        "p.toml",
        "--out",
        "o",
    ]);
    let request = a.request(None);
    let words = request
        .task_arguments(Some(Path::new("/j/p.toml")))
        .unwrap();
    let mut argv: Vec<&str> = words.iter().map(String::as_str).collect();
    argv.extend(["--out", "o"]);
    let b = sweep(&argv);
    assert_eq!(b.request(None), request);
    assert_eq!(b.source.params.as_deref(), Some(Path::new("/j/p.toml")));
}
