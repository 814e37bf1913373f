//! Whether the search's answers can be trusted: it finds an optimum an exhaustive grid
//! knows, wider limits never answer lower than narrower ones (unseeded, over seeds), a given
//! stroke is a start and a candidate, the answer reports where it stands against the paper's
//! measured regime, the paper's best is refined as the answer is before they are compared,
//! and a stroke for an uncertain bed maximises its worst case.

use std::path::Path;

use sandjumper_model::ModelName;
use sandjumper_model::params::Params;
use sandjumper_optimize::paper_sweep::{PaperGrid, PaperSpace, sweep};
use sandjumper_optimize::search::{SearchSettings, Start, search};
use sandjumper_optimize::{OptimizeRequest, run};
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::LinkArg;

/// A kinematic search (no link) on a coarse sweep with `evaluations` evaluations.
fn kinematic(out: &Path, evaluations: usize) -> OptimizeRequest {
    OptimizeRequest {
        evaluations,
        population: 12,
        random_starts: 2,
        sweep_freq_step_hz: 1.0,
        sweep_tau_step_s: 0.05,
        elites: 2,
        paper_candidates: 1,
        verify: Vec::new(),
        threads: Some(2),
        out: out.to_path_buf(),
        ..OptimizeRequest::default()
    }
}

/// Each paper stroke has a best amplitude, frequency and delay an exhaustive grid finds
/// (12.5-25 mm by 0.5 mm, 1-25 Hz by 0.1 Hz, delays 0-0.5 s by 5 ms): the search over the same
/// coordinates, from two points far from it, reaches it. The single jump's and the stutter's
/// optima are smooth maxima (or sit on the drive's force limit), reached within 0.2 %; the
/// delayed stutter's sits on a cliff's edge (5 ms shorter and the push-off meets the
/// preliminary hop's landing: 85 mm falls to 26 mm), which the search comes within 2 % of.
#[test]
fn the_search_reaches_the_optimum_an_exhaustive_grid_finds() {
    let dir = tempfile::tempdir().unwrap();
    let setup = kinematic(&dir.path().join("x"), 1000).setup().unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for (kind, amplitudes, taus, within) in [
        ("single", 26, 1, 2e-3),
        ("stutter", 26, 1, 2e-3),
        ("delayed", 1, 101, 2e-2),
    ] {
        let grid = PaperGrid {
            amplitudes_m: if amplitudes == 1 {
                vec![setup.problem.params.robot.stroke_amplitude_m]
            } else {
                (0..amplitudes)
                    .map(|i| 0.0125 + 0.0005 * f64::from(i))
                    .collect()
            },
            freqs_hz: (0..=240).map(|i| 1.0 + 0.1 * f64::from(i)).collect(),
            taus_s: (0..taus).map(|i| 0.005 * f64::from(i)).collect(),
        };
        let exhaustive = pool
            .install(|| sweep(&setup.problem, &grid, 4, &|_| true))
            .unwrap();
        let best = exhaustive
            .best_by_kind
            .iter()
            .find(|p| p.stroke.kind == kind)
            .unwrap()
            .clone();
        let space = PaperSpace::of(kind, &grid).unwrap();
        let dim = space.encode(&best.stroke).len();
        let starts: Vec<Start> = [0.05, 0.95]
            .iter()
            .enumerate()
            .map(|(i, &u)| Start {
                label: format!("far {i}"),
                x: (0..dim)
                    .map(|k| if k % 2 == 0 { u } else { 1.0 - u })
                    .collect(),
                sigma: 0.3,
            })
            .collect();
        let settings = SearchSettings {
            evaluations: 4800,
            population: 8,
            random_starts: 0,
            ..setup.settings.clone()
        };
        let found = pool
            .install(|| {
                search(
                    &setup.problem,
                    &|x| space.stroke(x).chain(4),
                    &starts,
                    &settings,
                    None,
                    &|_| true,
                )
            })
            .unwrap();
        let top = &found.by_start[0].evaluation;
        eprintln!(
            "{kind}: grid best {} ({:.5} m), search {:.5} m in {} evaluations, {} runs",
            best.stroke.describe(),
            best.evaluation.value,
            top.value,
            found.evaluations,
            found.restarts.len()
        );
        assert!(
            top.value >= best.evaluation.value * (1.0 - within),
            "{kind}: the search found {} m, the grid {} m ({})",
            top.value,
            best.evaluation.value,
            best.stroke.describe()
        );
    }
}

