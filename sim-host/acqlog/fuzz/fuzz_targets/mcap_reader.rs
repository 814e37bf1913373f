//! The MCAP reader (`sandjumper_acqlog::read_messages`, which recovers what a cut file
//! holds) on any bytes: it never panics; whatever a damaged length says, no allocation passes
//! 160 MiB (a record's 64 MiB limit, zstd's window of 128 MiB at most: `.ci/fuzz` runs it with
//! libFuzzer's `-malloc_limit_mb=160`; the list of messages read could pass it only past two
//! million messages, which a valid zstd chunk of a few kilobytes can hold but mutation is not
//! known to reach); and the file cut anywhere yields a prefix of the whole file's messages (a
//! cut costs the messages after it, never changes one before it).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_acqlog::read_messages;

fuzz_target!(|input: &[u8]| {
    // The last byte says where to cut (its share of the file), the rest is the file: the
    // file's own bytes would cut every MCAP file at the same place (its magic starts 0x89).
    let Some((&share, data)) = input.split_last() else {
        return;
    };
    let whole = read_messages(data);
    let at = data.len() * usize::from(share) / 256;
    let cut = read_messages(&data[..at]);
    assert!(
        cut.messages.len() <= whole.messages.len()
            && cut.messages[..] == whole.messages[..cut.messages.len()],
        "cut at {at} of {}: {} messages, not a prefix of the whole file's {}",
        data.len(),
        cut.messages.len(),
        whole.messages.len()
    );
});
