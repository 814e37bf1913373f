//! Speed of the loop.
//!
//! - SIL: one full delayed-stutter jump (tau 0.75 s, eq4, phi 0.57; 1.3 s simulated, 13,011
//!   control ticks at 10 kHz) through software in the loop. Target: at least 200x faster than
//!   real time, i.e. under 6.5 ms per jump.
//! - PIL: the delayed stutter at 10 Hz, tau 0.3 s (eq4, phi 0.57; 0.85 s simulated, 8,523
//!   ticks) through the real firmware in QEMU, QEMU's start-up included, with QEMU and the
//!   host's threads on one core (the default) and, side by side, unpinned. Target: at least
//!   2x real time, i.e. under 0.43 s. Needs QEMU and the emulated firmware (built here if
//!   missing); skipped with a message otherwise.
//! - SIL sweep: 2,000 delayed stutters (40 frequencies 4..19.6 Hz x 50 delays 6..300 ms, eq4,
//!   phi 0.57, gain lowering 0.05, the sweep's default rtol 1e-8) through the software-in-the-
//!   loop rig on 2 threads, as `sweep --link sil` runs them.

use criterion::{Criterion, criterion_group, criterion_main};
use sandjumper_model::{JumpKind, ModelName, Params};
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::pil::{self, PilConfig};
use sandjumper_rig::hil::run::rig_config;
use sandjumper_rig::hil::{HilSpec, RigModelConfig, SilLink, run_jump};
use sandjumper_study::sweep::drive::jump_metrics;
use sandjumper_study::sweep::{SweepDrive, SweepSpec, run_parallel};
use std::hint::black_box;

fn delayed_stutter_sil(c: &mut Criterion) {
    let params = Params::preset(0.57).unwrap();
    let spec = HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.75, ModelName::Eq4);
    let config = RigModelConfig::default();
    c.bench_function(
        "SIL delayed stutter tau 0.75 s, eq4, 10 kHz (1.3 s simulated)",
        |b| {
            b.iter(|| {
                let mut link = SilLink::new(rig_config(&config)).unwrap();
                run_jump(black_box(&params), black_box(&spec), config, &mut link).unwrap()
            })
        },
    );
}

fn delayed_stutter_pil(c: &mut Criterion) {
    let missing = emulated_firmware::missing_prerequisites();
    if !missing.is_empty() {
        eprintln!("PIL bench skipped: needs {}", missing.join(", "));
        return;
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let elf = match emulated_firmware::build(&root) {
        Ok(elf) => elf,
        Err(e) => {
            eprintln!("PIL bench skipped: {e}");
            return;
        }
    };
    let params = Params::preset(0.57).unwrap();
    let spec = HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.3, ModelName::Eq4);
    let config = RigModelConfig::default();
    let mut simulated_s = 0.0;
    let mut group = c.benchmark_group("PIL delayed stutter tau 0.3 s, eq4, start-up included");
    for pinned in [true, false] {
        let pil_config = PilConfig {
            pin_to_one_core: pinned,
            ..PilConfig::new(&elf)
        };
        let name = if pinned { "one core" } else { "unpinned" };
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut link = pil::start(&pil_config).unwrap();
                let o = run_jump(black_box(&params), black_box(&spec), config, &mut link).unwrap();
                simulated_s = o.simulated_time_s;
                o
            })
        });
    }
    group.finish();
    eprintln!(
        "PIL: {simulated_s:.3} s simulated per jump; real-time factor = {simulated_s:.3} s / the \
         times above (target: at least 2x, under {:.3} s)",
        simulated_s / 2.0
    );
}

fn sil_sweep_2000(c: &mut Criterion) {
    let params = Params::preset(0.57).unwrap();
    let spec = SweepSpec {
        kinds: vec![JumpKind::DelayedStutter],
        models: vec![ModelName::Eq4],
        phis: vec![0.57],
        freqs_hz: (0..40).map(|k| 4.0 + 0.4 * f64::from(k)).collect(),
        taus_s: (1..=50).map(|k| 0.006 * f64::from(k)).collect(),
        rtol: 1e-8,
        drive: SweepDrive::Sil {
            gain_lowering: Some(0.05),
        },
    };
    let combos = spec.combinations();
    assert_eq!(combos.len(), 2000);
    c.bench_function(
        "SIL sweep: 2,000 delayed stutters (tau up to 0.3 s), 2 threads",
        |b| {
            b.iter(|| {
                let out = run_parallel(&combos, 2, &|| {}, |c| {
                    jump_metrics(spec.drive, &params, c, spec.rtol)
                })
                .unwrap();
                assert_eq!(out.failures.len(), 0, "{:?}", out.failures.first());
                out
            })
        },
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).without_plots();
    targets = delayed_stutter_sil
}
criterion_group! {
    name = pil_benches;
    config = Criterion::default().sample_size(10).without_plots();
    targets = delayed_stutter_pil
}
criterion_group! {
    name = sweep_benches;
    config = Criterion::default().sample_size(10).without_plots();
    targets = sil_sweep_2000
}
criterion_main!(benches, pil_benches, sweep_benches);
