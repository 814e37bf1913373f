//! DEM bed preparation: a settled bed carries its weight (floor force, stress profile), a
//! packed bed reaches its area fraction, and checkpoints round-trip or are refused.

use sandjumper_dem::bed::{BedMethod, BedSpec, prepare};
use sandjumper_dem::grains::SizeDistribution;
use sandjumper_dem::params::{Choice, Model};

fn settled(
    model: Model,
    sizes: SizeDistribution,
) -> (sandjumper_dem::world::World, sandjumper_dem::bed::BedReport) {
    let mut c = Choice::new(model);
    c.sizes = sizes;
    c.overlap = 0.02;
    let p = c.resolve(false).unwrap();
    let spec = BedSpec {
        width_m: 0.02,
        height_m: 0.012,
        method: BedMethod::Settle,
        seed: 7,
        max_time_s: 1.0,
        rest_agitation: 1e-9,
    };
    prepare(&p, &spec, |_| {}).unwrap()
}

#[test]
fn settled_bed_on_a_frictionless_floor_carries_its_weight() {
    let (mut w, rep) = settled(Model::Paper, SizeDistribution::BI);
    eprintln!("{rep:?}");
    assert!(rep.settled, "{rep:?}");
    // Hold it under the gravity it settled with and read the floor.
    w.cfg.drag_per_s = 0.0;
    w.step();
    let weight = rep.mass_kg * w.cfg.gravity_m_s2;
    let floor = w.last.floor_n;
    eprintln!(
        "floor {floor} weight {weight} ratio {}",
        floor / weight - 1.0
    );
    assert!(
        (floor / weight - 1.0).abs() < 1e-3,
        "floor {floor} N, weight {weight} N"
    );
    // The vertical load across each height equals the weight of the grains above it.
    let heights: Vec<f64> = (1..8).map(|k| rep.surface_m * k as f64 / 8.0).collect();
    let load = w.vertical_load_across(&heights);
    for (h, l) in heights.iter().zip(&load) {
        let above: f64 = (0..w.g.len())
            .filter(|&i| w.g.y[i] >= *h)
            .map(|i| w.g.mass(i) * w.cfg.gravity_m_s2)
            .sum();
        eprintln!("h {h:.4} load {l:.4e} above {above:.4e}");
        assert!(
            (l / above - 1.0).abs() < 1e-3 * 5.0,
            "at {h} m: {l} N vs {above} N"
        );
    }
}
