//! The LAMMPS data file reader (`sandjumper_lammps::bed::parse_data`: a settled bed reused
//! with `--bed`, a run's `intrude.data` read back) on any text: it never panics, and what it
//! accepts has its header's count of atoms, each at most once, folded into a finite box.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_lammps::bed::parse_data;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok((bed, atoms)) = parse_data(text, "fuzz.data") {
        let w = bed.width_m;
        if w.is_finite() && w > 0.0 {
            for a in &atoms {
                for c in 0..2 {
                    let x = a.x[c];
                    assert!(
                        !x.is_finite() || (0.0..=w).contains(&x),
                        "atom {} folded to {x} outside the box 0..{w}",
                        a.id
                    );
                }
            }
        }
    }
});
