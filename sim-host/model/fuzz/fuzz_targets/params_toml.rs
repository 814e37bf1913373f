//! The parameter file reader (`Params::with_overrides_toml`, what `--params FILE` and every
//! `params.toml` go through) on any text: it never panics; what it accepts is valid
//! (`validate`), and written back with `to_toml` it reads back to the same parameters.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_model::params::Params;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(base) = Params::preset(0.6) else {
        return;
    };
    if let Ok(p) = base.clone().with_overrides_toml(text, "fuzz.toml") {
        assert!(p.validate().is_ok(), "accepted but invalid: {p:?}");
        let written = p.to_toml();
        let again = base
            .with_overrides_toml(&written, "written.toml")
            .expect("what it writes, it reads");
        assert_eq!(again, p);
    }
});
