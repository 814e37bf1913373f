//! The drive calibration file reader (`parse_calibration`: what `rig calibrate-drive` saves
//! and every rig program's `--drive-calibration FILE` reads) on any text: it never panics;
//! what it accepts the controller accepts too (`validate`), and written back as TOML it reads
//! back to the same calibration.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_rig::tool::drive_calibration::parse_calibration;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(cal) = parse_calibration(text) {
        assert!(
            cal.validate().is_ok(),
            "accepted, yet the controller refuses {cal:?}"
        );
        let written = toml::to_string(&cal).expect("a calibration writes out");
        assert_eq!(parse_calibration(&written), Ok(cal), "read back as itself");
    }
});
