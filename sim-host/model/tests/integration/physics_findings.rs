//! docs/model.md section 4: what the paper found, reproduced with the default parameters.
//! Each test states the finding; the numbers come from frequency scans, never hard-coded.

use sandjumper_model::*;

const FREQS: [f64; 17] = [
    4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 18.0, 19.0, 20.0,
];

fn height(model: ModelName, phi: f64, kind: JumpKind, f: f64, tau: f64) -> JumpSummary {
    let p = Params::preset(phi).unwrap();
    simulate_jump(
        &p,
        &JumpSpec {
            kind,
            freq_hz: f,
            tau_s: tau,
            model,
        },
        &SimOptions::default(),
    )
    .unwrap()
    .summary
}

/// (best frequency, best height) over the scan.
fn best(model: ModelName, phi: f64, kind: JumpKind, tau: f64) -> (f64, f64) {
    FREQS
        .iter()
        .map(|&f| (f, height(model, phi, kind, f, tau).jump_height_m))
        .fold((0.0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a })
}

#[test]
fn sand_at_low_phi_gives_about_a_third_of_the_hard_ground_height() {
    let (f_hard, hard) = best(ModelName::Hard, 0.57, JumpKind::Single, 0.0);
    let (f_sand, sand) = best(ModelName::Eq4, 0.57, JumpKind::Single, 0.0);
    let ratio = sand / hard;
    eprintln!(
        "hard {hard:.4} m at {f_hard} Hz, eq4 phi 0.57 {sand:.4} m at {f_sand} Hz, ratio {ratio:.3}"
    );
    assert!((0.25..0.45).contains(&ratio), "ratio {ratio}");
}

#[test]
fn height_rises_steeply_with_phi() {
    let heights: Vec<f64> = [0.57, 0.58, 0.59, 0.60, 0.61, 0.62]
        .iter()
        .map(|&phi| best(ModelName::Eq4, phi, JumpKind::Single, 0.0).1)
        .collect();
    eprintln!("best single heights vs phi: {heights:?}");
    assert!(heights.windows(2).all(|w| w[1] > w[0]), "{heights:?}");
    assert!(heights[5] > 1.6 * heights[0], "{heights:?}");
}

#[test]
fn good_forcing_frequencies_form_a_broad_band() {
    for model in [ModelName::Hard, ModelName::Eq4] {
        for phi in [0.57, 0.62] {
            let (_, top) = best(model, phi, JumpKind::Single, 0.0);
            let good: Vec<f64> = FREQS
                .iter()
                .copied()
                .filter(|&f| {
                    height(model, phi, JumpKind::Single, f, 0.0).jump_height_m >= 0.8 * top
                })
                .collect();
            let width = good.last().unwrap() - good[0];
            eprintln!(
                "{model} phi {phi}: within 80% of best from {} to {} Hz",
                good[0],
                good.last().unwrap()
            );
            assert!(width >= 5.0, "{model} phi {phi}: band {good:?}");
        }
    }
}

#[test]
fn at_low_phi_stutter_is_lower_and_delayed_stutter_higher_than_single() {
    let single = best(ModelName::Eq4, 0.57, JumpKind::Single, 0.0).1;
    let stutter = best(ModelName::Eq4, 0.57, JumpKind::Stutter, 0.0).1;
    let delayed = best(ModelName::Eq4, 0.57, JumpKind::DelayedStutter, 0.75).1;
    eprintln!(
        "phi 0.57 eq4: single {single:.4}, stutter {stutter:.4}, delayed(0.75 s) {delayed:.4} m"
    );
    assert!(stutter < single, "stutter {stutter} vs single {single}");
    assert!(delayed > single, "delayed {delayed} vs single {single}");
    // On hard ground the stutter jumps higher than the single jump.
    let hard_single = best(ModelName::Hard, 0.57, JumpKind::Single, 0.0).1;
    let hard_stutter = best(ModelName::Hard, 0.57, JumpKind::Stutter, 0.0).1;
    eprintln!("hard: single {hard_single:.4}, stutter {hard_stutter:.4} m");
    assert!(hard_stutter > hard_single);
}

#[test]
fn differences_between_the_three_jumps_shrink_at_high_phi() {
    let spread = |phi: f64| {
        let h = [
            best(ModelName::Eq4, phi, JumpKind::Single, 0.0).1,
            best(ModelName::Eq4, phi, JumpKind::Stutter, 0.0).1,
            best(ModelName::Eq4, phi, JumpKind::DelayedStutter, 0.75).1,
        ];
        let (lo, hi) = h
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        eprintln!("phi {phi}: single/stutter/delayed {h:?}");
        (hi - lo) / hi
    };
    let (low, high) = (spread(0.57), spread(0.62));
    eprintln!("relative spread: phi 0.57 {low:.3}, phi 0.62 {high:.3}");
    assert!(high < low, "spread at 0.62 {high} vs 0.57 {low}");
}

#[test]
fn added_mass_brings_the_stutter_push_off_down_at_low_phi() {
    // Compare final jump heights (after the push-off half begins), as docs/model.md says.
    let mut eq1_best: f64 = 0.0;
    let mut eq4_best: f64 = 0.0;
    for f in FREQS {
        let e1 = height(ModelName::Eq1, 0.57, JumpKind::Stutter, f, 0.0).final_jump_height_m;
        let e4 = height(ModelName::Eq4, 0.57, JumpKind::Stutter, f, 0.0).final_jump_height_m;
        eq1_best = eq1_best.max(e1);
        eq4_best = eq4_best.max(e4);
    }
    eprintln!("phi 0.57 stutter final height: eq1 {eq1_best:.4} m, eq4 {eq4_best:.4} m");
    assert!(eq4_best < eq1_best, "eq4 {eq4_best} vs eq1 {eq1_best}");
}
