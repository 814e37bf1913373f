//! Speed of the loop: one full delayed-stutter jump (tau 0.75 s, eq4, phi 0.57; 1.3 s simulated,
//! 13,011 control ticks at 10 kHz) through software in the loop. Target: at least 200x faster
//! than real time, i.e. under 6.5 ms per jump. (PIL speed: `sandjumper hil --link pil --bench N`,
//! it needs QEMU and the firmware ELF.)

use criterion::{Criterion, criterion_group, criterion_main};
use sandjumper_sim::rig::hil::run::rig_config;
use sandjumper_sim::rig::hil::{HilSpec, RigModelConfig, SilLink, run_jump};
use sandjumper_sim::{JumpKind, ModelName, Params};
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

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).without_plots();
    targets = delayed_stutter_sil
}
criterion_main!(benches);
