//! The final jump height (docs/model.md section 1): the push-off's own highest point, taken only
//! after the push-off half begins, checked against the sampled rod trajectory.

use sandjumper_model::*;

fn stutter(phi: f64, freq_hz: f64) -> JumpOutcome {
    let spec = JumpSpec {
        kind: JumpKind::Stutter,
        freq_hz,
        tau_s: 0.0,
        model: ModelName::Eq4,
    };
    let opts = SimOptions {
        record_series: true,
        series_interval_s: 1e-5,
        ..SimOptions::default()
    };
    simulate_jump(&Params::preset(phi).unwrap(), &spec, &opts).unwrap()
}

/// For stutters at low and high phi: the final height is reached at an apex after the
/// push-off start, and no sample after the push-off lift-off is higher (the preliminary
/// hop's falling tail at the push-off start is not the push-off's height).
#[test]
fn final_height_is_the_push_off_apex_not_the_preliminary_hops_tail() {
    for (phi, f) in [(0.57, 12.0), (0.57, 14.0), (0.62, 12.0)] {
        let out = stutter(phi, f);
        let s = &out.summary;
        let push_off = 0.5 / f;
        let x_r0 = out.series[0].x_r;
        let liftoff = s
            .final_liftoff_time_s
            .unwrap_or_else(|| panic!("phi {phi}, {f} Hz: the push-off never lifts off"));
        let sampled_max = out
            .series
            .iter()
            .filter(|r| r.t_s >= liftoff)
            .map(|r| r.x_r - x_r0)
            .fold(f64::NEG_INFINITY, f64::max);
        eprintln!(
            "phi {phi} {f} Hz: jump {:.5} m, final {:.5} m at {:.5} s, sampled max after lift-off {sampled_max:.5} m",
            s.jump_height_m, s.final_jump_height_m, s.final_apex_time_s
        );
        assert!(
            s.final_apex_time_s > push_off,
            "final apex at the push-off start"
        );
        let apex = s
            .events
            .iter()
            .find(|e| e.kind == EventKind::Apex && (e.t_s - s.final_apex_time_s).abs() < 1e-12);
        assert!(apex.is_some(), "final height not located at an apex event");
        // Exact apex vs 10 us samples: the samples can only be lower, by at most ~g dt^2/2.
        assert!(sampled_max <= s.final_jump_height_m + 1e-9);
        assert!(sampled_max >= s.final_jump_height_m - 1e-6);
        assert!(s.final_jump_height_m <= s.jump_height_m);
    }
}
