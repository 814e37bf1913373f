//! A small DEM intrusion from Rust: a packed bed 16 mm wide and 8 mm deep, a 6 mm foot
//! pushed 2 mm into it at 0.3 m/s, and what the run found (about a second).
//!
//! Run it with `cargo run --example intrusion -p sandjumper-dem`.

use sandjumper_dem::bed_run::{self, BedRequest};
use sandjumper_dem::intrude_run::{self, IntrudeOutcome, IntrudeRequest};
use sandjumper_dem::request::ModelRequest;
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::temp_dir().join("sandjumper-dem-example");
    let model = ModelRequest {
        overlap: 0.02,
        ..ModelRequest::default()
    };
    // The bed: packed to an area fraction of 0.8 with no gravity.
    let bed = bed_run::run(
        &BedRequest {
            model: model.clone(),
            width_m: 0.016,
            height_m: 0.008,
            pack: Some(0.8),
            out: dir.join("bed"),
            ..BedRequest::default()
        },
        &Silent,
    )?;
    println!("{bed}");
    // The foot: at constant speed to 2 mm, the frames left out.
    let outcome = intrude_run::run(
        &IntrudeRequest {
            bed: Some(bed.out),
            speed_m_s: Some(0.3),
            depth_m: 0.002,
            foot_width_m: 0.006,
            model: ModelRequest {
                walls: true,
                ..model
            },
            frames: false,
            out: dir.join("intrusion"),
            ..IntrudeRequest::default()
        },
        &Silent,
    )?;
    if let IntrudeOutcome::Finished(s) = &outcome {
        println!(
            "peak force {:.3} N, added mass {:.2e} kg",
            s.max_force_n, s.final_added_mass_kg
        );
    }
    println!("{outcome}");
    Ok(())
}
