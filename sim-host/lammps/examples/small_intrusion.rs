//! The 3-D intrusion from Rust, as `sandjumper dem lammps --preset small --speed 0.1 --out
//! OUT` runs it: LAMMPS pours the bed and drives the foot, and the dumps are read back into
//! the added mass, the column's momentum and the force. Needs LAMMPS (`$SANDJUMPER_LMP`, or
//! `lmp` on PATH) and MPI; minutes on two cores.
//!
//! Run it with `cargo run --release -p sandjumper-lammps --example small_intrusion -- OUT`.

use sandjumper_lammps::run::{self, LammpsRequest};
use sandjumper_lammps::spec::Preset;
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(out) = std::env::args_os().nth(1) else {
        return Err("usage: small_intrusion OUT (the output folder to write)".into());
    };
    let request = LammpsRequest {
        preset: Preset::Small,
        speed_m_s: Some(0.1),
        ranks: 2,
        out: out.into(),
        ..LammpsRequest::default()
    };
    // Refused here (bad values, no LAMMPS) before anything runs.
    request.validate()?;
    let outcome = run::run(&request, &Silent)?;
    println!("{outcome}");
    println!(
        "added mass / eq. 6 {:.2}; written to {}",
        outcome.summary.added_mass_vs_eq6_median,
        outcome.out.display()
    );
    Ok(())
}
