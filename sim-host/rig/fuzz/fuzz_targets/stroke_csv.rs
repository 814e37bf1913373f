//! The stroke file reader (`StrokeTable::parse_csv`: `stroke.csv` of `optimize`, read by
//! `jump --stroke`, `hil --stroke` and `rig replay --stroke`) on any text: it never panics;
//! what it accepts has at least two finite samples at a whole rate, passes or is refused by
//! the rig's feasibility check without a panic, and written back with `to_csv` reads back to
//! the same table.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_model::params::Params;
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(table) = StrokeTable::parse_csv(text) {
        assert!(table.samples_m.len() >= 2);
        assert!(table.rate_hz >= 1);
        assert!(table.samples_m.iter().all(|p| p.is_finite()));
        if let Ok(params) = Params::preset(0.6) {
            let _ = table.check(&RigLimits::of(&params));
        }
        let _ = table.period_ticks(10_000);
        let _ = table.checksum();
        let again = StrokeTable::parse_csv(&table.to_csv()).expect("what it writes, it reads");
        assert_eq!(again, table);
    }
});
