//! The DEM (#23): binary collisions against the analytic spring-dashpot, checkpoints,
//! determinism and resume, structure (crystals and shear bands), added mass, PIV on the
//! DEM's own frames, and bad input.

use std::path::Path;

use proptest::prelude::*;
use sandjumper_dem::bed::{BedMethod, BedSpec, prepare};
use sandjumper_dem::checkpoint;
use sandjumper_dem::collide::Collision;
use sandjumper_dem::grains::SizeDistribution;
use sandjumper_dem::params::{Choice, Model};
use sandjumper_dem::structure::hexatic_order;
use sandjumper_dem::world::Integrator;

mod common;
use common::{read, sandjumper_text};

#[path = "dem/closed_loop.rs"]
mod closed_loop;

fn collision(d1: f64, d2: f64, wall: bool, speed: f64, zeta: f64, steps: f64) -> Collision {
    let mut c = Collision {
        d1_m: d1,
        d2_m: d2,
        wall,
        kn_n_per_m: 2000.0,
        damping_n_s_per_m: 0.0,
        speed_m_s: speed,
        density_kg_m3: 1000.0,
        dt_s: None,
        integrator: Integrator::VelocityVerlet,
    };
    c.damping_n_s_per_m = zeta * c.pair().critical_damping();
    c.dt_s = Some(c.pair().contact_time_s() / steps);
    c
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Restitution and contact time within 1 % at t_c/40 and 0.1 % at t_c/200, for disk
    /// pairs of any sizes, disk-wall, any impact speed, and light damping (up to 0.05 of
    /// critical, e >= 0.85), plus, for the restitution, the dashpot's first-order separation
    /// error that the heavy-damping test below measures (under 4 % at t_c/40 and 1 % at
    /// t_c/200 for zeta 0.3, so 0.15 zeta and 0.04 zeta here: at zeta 0.047, t_c/200, the
    /// error reaches 0.15 %).
    #[test]
    fn binary_collisions_match_the_analytic_spring_dashpot(
        d1 in 0.5e-3f64..3e-3,
        d2 in 0.5e-3f64..3e-3,
        wall in any::<bool>(),
        speed in 0.01f64..5.0,
        zeta in 0.0f64..0.05,
    ) {
        for (steps, tol, damping_tol) in [(40.0, 1e-2, 0.15), (200.0, 1e-3, 0.04)] {
            let r = collision(d1, d2, wall, speed, zeta, steps).run(false).unwrap();
            let e_tol = tol + damping_tol * zeta;
            prop_assert!(r.restitution_error.abs() < e_tol, "e {} vs {} at t_c/{steps}", r.restitution, r.restitution_analytic);
            prop_assert!(r.contact_time_error.abs() < tol, "t_c {} vs {} at t_c/{steps}", r.contact_time_s, r.contact_time_analytic_s);
        }
    }
}

#[test]
fn heavy_damping_has_a_first_order_separation_error() {
    // The dashpot pulls at separation (kn delta + gamma v_n < 0 as delta -> 0), and the
    // step that holds the separation applies that pull for a whole step: an error of order
    // gamma dt / m that depends on where in the step the contact ends. Measured, not hidden:
    // at zeta 0.3 (e 0.37) it stays under 4 % at t_c/40 and under 1 % at t_c/200.
    let mut worst: [f64; 2] = [0.0, 0.0];
    for (k, steps) in [40.0, 200.0].into_iter().enumerate() {
        for speed in [0.3, 0.5, 1.0, 2.0, 3.2] {
            let r = collision(0.76e-3, 1e-3, true, speed, 0.3, steps)
                .run(false)
                .unwrap();
            worst[k] = worst[k].max(r.restitution_error.abs());
        }
    }
    eprintln!("zeta 0.3: worst restitution error {worst:?}");
    assert!(worst[0] < 0.04 && worst[1] < 0.01, "{worst:?}");
    assert!(worst[1] < worst[0]);
}

