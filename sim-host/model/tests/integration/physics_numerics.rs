//! Numerical facts of the plant simulator: energy, rest, convergence, event location, ringing.

use nalgebra::Vector4;
use sandjumper_model::ground::{GroundLaw, Sand};
use sandjumper_model::hybrid::Contact;
use sandjumper_model::jump::{Kinematic, kinematic_at_rest, run_kinematic};
use sandjumper_model::robot::Robot;
use sandjumper_model::simulation::Simulation;
use sandjumper_model::trajectory::HoldStroke;
use sandjumper_model::*;

fn opts(rtol: f64) -> SimOptions {
    SimOptions {
        rtol,
        atol: rtol * 1e-3,
        ..SimOptions::default()
    }
}

/// Motor+rod and foot in the air (motor held at p = 0), ground `below_m` under the foot.
fn airborne(
    params: &Params,
    y0: Vector4<f64>,
    ground_m: f64,
    o: &SimOptions,
) -> Simulation<Kinematic<HoldStroke>, 4> {
    let robot = Robot::new(params);
    let sand = Sand::new(params, GroundLaw::resolve(ModelName::Hard, &params.model));
    let contact = Contact::in_flight(&sand, ground_m);
    Simulation::new(
        robot,
        sand,
        contact,
        Kinematic::new(HoldStroke { position_m: 0.0 }),
        y0,
        0.0,
        o,
    )
}

fn energy(r: &Robot, y: &Vector4<f64>) -> f64 {
    let m = r.motor_rod_mass_kg();
    let stretch = r.spring_rest_length_m() - (y[0] - y[2]);
    0.5 * m * y[1] * y[1]
        + 0.5 * r.foot_mass_kg() * y[3] * y[3]
        + 0.5 * r.spring_stiffness_n_m() * stretch * stretch
        + r.gravity_m_s2() * (m * y[0] + r.foot_mass_kg() * y[2])
}

#[test]
fn free_flight_without_damping_conserves_energy() {
    let mut p = Params::preset(0.57).unwrap();
    p.robot.spring_damping_n_s_m = 0.0;
    let r = Robot::new(&p);
    // Spring compressed by 1 cm, everything moving up at 3 m/s, ground far below.
    let y0 = Vector4::new(1.0 + p.robot.spring_rest_length_m - 0.01, 3.0, 1.0, 3.0);
    let mut sim = airborne(&p, y0, -100.0, &opts(1e-10));
    let e0 = energy(&r, &y0);
    let mut worst: f64 = 0.0;
    for k in 1..=50 {
        sim.advance_to(0.01 * k as f64, false).unwrap();
        assert_eq!(sim.contact.mode, GroundMode::Aerial);
        worst = worst.max((energy(&r, sim.state()) - e0).abs());
    }
    assert!(
        worst < 1e-8 * e0.abs().max(1.0),
        "energy drift {worst} J of {e0} J"
    );
    // With damping the same flight loses energy: the check above can fail.
    p.robot.spring_damping_n_s_m = 4.0;
    let mut damped = airborne(&p, y0, -100.0, &opts(1e-10));
    damped.advance_to(0.5, false).unwrap();
    assert!(energy(&r, damped.state()) < e0 - 1e-3);
}

#[test]
fn touchdown_and_apex_times_match_the_parabola() {
    let p = Params::preset(0.57).unwrap();
    let g = p.robot.gravity_m_s2;
    // Spring at its rest length and both bodies moving together: a free parabola.
    let (h0, v0) = (0.05, 1.2);
    let y0 = Vector4::new(h0 + p.robot.spring_rest_length_m, v0, h0, v0);
    let mut sim = airborne(&p, y0, 0.0, &opts(1e-8));
    assert!(sim.advance_to(2.0, true).unwrap(), "the robot lands");
    let ev = sim.events();
    let apex = ev.iter().find(|e| e.kind == EventKind::Apex).unwrap().t_s;
    let touchdown = ev
        .iter()
        .find(|e| e.kind == EventKind::Touchdown)
        .unwrap()
        .t_s;
    let apex_exact = v0 / g;
    let touchdown_exact = (v0 + (v0 * v0 + 2.0 * g * h0).sqrt()) / g;
    assert!(
        (apex - apex_exact).abs() < 1e-9,
        "apex {apex} vs {apex_exact}"
    );
    assert!(
        (touchdown - touchdown_exact).abs() < 1e-9,
        "touchdown {touchdown} vs {touchdown_exact}"
    );
    let s = sim.summary();
    assert!((s.jump_height_m - v0 * v0 / (2.0 * g)).abs() < 1e-12);
}

