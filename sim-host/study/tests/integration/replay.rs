//! Replay in the simulator (the paper's method): an encoder record of a known trajectory,
//! quantized like the rig's encoder, drives the kinematic simulation to the same jump as the
//! exact trajectory.

use sandjumper_acqlog::{AcqLog, Column, JumpConfig, LogMetadata, LogRow, ReadOptions, read_log};
use sandjumper_core::trajectory::{JumpKind, SineJump};
use sandjumper_model::trajectory::Stroke;
use sandjumper_model::{JumpSpec, ModelName, Params, SimOptions, simulate_jump};
use sandjumper_study::replay::{DEFAULT_WINDOW_S, ReplayStroke, replay_log};

/// Encoder resolution of the synthetic logs: 1 um per count.
const COUNTS_PER_M: f64 = 1.0e6;
/// Control rate of the synthetic logs, Hz.
const RATE_HZ: f64 = 10_000.0;

/// The log the rig would record of `jump`, sampled at 10 kHz and quantized to 1 um:
/// `pre_s` of rest before the trajectory, `post_s` of hold after it.
fn synthetic_log(jump: &SineJump, pre_s: f64, post_s: f64) -> AcqLog {
    let mut meta = LogMetadata::new(RATE_HZ, COUNTS_PER_M);
    meta.jump = Some(JumpConfig {
        kind: match jump.kind() {
            JumpKind::Single => "single",
            JumpKind::Stutter => "stutter",
            JumpKind::DelayedStutter => "delayed-stutter",
        }
        .into(),
        amplitude_m: Some(jump.amplitude_m()),
        freq_hz: Some(jump.freq_hz()),
        tau_s: Some(jump.tau_s()),
    });
    let mut log = AcqLog::new(meta, &[Column::PCmdM]);
    let first = -(pre_s * RATE_HZ).round() as i64;
    let last = ((jump.end_s() + post_s) * RATE_HZ).round() as i64;
    for (tick, k) in (first..=last).enumerate() {
        let t = k as f64 / RATE_HZ;
        let p = jump.eval(t).position_m;
        let mut row = LogRow::new(tick as u64, t, (p * COUNTS_PER_M).round() as i64);
        row.p_cmd_m = Some(p);
        log.rows.push(row);
    }
    log
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Jump heights of the exact trajectory and of its quantized log, same model and parameters.
fn exact_and_replayed(
    kind: JumpKind,
    freq_hz: f64,
    tau_s: f64,
    model: ModelName,
    phi: f64,
    pre_s: f64,
) -> (f64, f64, f64, f64) {
    let params = Params::preset(phi).unwrap();
    let jump = SineJump::new(kind, params.robot.stroke_amplitude_m, freq_hz, tau_s).unwrap();
    let spec = JumpSpec {
        kind,
        freq_hz,
        tau_s,
        model,
    };
    let opts = SimOptions::default();
    let exact = simulate_jump(&params, &spec, &opts).unwrap().summary;
    // Write and read back, so the test goes through the file format too.
    let bytes = synthetic_log(&jump, pre_s, 0.0)
        .write_csv(Vec::new())
        .unwrap();
    let log = read_log(bytes.as_slice(), &ReadOptions::default()).unwrap();
    let replayed = replay_log(&log, &params, model, DEFAULT_WINDOW_S, &opts).unwrap();
    let r = replayed.outcome.summary;
    (
        exact.jump_height_m,
        r.jump_height_m,
        exact.final_jump_height_m,
        r.final_jump_height_m,
    )
}

#[test]
fn a_quantized_single_jump_replays_to_the_analytic_jump_height_within_one_percent() {
    for (model, phi) in [
        (ModelName::Hard, 0.57),
        (ModelName::Eq4, 0.57),
        (ModelName::Eq1, 0.62),
    ] {
        let (exact, replayed, _, _) =
            exact_and_replayed(JumpKind::Single, 10.0, 0.0, model, phi, 0.0);
        assert!(
            exact > 1e-3,
            "{model}: the exact jump must leave the ground ({exact} m)"
        );
        assert!(
            relative(replayed, exact) < 0.01,
            "{model} phi {phi}: replayed {replayed} m vs exact {exact} m"
        );
    }
}

#[test]
fn rest_before_the_trajectory_and_stutters_replay_within_one_percent() {
    // 25 ms of rest first: the filter must smooth across the step in p'' at the start.
    for (kind, freq, tau) in [
        (JumpKind::Single, 14.0, 0.0),
        (JumpKind::Stutter, 12.0, 0.0),
        (JumpKind::DelayedStutter, 12.0, 0.3),
    ] {
        let (exact, replayed, exact_final, replayed_final) =
            exact_and_replayed(kind, freq, tau, ModelName::Eq4, 0.57, 0.025);
        assert!(
            exact > 1e-3,
            "{kind:?}: the exact jump must leave the ground"
        );
        assert!(
            relative(replayed, exact) < 0.01,
            "{kind:?}: {replayed} vs {exact}"
        );
        // The push-off may not rise above the rest height at all (final height 0): then the
        // replay must not either; otherwise within 1 %.
        if exact_final > 1e-3 {
            assert!(
                relative(replayed_final, exact_final) < 0.01,
                "{kind:?} final: {replayed_final} vs {exact_final}"
            );
        } else {
            assert!(
                replayed_final < 1e-3,
                "{kind:?} final: {replayed_final} vs {exact_final}"
            );
        }
    }
}

#[test]
fn the_stroke_follows_the_trajectory_and_holds_outside_the_log() {
    let jump = SineJump::new(JumpKind::Single, 0.01875, 10.0, 0.0).unwrap();
    let log = synthetic_log(&jump, 0.0, 0.05);
    let stroke = ReplayStroke::from_log(&log, DEFAULT_WINDOW_S).unwrap();
    assert!((stroke.end_s() - 0.15).abs() < 1e-9);
    assert_eq!(stroke.breakpoints_s(), vec![0.0, stroke.end_s()]);
    let peak = jump.eval(0.0).accel_m_s2.abs();
    // p follows the curve within the 1 um quantization everywhere. p'' carries the
    // quantization noise the short window lets through (a few m/s^2 per sample; harmless, the
    // plant responds to its double integral, ~1 um), but over any 5 ms it averages to the exact
    // p'' within 1 % of its peak.
    let block = 0.005;
    // (The last block before the end of the cycle at 0.1 s is left out: p'' steps there.)
    for k in 0..19 {
        let (a, b) = (k as f64 * block, (k + 1) as f64 * block);
        let mean = |f: &dyn Fn(f64) -> f64| {
            (0..500)
                .map(|i| f(a + (i as f64 + 0.5) * block / 500.0))
                .sum::<f64>()
                / 500.0
        };
        let got = mean(&|t| stroke.eval(t).accel_m_s2);
        let want = mean(&|t| jump.eval(t).accel_m_s2);
        assert!(
            (got - want).abs() < 1e-2 * peak,
            "mean p'' over [{a}, {b}]: {got} vs {want}"
        );
    }
    for k in 0..1500 {
        let t = k as f64 * 1e-4;
        let (got, want) = (stroke.eval(t), jump.eval(t));
        assert!((got.position_m - want.position_m).abs() < 1e-6, "p at {t}");
    }
    let before = stroke.eval(-1.0);
    let after = stroke.eval(10.0);
    assert_eq!((before.velocity_m_s, before.accel_m_s2), (0.0, 0.0));
    assert_eq!((after.velocity_m_s, after.accel_m_s2), (0.0, 0.0));
    assert!((before.position_m + 0.01875).abs() < 2e-6);
    assert!((after.position_m + 0.01875).abs() < 2e-6);
}

#[test]
fn measured_heights_are_compared_with_the_prediction() {
    let params = Params::preset(0.57).unwrap();
    let jump = SineJump::new(JumpKind::Single, params.robot.stroke_amplitude_m, 10.0, 0.0).unwrap();
    let mut log = synthetic_log(&jump, 0.0, 0.2);
    log.columns = log.columns.with(Column::RodHeightM);
    log.meta.measured_jump_height_m = Some(0.02);
    for row in log.rows.iter_mut().step_by(50) {
        row.rod_height_m = Some(0.0);
    }
    let opts = SimOptions::default();
    let out = replay_log(&log, &params, ModelName::Eq4, DEFAULT_WINDOW_S, &opts).unwrap();
    let m = out.measured.expect("the log has measurements");
    let predicted = out.outcome.summary.jump_height_m;
    assert_eq!(m.predicted_jump_height_m, predicted);
    assert!((m.jump_height_relative_error.unwrap() - (predicted - 0.02) / 0.02).abs() < 1e-12);
    assert!(m.rod_height_samples > 10);
    // "Measured" rod heights of zero: the RMS error is the predicted motion's RMS, > 0.
    assert!(m.rod_height_rms_error_m.unwrap() > 1e-4);
}

#[test]
fn a_log_shorter_than_the_window_is_refused_with_the_reason() {
    let text =
        "# rate_hz: 10000\n# counts_per_m: 1e6\nt_s,encoder_counts\n0,0\n0.0001,1\n0.0002,2\n";
    let log = read_log(text.as_bytes(), &ReadOptions::default()).unwrap();
    let params = Params::preset(0.57).unwrap();
    let err = replay_log(
        &log,
        &params,
        ModelName::Hard,
        DEFAULT_WINDOW_S,
        &SimOptions::default(),
    )
    .unwrap_err();
    assert!(
        err.contains("fewer than the differentiator's window"),
        "{err}"
    );
}
