//! The LAMMPS data file reader (`sandjumper_lammps::bed::parse_data`: a settled bed reused
//! with `--bed`, a run's `intrude.data` read back) on any text: it never panics, and what it
//! accepts is a finite box holding finite atoms, each id at most once, folded into the box
//! across its periodic sides.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_lammps::bed::parse_data;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok((bed, atoms)) = parse_data(text, "fuzz.data") {
        assert!(
            bed.width_m.is_finite() && bed.width_m > 0.0 && bed.top_m.is_finite(),
            "{bed:?}"
        );
        let mut ids = std::collections::HashSet::new();
        for a in &atoms {
            assert!(ids.insert(a.id), "atom {} accepted twice", a.id);
            assert!(
                a.x.iter().chain(&a.v).all(|c| c.is_finite())
                    && a.diameter_m.is_finite()
                    && a.density_kg_m3.is_finite(),
                "a non-finite atom accepted: {a:?}"
            );
            let w = bed.width_m;
            for c in 0..2 {
                assert!(
                    (0.0..=w).contains(&a.x[c]),
                    "atom {} folded to {} outside the box 0..{w}",
                    a.id,
                    a.x[c]
                );
            }
        }
    }
});
