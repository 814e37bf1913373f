//! The LAMMPS dump reader (`sandjumper_lammps::dump::parse_frame`) on any bytes, as text and
//! as gzip: it never panics, and what it accepts is a frame of the run it was checked
//! against (every atom of the run, with the run's radius; no more atoms than the run has).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_lammps::dump::{DumpFormat, RunCheck, parse_frame};

fuzz_target!(|data: &[u8]| {
    let check = |format| RunCheck {
        width_m: 0.06,
        radius_by_id: [(1, 0.001), (2, 0.0009), (3, 0.001)].into_iter().collect(),
        format,
    };
    for format in [DumpFormat::Text, DumpFormat::Gzip] {
        let c = check(format);
        if let Ok(frame) = parse_frame(std::io::Cursor::new(data.to_vec()), "fuzz", 40, &c) {
            assert_eq!(frame.step, 40);
            assert!(frame.atoms.len() <= c.radius_by_id.len());
            for a in &frame.atoms {
                let r = c.radius_by_id[&a.id];
                assert!((a.radius_m - r).abs() <= 1e-6 * r);
            }
        }
    }
});