/// Wider limits never answer lower: the search at the rig's 25 mm stroke, not seeded with the
/// 18.75 mm search's answer, answers at least as high, on sand at both ends of the presets and
/// on hard ground, over three seeds.
#[test]
fn wider_limits_never_answer_lower_than_narrower_ones_over_seeds() {
    let dir = tempfile::tempdir().unwrap();
    for (model, phi) in [
        (ModelName::Eq4, 0.57),
        (ModelName::Eq4, 0.62),
        (ModelName::Hard, 0.57),
    ] {
        for seed in 1..=3 {
            let answer = |stroke: f64| -> (f64, f64) {
                let out = dir.path().join(format!("{model}-{phi}-{seed}-{stroke}"));
                let o = run(
                    &OptimizeRequest {
                        model,
                        params: Params::preset(phi).unwrap(),
                        seed,
                        max_stroke_m: stroke,
                        ..kinematic(&out, 10000)
                    },
                    &Silent,
                )
                .unwrap();
                (o.best_value, o.best_paper_value)
            };
            let ((narrow, _), (wide, wide_paper)) = (answer(0.01875), answer(0.025));
            // Not the paper sweep's doing: the narrower search's answer beats every paper
            // stroke of the wider limits, so the wider search had to find its own.
            assert!(
                narrow > wide_paper,
                "{model} phi {phi} seed {seed}: 18.75 mm {narrow} m, 25 mm paper {wide_paper} m"
            );
            eprintln!("{model} phi {phi} seed {seed}: 18.75 mm {narrow:.4} m, 25 mm {wide:.4} m");
            assert!(
                wide >= narrow,
                "{model} phi {phi} seed {seed}: 25 mm answers {wide} m, 18.75 mm {narrow} m"
            );
        }
    }
}

/// A given stroke (a narrower search's answer) is a start and a candidate: a search given it
/// answers at least as high even on a budget too small to find it alone.
#[test]
fn a_given_stroke_starts_the_search_and_is_a_candidate() {
    let dir = tempfile::tempdir().unwrap();
    let narrow = run(
        &OptimizeRequest {
            max_stroke_m: 0.01875,
            ..kinematic(&dir.path().join("narrow"), 3000)
        },
        &Silent,
    )
    .unwrap();
    let chain = narrow.answer.chain.clone().expect("the answer's chain");
    let back = sandjumper_optimize::outcome::answer_chain_in(&narrow.dir).unwrap();
    assert_eq!(back, chain);
    let given = run(
        &OptimizeRequest {
            start_from: vec![chain],
            ..kinematic(&dir.path().join("given"), 200)
        },
        &Silent,
    )
    .unwrap();
    assert!(
        given.best_value >= narrow.best_value - 1e-12,
        "{} against the given stroke's {}",
        given.best_value,
        narrow.best_value
    );
    assert!(
        given
            .candidates
            .iter()
            .any(|c| c.label.starts_with("given stroke 1"))
    );
    // A chain with more moves than the search's is refused before anything runs.
    let mut long = narrow.answer.chain.clone().unwrap();
    long.moves.extend(long.moves.clone());
    let e = run(
        &OptimizeRequest {
            start_from: vec![long],
            ..kinematic(&dir.path().join("long"), 200)
        },
        &Silent,
    )
    .unwrap_err();
    assert!(e.to_string().contains("start stroke 1"), "{e}");
}

