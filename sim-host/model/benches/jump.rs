//! Speed of the plant simulator: one eq4 single jump at rtol 1e-8, and a 2,000-jump sweep on
//! two threads (targets on the 2-core machine: < 60 us and < 0.3 s). Beside them, the floor
//! of the method on the machine at hand: the same Dormand-Prince stepper on the robot's free
//! flight alone (no ground, no events, no dense-output use), whose time per step is what any
//! jump's steps cost at the least. And the same jump in its three phases (the foot in the sand
//! until lift-off, flight while the stroke runs, flight after it), so the cost beyond that
//! floor can be placed.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector4;
use sandjumper_core::trajectory::SineJump;
use sandjumper_model::jump::{GROUNDED_TAIL_S, Kinematic, kinematic_at_rest};
use sandjumper_model::robot::Robot;
use sandjumper_model::simulation::{Simulation, plant_stepper};
use sandjumper_model::*;
use std::hint::black_box;

/// The benchmark jump: eq4, phi 0.57, a 10 Hz single jump at rtol 1e-8.
fn benchmark_jump() -> (Params, JumpSpec, SimOptions) {
    let params = Params::preset(0.57).unwrap();
    let spec = JumpSpec {
        kind: JumpKind::Single,
        freq_hz: 10.0,
        tau_s: 0.0,
        model: ModelName::Eq4,
    };
    let opts = SimOptions {
        rtol: 1e-8,
        ..SimOptions::default()
    };
    (params, spec, opts)
}

fn one_jump(c: &mut Criterion) {
    let (params, spec, opts) = benchmark_jump();
    c.bench_function("eq4 single jump, rtol 1e-8", |b| {
        b.iter(|| simulate_jump(black_box(&params), black_box(&spec), &opts).unwrap())
    });
}

/// The robot in free flight with its foot ringing, integrated for `duration_s` by the bare
/// stepper, configured as a jump's ([`plant_stepper`]) at rtol 1e-8: returns the accepted steps.
fn free_flight(robot: &Robot, duration_s: f64) -> u64 {
    let mut rhs = |_t: f64, y: &Vector4<f64>| {
        let f_s = robot.spring_force(y[0], y[1], y[2], y[3]);
        Vector4::new(
            y[1],
            robot.rod_accel_kinematic(f_s, 0.0),
            y[3],
            robot.foot_accel_aerial(f_s),
        )
    };
    let (mut t, mut y) = (
        0.0,
        Vector4::new(robot.rest_rod_above_foot_m(), 1.5, 0.0, 2.5),
    );
    let opts = SimOptions {
        rtol: 1e-8,
        ..SimOptions::default()
    };
    let mut dp = plant_stepper(&opts, &y);
    while t < duration_s {
        dp.step(&mut rhs, t, &y, duration_s).unwrap();
        t = dp.dense().t1;
        y = dp.dense().end_state();
    }
    dp.accepted
}

fn integrator_floor(c: &mut Criterion) {
    let robot = Robot::new(&Params::preset(0.57).unwrap());
    let steps = free_flight(&robot, 0.25);
    c.bench_function(
        &format!("integrator floor: {steps} DP5 steps of free flight, rtol 1e-8"),
        |b| b.iter(|| free_flight(black_box(&robot), 0.25)),
    );
}

/// The benchmark jump in three phases, each run from a copy of the simulation where the last
/// one ended: the foot in the sand up to the first lift-off, flight to the stroke's end, and
/// flight to touchdown (the run-length rule of `run_kinematic`). The phases' boundaries add
/// one step end at lift-off, so their steps sum to about the jump's.
fn jump_phases(c: &mut Criterion) {
    let (params, spec, opts) = benchmark_jump();
    let liftoff_s = simulate_jump(&params, &spec, &opts)
        .unwrap()
        .summary
        .liftoff_time_s
        .unwrap();
    let stroke = SineJump::new(
        spec.kind,
        params.robot.stroke_amplitude_m,
        spec.freq_hz,
        spec.tau_s,
    )
    .unwrap();
    let end_s = stroke.end_s();
    let mut at_rest = kinematic_at_rest(&params, spec.model, stroke, &opts).unwrap();
    at_rest.settle().unwrap();
    at_rest.actuation.begin_segment(end_s);
    let mut lifted = at_rest.clone();
    lifted.advance_to(liftoff_s, false).unwrap();
    let mut stroke_done = lifted.clone();
    stroke_done.advance_to(end_s, false).unwrap();
    stroke_done.discontinuity();
    stroke_done.actuation.begin_segment(f64::INFINITY);
    let steps = |sim: &Simulation<Kinematic<SineJump>, 4>| {
        let s = sim.summary();
        s.steps_accepted + s.steps_rejected
    };
    let mut landed = stroke_done.clone();
    assert!(landed.advance_to(end_s + GROUNDED_TAIL_S, true).unwrap());
    let phases = [
        (
            "in the sand to lift-off",
            &at_rest,
            liftoff_s,
            false,
            steps(&lifted),
        ),
        (
            "flight under the stroke",
            &lifted,
            end_s,
            false,
            steps(&stroke_done) - steps(&lifted),
        ),
        (
            "flight to touchdown",
            &stroke_done,
            end_s + GROUNDED_TAIL_S,
            true,
            steps(&landed) - steps(&stroke_done),
        ),
    ];
    let mut group = c.benchmark_group("eq4 single jump phases");
    for (name, start, until_s, stop_at_touchdown, n) in phases {
        group.bench_function(format!("{name}: {n} steps"), |b| {
            b.iter(|| {
                let mut sim = start.clone();
                sim.advance_to(black_box(until_s), stop_at_touchdown)
                    .unwrap()
            })
        });
    }
    group.finish();
}

fn sweep(c: &mut Criterion) {
    let (params, _, opts) = benchmark_jump();
    // 2,000 jumps: 4 models x 2 kinds x 250 frequencies from 4 to 20 Hz... on two threads.
    let mut specs = Vec::with_capacity(2000);
    for model in ModelName::ALL {
        for kind in [JumpKind::Single, JumpKind::Stutter] {
            for i in 0..250 {
                let freq_hz = 4.0 + 16.0 * i as f64 / 249.0;
                specs.push(JumpSpec {
                    kind,
                    freq_hz,
                    tau_s: 0.0,
                    model,
                });
            }
        }
    }
    assert_eq!(specs.len(), 2000);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("sweep");
    group.sample_size(10);
    group.bench_function("2000 jumps, 2 threads", |b| {
        b.iter(|| pool.install(|| simulate_many(black_box(&params), &specs, &opts)))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: criterion's plotters backend needs system fonts a fresh machine lacks.
    config = Criterion::default().without_plots();
    targets = one_jump, jump_phases, integrator_floor, sweep
}
criterion_main!(benches);
