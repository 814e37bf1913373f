//! Fuzz target: the acquisition-log reader must refuse bad input with an error, never panic,
//! and whatever it accepts must write back and read again to the same log.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_acqlog::{ReadOptions, read_log};

fuzz_target!(|data: &[u8]| {
    for allow_gaps in [false, true] {
        let opts = ReadOptions {
            allow_gaps,
            max_rows: 10_000,
            max_line_bytes: 1024,
        };
        if let Ok(log) = read_log(data, &opts) {
            let _ = log.summary();
            let mut clean = log.clone();
            clean.gaps.clear();
            let bytes = clean
                .write_csv(Vec::new())
                .expect("an accepted log writes back");
            let back = read_log(bytes.as_slice(), &opts).expect("a written log reads back");
            assert_eq!(back.rows, log.rows);
            assert_eq!(back.meta, log.meta);
        }
    }
});
