//! Fault injection through SIL. Each fault is detected, the force is zero within 2 ticks of
//! the fault being latched (here: from the very tick the controller reports it), the fault code
//! is reported, and the acquisition log is intact up to the fault (consecutive sequence
//! numbers, and it writes and reads back in the acquisition-log format).

use crate::hil_common;

use hil_common::{params, sil};
use sandjumper_acqlog::{ReadOptions, read_log};
use sandjumper_core::FaultCode;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::{ModelName, Params};
use sandjumper_rig::hil::log::acquisition_log;
use sandjumper_rig::hil::{HilOutcome, HilSpec, InjectedFault, Injection};

/// 30 ms into a 10 Hz single jump on sand at phi 0.57: the motor is moving fast.
const AT_S: f64 = 0.03;

fn spec_with(fault: InjectedFault) -> HilSpec {
    let mut s = HilSpec::new(JumpKind::Single, 10.0, 0.0, ModelName::Eq4);
    s.injections.push(Injection { at_s: AT_S, fault });
    s
}

/// The common checks; returns the controller tick the fault was latched on.
fn check_fault(p: &Params, spec: &HilSpec, o: &HilOutcome, expected: FaultCode) -> u32 {
    let report = o
        .first_fault()
        .unwrap_or_else(|| panic!("no fault reported for {:?}", spec.injections));
    assert_eq!(report.code, expected, "{:?}", spec.injections);
    assert_eq!(o.faults.len(), 1, "one latched fault: {:?}", o.faults);
    // Force: the first period whose answer reports the fault, and every period after it, has
    // zero force at the drive; that period is the fault's own tick (or, for a link that went
    // silent, the first period after the timeout).
    let first = o
        .trace
        .iter()
        .position(|r| r.faulted)
        .expect("a faulted answer");
    if let Some(t) = o.trace[first].rig_tick {
        assert!(
            t <= report.tick + 2,
            "force zeroed at tick {t}, fault latched at {}",
            report.tick
        );
    }
    for r in &o.trace[first..] {
        assert_eq!(
            r.drive_command_n, 0.0,
            "period {} after the fault",
            r.period
        );
    }
    // Zero force in the controller's own records from the fault tick on.
    for s in o.samples.iter().filter(|s| s.tick >= report.tick) {
        assert_eq!(s.force_n, 0.0, "tick {}", s.tick);
    }
    // The log is intact up to the fault: sequence numbers 0.. without a gap through the fault.
    let upto: Vec<_> = o.samples.iter().filter(|s| s.tick <= report.tick).collect();
    for (i, s) in upto.iter().enumerate() {
        assert_eq!(s.seq as usize, i, "sample sequence");
    }
    assert_eq!(o.samples_missing(), 0);
    let log = acquisition_log(o, spec, 10_000, 1e-6, p.robot.stroke_amplitude_m, 0.57);
    let bytes = log.write_csv(Vec::new()).expect("log writes");
    let back = read_log(bytes.as_slice(), &ReadOptions::default()).expect("log reads back");
    assert_eq!(back.rows.len(), o.samples.len());
    report.tick
}

#[test]
fn frozen_encoder_is_caught_as_a_tracking_error() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::EncoderFrozen);
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::TrackingError);
    // Within the time the commanded motion takes to move 5 mm away from the frozen reading.
    assert!(
        u64::from(tick) < o.start_period + 300 + 200,
        "detected at tick {tick}"
    );
}

#[test]
fn encoder_jump_is_an_encoder_fault_on_the_same_tick() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::EncoderJump { counts: 5_000 });
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::EncoderFault);
    assert_eq!(u64::from(tick), o.start_period + 300);
}

