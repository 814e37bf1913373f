//! The campaign file reader (`CampaignFile::parse`, what `campaign run FILE` reads) on any
//! text: it never panics, and a file it accepts also passes or refuses the board check
//! (`check_for_board`) without a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_campaign::file::CampaignFile;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(file) = CampaignFile::parse(text, "fuzz.toml") {
        let _ = file.check_for_board("fuzz.toml");
    }
});
