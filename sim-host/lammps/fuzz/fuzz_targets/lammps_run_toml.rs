//! A LAMMPS run's record (`run.toml`, read back by `dem lammps --read` and `figures dem`) on
//! any text (`sandjumper_lammps::outputs::Manifest::parse`): it never panics, and what it
//! accepts has a valid spec that agrees with its geometry, and reads back as itself once
//! written out again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_lammps::outputs::Manifest;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(m) = Manifest::parse(text) {
        m.spec.check().expect("an accepted record's spec is valid");
        m.check().expect("an accepted record agrees with its spec");
        let again = toml::to_string(&m).expect("an accepted record writes out");
        let back = Manifest::parse(&again).expect("what was written reads back");
        // Floats round-trip through TOML exactly (NaN aside: never equal to itself).
        if format!("{m:?}").contains("NaN") {
            return;
        }
        assert_eq!(back, m, "read back as itself");
    }
});