/// Rod ringing on the rigid floor after a kick: the times of its apexes.
fn ringing_apexes(damping: f64, rtol: f64) -> (Vec<f64>, f64) {
    let mut p = Params::preset(0.57).unwrap();
    p.robot.spring_damping_n_s_m = damping;
    let mut sim = kinematic_at_rest(
        &p,
        ModelName::Hard,
        HoldStroke { position_m: 0.0 },
        &opts(rtol),
    )
    .unwrap();
    let f0 = sim.robot.hard_ground_frequency_hz();
    // Start the rod at the equilibrium moving down slowly enough to keep the foot down.
    let mut y = *sim.state();
    y[1] = -0.05;
    let contact = sim.contact;
    sim = Simulation::new(
        sim.robot,
        sim.sand,
        contact,
        sim.actuation.clone(),
        y,
        0.0,
        &opts(rtol),
    );
    sim.advance_to(1.0, false).unwrap();
    let apexes = sim
        .events()
        .iter()
        .filter(|e| e.kind == EventKind::Apex)
        .map(|e| e.t_s)
        .collect();
    assert_eq!(
        sim.contact.mode,
        GroundMode::Static,
        "the foot stays on the floor"
    );
    (apexes, f0)
}

#[test]
fn hard_ground_ringing_is_8_18_hz_and_apex_times_are_exact() {
    let (apexes, f0) = ringing_apexes(0.0, 1e-10);
    assert!((f0 - 8.18).abs() < 0.005, "sqrt(k_s/M)/2pi = {f0}");
    // Undamped: x_r = x_eq - (v/w) sin(w t); apexes at t = (k + 3/4) T.
    let period = 1.0 / f0;
    assert!(apexes.len() >= 7);
    for (k, t) in apexes.iter().enumerate() {
        let exact = (k as f64 + 0.75) * period;
        assert!((t - exact).abs() < 1e-9, "apex {k}: {t} vs {exact}");
    }
    // With the default damping the measured period is the damped one (zeta ~ 0.03).
    let (apexes, _) = ringing_apexes(4.0, 1e-8);
    let measured = (apexes.last().unwrap() - apexes[0]) / (apexes.len() - 1) as f64;
    let f = 1.0 / measured;
    assert!((f - 8.18).abs() < 0.02, "measured ringing {f} Hz");
}

#[test]
fn a_robot_at_rest_stays_at_rest_for_10_s() {
    for model in ModelName::ALL {
        for phi in [0.57, 0.62] {
            let p = Params::preset(phi).unwrap();
            let mut sim =
                kinematic_at_rest(&p, model, HoldStroke { position_m: 0.0 }, &opts(1e-8)).unwrap();
            let y0 = *sim.state();
            sim.settle().unwrap();
            sim.advance_to(10.0, false).unwrap();
            let s = sim.summary();
            assert_eq!(s.mode_switches, 0, "{model} phi {phi}: {:?}", s.events);
            assert_eq!(sim.contact.mode, GroundMode::Static);
            assert!(
                (sim.state() - y0).norm() < 1e-9,
                "{model} phi {phi} drifted"
            );
        }
    }
}