#[test]
fn motor_beyond_the_stroke_is_a_stroke_limit_fault() {
    // A controller that cannot hold the carriage up (position gain 200 N/m, no integrator) with
    // a generous tracking bound: the carriage sinks from -18.75 mm past the 25.5 mm limit.
    let p = params(0.57);
    let mut spec = HilSpec::new(JumpKind::Single, 10.0, 0.0, ModelName::Eq4);
    spec.gains.kp_n_per_m = 200.0;
    spec.gains.kd_n_s_per_m = 5.0;
    spec.gains.ki_n_per_m_s = 0.0;
    spec.tracking_error_limit_m = 0.05;
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::StrokeLimit);
    // The measured position at the fault tick is beyond the limit.
    let s = o
        .samples
        .iter()
        .find(|s| s.tick == tick)
        .expect("sample at the fault");
    assert!(
        (s.encoder_count as f64 * 1e-6).abs() > 0.0255,
        "{}",
        s.encoder_count
    );
}

#[test]
fn simulated_control_overrun_is_a_deadline_fault_on_the_same_tick() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::Overrun);
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::DeadlineOverrun);
    assert_eq!(u64::from(tick), o.start_period + 300);
}

#[test]
fn a_rig_whose_lift_is_not_down_refuses_to_arm_and_one_whose_lift_is_down_jumps() {
    use sandjumper_core::bed::BedInputs;
    use sandjumper_rig::hil::run::rig_config;
    use sandjumper_rig::hil::{RigModelConfig, SilLink, run_jump};
    let p = params(0.57);
    let mut spec = HilSpec::new(JumpKind::Single, 10.0, 0.0, ModelName::Eq4);
    let config = RigModelConfig::default();
    spec.bed = Some(BedInputs {
        lift_up_limit: true,
        ..BedInputs::default()
    });
    let mut link = SilLink::new(rig_config(&config)).unwrap();
    let err = run_jump(&p, &spec, config, &mut link).expect_err("the interlock refuses Arm");
    assert!(err.to_string().contains("the lift is not down"), "{err}");
    spec.bed = Some(BedInputs {
        lift_down_limit: true,
        ..BedInputs::default()
    });
    let o = sil(&p, &spec);
    assert!(o.faults.is_empty(), "{:?}", o.faults);
    assert!(o.summary.jump_height_m > 0.03);
}

#[test]
fn the_emergency_stop_in_the_sensor_frames_is_a_fault_on_the_same_tick() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::EmergencyStop);
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::EmergencyStop);
    assert_eq!(u64::from(tick), o.start_period + 300);
}

#[test]
fn link_that_stops_is_a_link_lost_fault_and_zero_force() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::LinkStops);
    let o = sil(&p, &spec);
    check_fault(&p, &spec, &o, FaultCode::LinkLost);
    // The SIL glue's timeout is 2 periods: zero force from the second silent period.
    let silent = (o.start_period + 300) as usize - 1; // trace starts at period 1
    assert!(o.trace[silent].rig_tick.is_none());
    assert!(
        o.trace[silent + 1].faulted,
        "fault reported in the second silent period"
    );
}

#[test]
fn a_few_corrupted_frames_are_rejected_and_counted_without_a_fault() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::CorruptFrames { count: 3 });
    let o = sil(&p, &spec);
    assert!(o.faults.is_empty(), "{:?}", o.faults);
    assert_eq!(o.frames_rejected, 3);
    // The controller saw 3 frame numbers missing.
    assert_eq!(o.frames_lost, 3);
    assert!(o.summary.jump_height_m > 0.02, "the jump still happens");
}

#[test]
fn a_burst_of_corrupted_frames_beyond_the_limit_faults() {
    let p = params(0.57);
    let spec = spec_with(InjectedFault::CorruptFrames { count: 12 });
    let o = sil(&p, &spec);
    let tick = check_fault(&p, &spec, &o, FaultCode::LinkCorrupted);
    assert_eq!(o.frames_rejected, 12);
    // Latched on the 10th rejected frame (the default limit): the next tick the controller runs.
    assert_eq!(u64::from(tick), o.start_period + 300);
}