#[test]
fn forward_euler_is_first_order_and_gains_energy() {
    // The paper's integrator: its restitution error halves when the step halves, and it
    // overshoots (explicit Euler feeds energy into a spring). Stated, not hidden.
    let mut c = collision(1e-3, 1e-3, false, 0.5, 0.2, 40.0);
    c.integrator = Integrator::ForwardEuler;
    let e40 = c.run(false).unwrap().restitution_error;
    c.dt_s = Some(c.pair().contact_time_s() / 80.0);
    let e80 = c.run(false).unwrap().restitution_error;
    assert!(e40 > 0.0 && e80 > 0.0, "{e40} {e80}");
    assert!((1.4..2.3).contains(&(e40 / e80)), "order: {e40} / {e80}");
}

#[test]
fn collide_prints_the_verification_numbers_as_json() {
    let (code, out, err) = sandjumper_text(&[
        "dem",
        "collide",
        "--d1",
        "1e-3",
        "--d2",
        "1.4e-3",
        "--kn",
        "1000",
        "--damping",
        "0.005",
        "--speed",
        "0.3",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in ["restitution", "contact_time_s", "effective_mass_kg", "dt_s"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k} in {out}");
    }
    let m1 = 1000.0 * std::f64::consts::PI * 1e-9 / 6.0;
    let m2 = m1 * 1.4f64.powi(3);
    let meff = v["effective_mass_kg"].as_f64().unwrap();
    assert!((meff / (m1 * m2 / (m1 + m2)) - 1.0).abs() < 1e-12);
    assert!(v["restitution_error"].as_f64().unwrap().abs() < 1e-3);
}

#[test]
fn unphysical_collisions_are_refused_with_exit_2() {
    let base = [
        "dem", "collide", "--d1", "1e-3", "--d2", "1e-3", "--speed", "0.3",
    ];
    let cases: [(&[&str], &str); 4] = [
        (&["--kn=-5", "--damping", "0"], "stiffness"),
        (&["--kn", "1000", "--damping", "1"], "overdamps"),
        (
            &["--kn", "1000", "--damping", "0", "--dt", "1e-5"],
            "t_c/10",
        ),
        (&["--kn", "1000", "--damping=-1"], "damping"),
    ];
    for (extra, want) in cases {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let (code, _, err) = sandjumper_text(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(err.contains(want), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // --force-step runs the coarse step anyway.
    let (code, _, err) = sandjumper_text(&[
        "dem",
        "collide",
        "--d1",
        "1e-3",
        "--wall",
        "--kn",
        "1000",
        "--damping",
        "0",
        "--speed",
        "0.3",
        "--dt",
        "1e-5",
        "--force-step",
    ]);
    assert_eq!(code, 0, "{err}");
}

fn settled_hexatic(sizes: SizeDistribution) -> f64 {
    let mut c = Choice::new(Model::Full);
    c.sizes = sizes;
    c.overlap = 0.02;
    let p = c.resolve(false).unwrap();
    let spec = BedSpec {
        width_m: 0.025,
        height_m: 0.012,
        method: BedMethod::Settle,
        seed: 3,
        max_time_s: 0.6,
        rest_agitation: 1e-7,
    };
    let (w, _) = prepare(&p, &spec, |_| {}).unwrap();
    hexatic_order(&w)
}

#[test]
fn monodisperse_beds_crystallise_and_bidisperse_ones_do_not() {
    let mono = settled_hexatic(SizeDistribution::Mono);
    let bi = settled_hexatic(SizeDistribution::BI);
    eprintln!("hexatic order: mono {mono:.3}, bi {bi:.3}");
    assert!(mono > 0.7, "mono {mono}");
    assert!(bi < 0.6, "bi {bi}");
}

#[test]
fn checkpoints_round_trip_and_refuse_corruption() {
    let mut c = Choice::new(Model::Full);
    c.overlap = 0.02;
    let p = c.resolve(false).unwrap();
    let spec = BedSpec {
        width_m: 0.012,
        height_m: 0.006,
        method: BedMethod::Pack { phi: 0.8 },
        seed: 5,
        max_time_s: 0.01,
        rest_agitation: 1e-6,
    };
    let (mut w, _) = prepare(&p, &spec, |_| {}).unwrap();
    w.cfg.gravity_m_s2 = 9.81;
    for _ in 0..500 {
        w.step();
    }
    w.rebuild();
    let rec = serde_json::json!({"note": "x"});
    let bytes = checkpoint::encode(&w, &rec, &[1.0, 2.5]);
    let mut a = checkpoint::decode(&bytes).unwrap();
    assert_eq!(a.extra, vec![1.0, 2.5]);
    assert_eq!(a.record, rec);
    assert_eq!(a.world.g, w.g);
    // The same future.
    let mut b = w.clone();
    for _ in 0..300 {
        a.world.step();
        b.step();
    }
    assert_eq!(a.world.g.x, b.g.x);
    assert_eq!(a.world.g.vy, b.g.vy);
    // A flipped byte, a cut file, another version: refused with the reason.
    let mut bad = bytes.clone();
    let k = bad.len() / 2;
    bad[k] ^= 0x10;
    assert!(checkpoint::decode(&bad).unwrap_err().contains("checksum"));
    let cut = &bytes[..bytes.len() - 100];
    assert!(checkpoint::decode(cut).is_err());
    let mut ver = bytes.clone();
    ver[8] = 9;
    assert!(checkpoint::decode(&ver).unwrap_err().contains("version"));
    assert!(
        checkpoint::decode(b"hello")
            .unwrap_err()
            .contains("not a sandjumper")
    );
}

fn bed(dir: &Path, extra: &[&str]) -> String {
    let out = dir.join("bed");
    let mut args = vec![
        "dem",
        "bed",
        "--pack",
        "0.8",
        "--width",
        "0.016",
        "--height",
        "0.008",
        "--overlap",
        "0.02",
        "--out",
    ];
    let o = out.to_str().unwrap().to_string();
    args.push(&o);
    args.extend_from_slice(extra);
    let (code, _, err) = sandjumper_text(&args);
    assert_eq!(code, 0, "{err}");
    o
}

fn intrude(bed: &str, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let o = out.to_str().unwrap().to_string();
    let mut args = vec![
        "dem",
        "intrude",
        "--bed",
        bed,
        "--speed",
        "0.3",
        "--overlap",
        "0.02",
        "--walls",
        "--out",
        &o,
    ];
    if !extra.contains(&"--depth") {
        args.extend_from_slice(&["--depth", "0.002"]);
    }
    if !extra.contains(&"--foot-width") {
        args.extend_from_slice(&["--foot-width", "0.006"]);
    }
    args.extend_from_slice(extra);
    sandjumper_text(&args)
}

/// A packed bed (no gravity) 5 cm wide and 1.2 cm deep, wide against an 8 mm foot.
fn wide_bed(dir: &Path) -> std::path::PathBuf {
    let bed = dir.join("wide");
    let (c, _, e) = sandjumper_text(&[
        "dem",
        "bed",
        "--pack",
        "0.8",
        "--width",
        "0.05",
        "--height",
        "0.012",
        "--overlap",
        "0.02",
        "--out",
        bed.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    bed
}

#[test]
fn same_seed_gives_the_same_bits_on_one_or_two_threads_and_after_a_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let one = tmp.path().join("one");
    let two = tmp.path().join("two");
    let res = tmp.path().join("res");
    // A checkpoint rebuilds the neighbour list (which orders the force sums), so the runs
    // compared share the checkpoint interval.
    let every = ["--checkpoint-every", "1000"];
    let (c, _, e) = intrude(
        &b,
        &one,
        &[&["--threads", "1", "--no-frames"][..], &every].concat(),
    );
    assert_eq!(c, 0, "{e}");
    // Two threads, pinned to cores of their own where the machine has two.
    let cores = std::thread::available_parallelism().map_or(1, |p| p.get());
    let pin: &[&str] = if cores >= 2 { &["--pin-threads"] } else { &[] };
    let (c, _, e) = intrude(
        &b,
        &two,
        &[&["--threads", "2", "--no-frames"][..], &every, pin].concat(),
    );
    assert_eq!(c, 0, "{e}");
    // Stopped twice (once between checkpoints), resumed twice.
    let (c, out, e) = intrude(
        &b,
        &res,
        &[
            "--threads",
            "2",
            "--no-frames",
            "--checkpoint-every",
            "1000",
            "--stop-after",
            "2500",
        ],
    );
    assert_eq!(c, 0, "{e}");
    assert!(out.contains("stopped after 2500"), "{out}");
    assert!(!res.exists(), "a stopped run must not look finished");
    let r = res.to_str().unwrap();
    let (c, _, e) = sandjumper_text(&[
        "dem",
        "intrude",
        "--resume",
        "--out",
        r,
        "--stop-after",
        "4000",
    ]);
    assert_eq!(c, 0, "{e}");
    let (c, _, e) = sandjumper_text(&["dem", "intrude", "--resume", "--out", r, "--threads", "1"]);
    assert_eq!(c, 0, "{e}");
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
    let none = tmp.path().join("none");
    let (c, _, e) = sandjumper_text(&[
        "dem",
        "intrude",
        "--resume",
        "--out",
        none.to_str().unwrap(),
    ]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("--resume"), "{e}");
}

#[test]
fn an_intrusion_writes_its_folder_and_the_added_mass_grows_then_saturates() {
    // The paper's model: no gravity, no walls, a bed wide against the foot (in a narrow box
    // the displaced grains rise along the walls and, weighted by r, outweigh the cone).
    let tmp = tempfile::tempdir().unwrap();
    let bed_dir = wide_bed(tmp.path());
    let bd = bed_dir.to_str().unwrap();
    let out = tmp.path().join("run");
    let (c, json, e) = sandjumper_text(&[
        "dem",
        "intrude",
        "--bed",
        bd,
        "--speed",
        "0.3",
        "--overlap",
        "0.02",
        "--depth",
        "0.005",
        "--foot-width",
        "0.008",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    for f in [
        "force_depth.csv",
        "force_depth.png",
        "force_depth.svg",
        "flow.csv",
        "added_mass.csv",
        "added_mass.png",
        "added_mass.svg",
        "shear_rate.png",
        "shear_rate.svg",
        "snapshot.png",
        "snapshot.svg",
        "animation.gif",
        "dem.toml",
        "summary.json",
        "u_m_s.npy",
        "v_m_s.npy",
        "shear_rate_per_s.npy",
        "foot.csv",
        "camera.toml",
        "frames/frame_000000.png",
        "fields/0000.csv",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    assert!(
        e.contains("Froude"),
        "the dimensionless numbers are printed: {e}"
    );
    // The paper's measurement: the column under the foot moves down with it, and its added
    // mass is compared with eq. 6 (C scaled to this foot).
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let under = v["grain_momentum_under_foot_kg_m_s"].as_f64().unwrap();
    assert!(under > 0.0, "{json}");
    let vs_eq6 = v["added_mass_vs_eq6_median"].as_f64().unwrap();
    assert!(vs_eq6.is_finite() && vs_eq6 > 0.0, "{json}");
    assert!(
        v.get("added_mass_ratio_to_model").is_none(),
        "one name per quantity"
    );
    // How much of P lies deeper than the jammed cone: a share, reported.
    let beyond = v["momentum_beyond_cone_depth_share"].as_f64().unwrap();
    assert!((0.0..1.0).contains(&beyond), "{json}");
    // And how much reaches the window's bottom tenth (a warning above 5 %).
    let bottom = v["momentum_in_window_bottom_tenth_share"].as_f64().unwrap();
    assert!((-0.5..1.0).contains(&bottom), "{json}");
    assert_eq!(
        v.get("window_depth_warning").is_some(),
        bottom > 0.05,
        "{json}"
    );
    let flow = read(&out.join("flow.csv"));
    assert!(
        flow.lines()
            .next()
            .unwrap()
            .contains(",momentum_kg_m_s,momentum_under_foot_kg_m_s,momentum_under_foot_to_cone_depth_kg_m_s,momentum_band_r_to_2r_kg_m_s,momentum_band_2r_to_3r_kg_m_s,momentum_elsewhere_kg_m_s,momentum_in_window_bottom_tenth_kg_m_s,added_mass_kg,"),
        "{flow}"
    );
    // Force on the intruder resists it; the added mass is positive, grows, then levels off.
    let force = read(&out.join("force_depth.csv"));
    let f: Vec<f64> = force
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    let late = &f[f.len() / 2..];
    let peak = f.iter().copied().fold(0.0, f64::max);
    // Only the dashpot's pull at separation is ever negative, and it is small.
    assert!(
        late.iter().all(|&x| x > -0.01 * peak),
        "the grains push the intruder up: {f:?}"
    );
    assert!(late.iter().sum::<f64>() > 0.0, "{f:?}");
    let am: Vec<(f64, f64)> = read(&out.join("added_mass.csv"))
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1])
        })
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

#[test]
fn bad_intrusions_are_refused_with_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let out = tmp.path().join("x");
    let (c, _, e) = intrude(&b, &out, &["--foot-width", "0.05"]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("wider than the bed"), "{e}");
    // Trajectory CSVs: a missing column, time going back.
    let t1 = tmp.path().join("t1.csv");
    std::fs::write(&t1, "t_s,height\n0,0\n0.001,0.001\n").unwrap();
    let t2 = tmp.path().join("t2.csv");
    std::fs::write(&t2, "t_s,depth_m\n0,0\n0.002,0.001\n0.001,0.002\n").unwrap();
    let o = out.to_str().unwrap();
    for (t, want) in [(&t1, "no `x_f_m` or `depth_m`"), (&t2, "does not increase")] {
        let (c, _, e) = sandjumper_text(&[
            "dem",
            "intrude",
            "--bed",
            &b,
            "--trajectory",
            t.to_str().unwrap(),
            "--foot-width",
            "0.006",
            "--out",
            o,
        ]);
        assert_eq!(c, 2, "{e}");
        assert!(e.contains(want), "{e}");
    }
    // A corrupt bed checkpoint.
    let ck = Path::new(&b).join("bed.ckpt");
    let mut bytes = std::fs::read(&ck).unwrap();
    let k = bytes.len() / 3;
    bytes[k] ^= 1;
    std::fs::write(&ck, bytes).unwrap();
    let (c, _, e) = intrude(&b, &out, &[]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("checksum"), "{e}");
    // More pinned threads than cores.
    let (c, _, e) = intrude(&b, &out, &["--threads", "100000", "--pin-threads"]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("--pin-threads: 100000 threads need"), "{e}");
    // Unphysical grains.
    let (c, _, e) = sandjumper_text(&["dem", "bed", "--kn=-1", "--out", o]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("stiffness"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

/// A jump's trajectory starts with the foot at rest below the surface of an intact bed: it
/// is refused as it is, and its push-off episode, shifted to the surface, is accepted, also
/// from a stutter whose preliminary hop lasts longer than its flight (20 Hz), and a stopped
/// run resumes (its slow samples have no added mass: NaN in the checkpoint).
#[test]
fn a_jump_trajectory_is_refused_below_the_surface_and_its_push_off_is_taken() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let jump = tmp.path().join("jump");
    let (c, _, e) = sandjumper_text(&[
        "jump",
        "--kind",
        "stutter",
        "--freq",
        "20",
        "--model",
        "eq4",
        "--phi",
        "0.57",
        "--out",
        jump.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    let traj = jump.join("trajectory.csv");
    let out = tmp.path().join("run");
    let args = |extra: &[&'static str]| {
        let mut v: Vec<String> = [
            "dem",
            "intrude",
            "--bed",
            &b,
            "--trajectory",
            traj.to_str().unwrap(),
            "--foot-width",
            "0.006",
            "--overlap",
            "0.02",
            "--no-frames",
            "--out",
            out.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |extra: &[&'static str]| {
        let a = args(extra);
        sandjumper_text(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (c, _, e) = run(&[]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("below the bed's surface"), "{e}");
    assert!(e.contains("--episode push-off"), "{e}");
    let (c, _, e) = run(&["--episode", "push-off", "--from", "0.1"]);
    assert_eq!(c, 2, "{e}");
    let (c, stdout, e) = run(&[
        "--episode",
        "push-off",
        "--checkpoint-every",
        "200",
        "--stop-after",
        "400",
    ]);
    assert_eq!(c, 0, "{e}");
    assert!(stdout.contains("stopped after 400"), "{stdout}");
    let (c, json, e) = sandjumper_text(&[
        "dem",
        "intrude",
        "--resume",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(
        v["grain_momentum_under_foot_kg_m_s"].as_f64().unwrap() > 0.0,
        "{json}"
    );
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