/// The answer reports its landings, its pushes into moving grains and its overshoot
/// episodes beside the paper's best's, and its value under each alternative rule of the
/// ground model (validity.csv); on hard ground there is no sand rule to swap.
#[test]
fn the_answer_is_rescored_under_the_models_alternatives() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(&kinematic(&dir.path().join("eq4"), 600), &Silent).unwrap();
    let v = &o.validity;
    let rules: Vec<&str> = v.rescored.iter().map(|r| r.rule.as_str()).collect();
    assert_eq!(rules.len(), 3, "{rules:?}");
    assert!(rules[0].contains("re-intrusion"), "{rules:?}");
    for r in &v.rescored {
        assert_eq!(r.answer_value, o.answer.kinematic.value);
        assert!(r.answer_value_alternative.is_finite() || !r.violation.is_empty());
    }
    // Without the overshoot the sand holds less after a landing: some stroke's value moves.
    let moved = v.rescored[0].answer_value_alternative != v.rescored[0].answer_value
        || v.rescored[0].paper_value_alternative != v.rescored[0].paper_value;
    assert!(moved, "{:?}", v.rescored[0]);
    assert!(v.paper_sweep_max_landing_speed_m_s > 0.0);
    let csv = std::fs::read_to_string(o.dir.join("validity.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    // Every rule the answer relies on is one whose alternative shrinks its lead, in words.
    let relied = v.rescored.iter().filter(|r| r.relied_on()).count();
    let landings =
        usize::from(v.answer.max_landing_speed_m_s > v.paper_sweep_max_landing_speed_m_s)
            + usize::from(v.answer.pushes_during_grain_motion > 0);
    assert_eq!(v.relies_on.len(), relied + landings, "{:?}", v.relies_on);
    assert_eq!(v.relies_on_tags.len(), v.relies_on.len());
    for r in v.rescored.iter().filter(|r| r.relied_on()) {
        assert!(
            v.relies_on.iter().any(|w| w.starts_with(&r.rule)),
            "{:?}",
            v.relies_on
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(o.dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        json["validity"]["relies_on"].as_array().unwrap().len(),
        v.relies_on.len()
    );
    let hard = run(
        &OptimizeRequest {
            model: ModelName::Hard,
            ..kinematic(&dir.path().join("hard"), 300)
        },
        &Silent,
    )
    .unwrap();
    assert!(hard.validity.rescored.is_empty());
    assert_eq!(hard.validity.answer.pushes_during_grain_motion, 0);
    assert_eq!(hard.validity.answer.reintrusion_episodes, 0);
}

/// Over an uncertain bed the search maximises the worst case: a candidate's value is its
/// lowest over the beds, the answer's worst case beats the worst case of the answer a search
/// at the nominal bed alone gives (same budget and seed), and beds.csv holds every bed with
/// the answer and the paper's best (refined with the same budget) through the controller.
#[test]
fn a_stroke_for_an_uncertain_bed_maximises_its_worst_case() {
    let dir = tempfile::tempdir().unwrap();
    let beds = vec![Params::preset(0.57).unwrap(), Params::preset(0.62).unwrap()];
    let request = OptimizeRequest {
        params: Params::preset(0.595).unwrap(),
        beds: beds.clone(),
        ..kinematic(&dir.path().join("range"), 3000)
    };
    let setup = request.setup().unwrap();
    let p = &setup.problem;
    let chain = sandjumper_optimize::family::MoveChain::delayed_stutter(0.01875, 9.0, 0.1, 4);
    let each: Vec<f64> = p
        .all_beds()
        .map(|b| p.evaluate_on(b, &chain).value)
        .collect();
    let e = p.evaluate(&chain);
    assert_eq!(e.value, each.iter().copied().fold(f64::INFINITY, f64::min));
    assert!((e.mean_value - each.iter().sum::<f64>() / 3.0).abs() < 1e-15);
    assert!(each.iter().any(|v| *v > e.value), "{each:?}");
    let range = run(&request, &Silent).unwrap();
    let nominal = run(
        &OptimizeRequest {
            beds: Vec::new(),
            ..request.clone()
        },
        &Silent,
    )
    .unwrap();
    let nominal_worst = p.evaluate(nominal.answer.chain.as_ref().unwrap()).value;
    eprintln!(
        "worst case: {} m for the range's answer, {nominal_worst} m for the nominal bed's \
         ({} m there)",
        range.best_value, nominal.best_value
    );
    assert!(
        range.best_value > nominal_worst || nominal_worst.is_nan(),
        "{} {nominal_worst}",
        range.best_value
    );
    // Through the controller: the worst case, and every bed in beds.csv.
    let o = run(
        &OptimizeRequest {
            params: Params::preset(0.595).unwrap(),
            beds,
            verify: vec![LinkArg::Sil],
            refine: 24,
            ..kinematic(&dir.path().join("sil"), 600)
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(o.height_basis, "sil");
    let phis: Vec<f64> = o.beds.iter().map(|b| b.phi).collect();
    assert_eq!(phis, vec![0.57, 0.595, 0.62]);
    let b = &o.over_beds;
    assert_eq!(b.beds, 3);
    let worst_sil = o
        .beds
        .iter()
        .map(|r| r.answer_sil_value)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (o.best_value - worst_sil).abs() < 1e-12,
        "{} {worst_sil}",
        o.best_value
    );
    assert!(o.paper_refine_runs > 0 && o.refine_runs > 0);
    assert!(
        o.candidates
            .iter()
            .any(|c| c.label.ends_with("refined through sil") && c.controller_value.is_finite()),
        "no refined paper stroke among the candidates"
    );
    let csv = std::fs::read_to_string(o.dir.join("beds.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    // A bed with another robot is refused.
    let mut other = Params::preset(0.62).unwrap();
    other.robot.motor_mass_kg *= 1.1;
    let e = OptimizeRequest {
        beds: vec![other],
        ..request
    }
    .validate()
    .unwrap_err();
    assert!(e.to_string().contains("sand only"), "{e}");
}

/// The phi range's grammar and its beds: A:B with A < B, the samples evenly spaced, the
/// nominal bed the middle one.
#[test]
fn a_phi_range_is_two_packing_fractions_and_its_beds_the_presets() {
    use sandjumper_optimize::{PhiRange, parse_phi_range};
    let r = parse_phi_range("0.57:0.62", 5).unwrap();
    assert_eq!(
        r,
        PhiRange {
            lo: 0.57,
            hi: 0.62,
            points: 5
        }
    );
    let phis = r.phis();
    assert_eq!(phis.len(), 5);
    assert!((phis[1] - 0.5825).abs() < 1e-12 && phis[4] == 0.62);
    assert!((r.nominal() - 0.595).abs() < 1e-12);
    let (nominal, others) = r.beds(None).unwrap();
    assert!((nominal.sand.packing_fraction - 0.595).abs() < 1e-12);
    assert_eq!(others.len(), 4);
    for bad in ["0.62:0.57", "0.57", "0.57:0.6:0.01", "a:b", "0.57:1.2", ":"] {
        let e = parse_phi_range(bad, 5).unwrap_err();
        assert!(e.contains(&format!("`{bad}`")), "{e}");
    }
    assert!(
        parse_phi_range("0.57:0.62", 1)
            .unwrap_err()
            .contains("--phi-points")
    );
    let e = parse_phi_range("0.5:0.6", 3)
        .unwrap()
        .beds(None)
        .unwrap_err();
    assert!(e.to_string().contains("0.5"), "{e}");
}
