//! DEM bed preparation: a settled bed carries its weight (floor force, stress profile),
//! monodisperse beds crystallise and bidisperse ones do not, and checkpoints round-trip or
//! are refused.

use sandjumper_dem::bed::{BedMethod, BedSpec, prepare};
use sandjumper_dem::checkpoint;
use sandjumper_dem::grains::SizeDistribution;
use sandjumper_dem::params::{Choice, Model};
use sandjumper_dem::structure::hexatic_order;

/// A bed of `model`'s grains of `sizes` (at a 2 % overlap) prepared as `spec` says.
fn prepared(
    model: Model,
    sizes: SizeDistribution,
    spec: &BedSpec,
) -> (sandjumper_dem::world::World, sandjumper_dem::bed::BedReport) {
    let mut c = Choice::new(model);
    c.sizes = sizes;
    c.overlap = 0.02;
    let p = c.resolve(false).unwrap();
    prepare(&p, spec, |_| true).unwrap()
}

fn settled(
    model: Model,
    sizes: SizeDistribution,
) -> (sandjumper_dem::world::World, sandjumper_dem::bed::BedReport) {
    let spec = BedSpec {
        width_m: 0.02,
        height_m: 0.012,
        method: BedMethod::Settle,
        seed: 7,
        max_time_s: 1.0,
        rest_agitation: 1e-9,
    };
    prepared(model, sizes, &spec)
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

fn settled_hexatic(sizes: SizeDistribution) -> f64 {
    let spec = BedSpec {
        width_m: 0.025,
        height_m: 0.012,
        method: BedMethod::Settle,
        seed: 3,
        max_time_s: 0.6,
        rest_agitation: 1e-7,
    };
    hexatic_order(&prepared(Model::Full, sizes, &spec).0)
}

#[test]
fn monodisperse_beds_crystallise_and_bidisperse_ones_do_not() {
    let mono = settled_hexatic(SizeDistribution::Mono);
    let bi = settled_hexatic(SizeDistribution::BI);
    eprintln!("hexatic order: mono {mono:.3}, bi {bi:.3}");
    assert!(mono > 0.7, "mono {mono}");
    assert!(bi < 0.6, "bi {bi}");
}

#[test]
fn checkpoints_round_trip_and_refuse_corruption() {
    let spec = BedSpec {
        width_m: 0.012,
        height_m: 0.006,
        method: BedMethod::Pack { phi: 0.8 },
        seed: 5,
        max_time_s: 0.01,
        rest_agitation: 1e-6,
    };
    let (mut w, _) = prepared(Model::Full, SizeDistribution::BI, &spec);
    w.cfg.gravity_m_s2 = 9.81;
    for _ in 0..500 {
        w.step();
    }
    w.rebuild();
    let rec = serde_json::json!({"note": "x"});
    let bytes = checkpoint::encode(&w, &rec, &[1.0, 2.5]);
    let mut a = checkpoint::decode(&bytes).unwrap();
    assert_eq!(a.extra, vec![1.0, 2.5]);
    assert_eq!(a.record, rec);
    assert_eq!(a.world.g, w.g);
    // The same future.
    let mut b = w.clone();
    for _ in 0..300 {
        a.world.step();
        b.step();
    }
    assert_eq!(a.world.g.x, b.g.x);
    assert_eq!(a.world.g.vy, b.g.vy);
    // A flipped byte, a cut file, another version: refused with the reason.
    let mut bad = bytes.clone();
    let k = bad.len() / 2;
    bad[k] ^= 0x10;
    assert!(checkpoint::decode(&bad).unwrap_err().contains("checksum"));
    let cut = &bytes[..bytes.len() - 100];
    assert!(checkpoint::decode(cut).is_err());
    let mut ver = bytes.clone();
    ver[8] = 9;
    assert!(checkpoint::decode(&ver).unwrap_err().contains("version"));
    assert!(
        checkpoint::decode(b"hello")
            .unwrap_err()
            .contains("not a sandjumper")
    );
}