#[test]
fn after_a_jump_the_robot_settles_without_chattering() {
    for model in ModelName::ALL {
        let p = Params::preset(0.57).unwrap();
        let stroke = sandjumper_core::SineJump::new(JumpKind::Single, 0.01875, 10.0, 0.0).unwrap();
        let mut sim = kinematic_at_rest(&p, model, stroke, &opts(1e-8)).unwrap();
        run_kinematic(&mut sim).unwrap();
        let before = sim.summary().mode_switches;
        let t = sim.time_s();
        sim.advance_to(t + 10.0, false).unwrap();
        let s = sim.summary();
        assert!(
            s.mode_switches - before <= 30,
            "{model}: {} switches while settling",
            s.mode_switches - before
        );
        assert_eq!(sim.contact.mode, GroundMode::Static, "{model} ends at rest");
        assert!(
            s.steps_accepted < 100_000,
            "{model}: {} steps",
            s.steps_accepted
        );
    }
}

/// Heights converge as rtol shrinks: rtol 1e-6 and 1e-8 are within 1e-6 m and 1e-8 m of
/// rtol 1e-10 (the bound, and the same bound two decades on). The cases include the
/// hardest seen in a 4-20 Hz scan: a 0.75 s delay on hard ground, where the undamped 8 Hz
/// ringing accumulates phase error (worst seen 7e-7 m at rtol 1e-6).
#[test]
fn heights_converge_as_rtol_shrinks() {
    let p = Params::preset(0.57).unwrap();
    let kinds = [
        (JumpKind::Single, 0.0),
        (JumpKind::Stutter, 0.0),
        (JumpKind::DelayedStutter, 0.3),
        (JumpKind::DelayedStutter, 0.75),
    ];
    for spec in jump_specs(&kinds, &[6.0, 9.0, 14.0, 16.0]) {
        let reference = simulate_jump(&p, &spec, &opts(1e-10)).unwrap().summary;
        for (rtol, bound) in [(1e-6, 1e-6), (1e-8, 1e-8)] {
            let s = simulate_jump(&p, &spec, &opts(rtol)).unwrap().summary;
            for (a, b, what) in [
                (s.jump_height_m, reference.jump_height_m, "height"),
                (
                    s.final_jump_height_m,
                    reference.final_jump_height_m,
                    "final height",
                ),
            ] {
                assert!(
                    (a - b).abs() < bound,
                    "{spec:?} {what} at rtol {rtol}: {a} vs {b}"
                );
            }
        }
    }
}

/// Every model with every `(kind, tau)` at every frequency, Hz.
fn jump_specs(kinds: &[(JumpKind, f64)], freqs_hz: &[f64]) -> Vec<JumpSpec> {
    let mut specs = Vec::new();
    for model in ModelName::ALL {
        for &(kind, tau_s) in kinds {
            for &freq_hz in freqs_hz {
                specs.push(JumpSpec {
                    kind,
                    freq_hz,
                    tau_s,
                    model,
                });
            }
        }
    }
    specs
}

/// Steps that end on a breakpoint of `p(t)` (where `p''` jumps) integrate the segment they
/// cover, so no step straddles the jump. A step that did would be rejected again and again,
/// crawling onto the breakpoint (before the fix: 10-14 % of the steps were rejected; now ~4 %,
/// the rejections of ordinary step-size control).
#[test]
fn breakpoints_cause_no_rejected_step_crawl() {
    let p = Params::preset(0.57).unwrap();
    let kinds = [
        (JumpKind::Single, 0.0),
        (JumpKind::Stutter, 0.0),
        (JumpKind::DelayedStutter, 0.3),
    ];
    for spec in jump_specs(&kinds, &[6.0, 10.0, 15.0]) {
        let s = simulate_jump(&p, &spec, &opts(1e-8)).unwrap().summary;
        assert!(
            s.steps_rejected * 100 < 7 * s.steps_accepted,
            "{spec:?}: {} rejected of {} accepted",
            s.steps_rejected,
            s.steps_accepted
        );
    }
}

#[test]
fn simulation_is_deterministic() {
    let p = Params::preset(0.58).unwrap();
    let spec = JumpSpec {
        kind: JumpKind::DelayedStutter,
        freq_hz: 9.0,
        tau_s: 0.2,
        model: ModelName::Eq4,
    };
    let a = simulate_jump(&p, &spec, &SimOptions::default()).unwrap();
    let b = simulate_jump(&p, &spec, &SimOptions::default()).unwrap();
    assert_eq!(a, b);
}

#[test]
fn plant_holding_still_stays_at_rest_and_matches_the_kinematic_jump() {
    let p = Params::preset(0.57).unwrap();
    let mut plant = Plant::new(&p, ModelName::Eq4, -0.01875, &SimOptions::default()).unwrap();
    let hold = p.robot.motor_mass_kg * p.robot.gravity_m_s2;
    let s0 = plant.state();
    for _ in 0..10_000 {
        plant.advance(1e-3, hold).unwrap();
    }
    let s1 = plant.state();
    assert!((s1.t_s - 10.0).abs() < 1e-9);
    assert_eq!(plant.summary().mode_switches, 0);
    assert!((s1.x_r - s0.x_r).abs() < 1e-9 && (s1.p - s0.p).abs() < 1e-9);
}

#[test]
fn plant_driven_by_force_intrudes_and_clamps_at_f_peak() {
    let p = Params::preset(0.6).unwrap();
    let mut plant = Plant::new(&p, ModelName::Eq4, 0.0, &SimOptions::default()).unwrap();
    // Push the carriage up hard for 30 ms (rod and foot pushed down), then pull back.
    for k in 0..200 {
        let f = if k < 30 {
            150.0
        } else if k < 60 {
            -150.0
        } else {
            11.0
        };
        plant.advance(1e-3, f).unwrap();
    }
    let s = plant.summary();
    assert!(s.events.iter().any(|e| e.kind == EventKind::Intrusion));
    assert!(s.max_depth_m > Params::preset(0.6).unwrap().sand.delta_m * 0.3);
    // Forces beyond F_peak are clamped.
    let mut plant = Plant::new(&p, ModelName::Hard, 0.0, &SimOptions::default()).unwrap();
    plant.advance(1e-2, 1e6).unwrap();
    assert!(plant.state().f_m <= p.drive.peak_force_n + 1e-9);
    assert!(plant.advance(0.0, 1.0).is_err());
}

#[test]
fn intrusion_at_low_phi_rings_near_5_hz() {
    // Kick the rod down from rest on phi = 0.57 sand (F_p = k1 z): spring and sand act as
    // springs in series, so the foot stops (the rod at its lowest point) a quarter period of
    // the ~5 Hz series oscillation after the kick (8.18 Hz on the rigid floor, tested above).
    let p = Params::preset(0.57).unwrap();
    let mut sim = kinematic_at_rest(
        &p,
        ModelName::Eq1Linear,
        HoldStroke { position_m: 0.0 },
        &opts(1e-10),
    )
    .unwrap();
    let mut y = *sim.state();
    y[1] = -0.3;
    let c = sim.contact;
    sim = Simulation::new(
        sim.robot,
        sim.sand,
        c,
        sim.actuation.clone(),
        y,
        0.0,
        &opts(1e-10),
    );
    sim.settle().unwrap();
    sim.advance_to(0.5, false).unwrap();
    let ev = sim.events();
    assert_eq!(ev[0].kind, EventKind::Intrusion);
    let stop = ev.iter().find(|e| e.kind == EventKind::Static).unwrap().t_s;
    let f = 1.0 / (4.0 * stop);
    let (ks, k1, m) = (
        p.robot.spring_stiffness_n_m,
        p.sand.k1_n_m,
        p.motor_rod_mass_kg(),
    );
    let series = (ks * k1 / (ks + k1) / m).sqrt() / core::f64::consts::TAU;
    eprintln!("ringing on sand {f:.2} Hz (springs in series: {series:.2} Hz)");
    assert!((4.0..6.0).contains(&f), "sand ringing {f} Hz");
    assert!((f - series).abs() < 0.1 * series);
}

/// The robot's centre of mass (motor, rod and foot) at a series row, m, for `p`'s masses.
fn centre_of_mass(p: &Params) -> impl Fn(&SeriesRow) -> f64 {
    let r = &p.robot;
    let (m_m, m_r, m_f) = (r.motor_mass_kg, r.rod_mass_kg, r.foot_mass_kg);
    move |s: &SeriesRow| (m_m * (s.x_r + s.p) + m_r * s.x_r + m_f * s.x_f) / (m_m + m_r + m_f)
}

/// The centre of mass's rise (motor, rod and foot) matches the one worked out from a dense time
/// series of the same run, for a single jump and a delayed stutter on sand and on hard ground;
/// it is below the rod's apex when the motor is lowered in flight, and zero for a stroke that
/// never leaves the ground.
#[test]
fn the_centre_of_mass_rise_matches_the_time_series() {
    let p = Params::preset(0.57).unwrap();
    let com = centre_of_mass(&p);
    let opts = SimOptions {
        record_series: true,
        series_interval_s: 2e-5,
        ..SimOptions::default()
    };
    for (model, kind, f, tau) in [
        (ModelName::Eq4, JumpKind::Single, 10.0, 0.0),
        (ModelName::Eq4, JumpKind::DelayedStutter, 8.5, 0.19),
        (ModelName::Hard, JumpKind::Stutter, 12.0, 0.0),
    ] {
        let o = simulate_jump(
            &p,
            &JumpSpec {
                kind,
                freq_hz: f,
                tau_s: tau,
                model,
            },
            &opts,
        )
        .unwrap();
        let series = &o.series;
        assert!(series.len() > 100);
        let com0 = com(&series[0]);
        let rise = series
            .iter()
            .map(|r| com(r) - com0)
            .fold(f64::MIN, f64::max);
        let s = &o.summary;
        assert!(
            (s.com_rise_m - rise).abs() < 2e-6 * (1.0 + rise.abs()) + 1e-6,
            "{model:?} {kind:?}: {} m against the series' {rise} m",
            s.com_rise_m
        );
        assert!(s.com_rise_m > 0.005, "{model:?} {kind:?}: {}", s.com_rise_m);
    }
}

/// Each touchdown's landing speed is the robot's centre of mass's downward speed just before
/// the contact, as a dense time series of the same run shows it (on hard ground too, where the
/// impact then stops the foot), one per `Touchdown` event.
#[test]
fn the_landing_speeds_match_the_time_series() {
    let p = Params::preset(0.57).unwrap();
    let com = centre_of_mass(&p);
    let opts = SimOptions {
        record_series: true,
        series_interval_s: 1e-5,
        ..SimOptions::default()
    };
    for (model, kind, f, tau) in [
        (ModelName::Eq4, JumpKind::Stutter, 12.0, 0.0),
        (ModelName::Eq4, JumpKind::DelayedStutter, 8.5, 0.19),
        (ModelName::Hard, JumpKind::Stutter, 12.0, 0.0),
    ] {
        let spec = JumpSpec {
            kind,
            freq_hz: f,
            tau_s: tau,
            model,
        };
        let o = simulate_jump(&p, &spec, &opts).unwrap();
        let s = &o.summary;
        let touchdowns: Vec<f64> = s
            .events
            .iter()
            .filter(|e| e.kind == EventKind::Touchdown)
            .map(|e| e.t_s)
            .collect();
        assert!(!touchdowns.is_empty(), "{model:?} {kind:?}: no landing");
        assert_eq!(touchdowns.len(), s.touchdown_speeds_m_s.len());
        for (t, speed) in touchdowns.iter().zip(&s.touchdown_speeds_m_s) {
            let before: Vec<&SeriesRow> = o.series.iter().filter(|r| r.t_s < *t).collect();
            let (a, b) = (before[before.len() - 2], before[before.len() - 1]);
            let seen = -(com(b) - com(a)) / (b.t_s - a.t_s);
            let foot = -(b.x_f - a.x_f) / (b.t_s - a.t_s);
            assert!(
                *speed > 0.05 && (speed - seen).abs() < 0.01 * seen + 1e-3,
                "{model:?} {kind:?} at {t} s: {speed} m/s against the series' {seen} m/s \
                 (the foot's {foot} m/s)"
            );
        }
    }
}
