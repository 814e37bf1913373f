//! Fuzz the frame decoder: arbitrary bytes, streamed and as one frame, in both directions'
//! message types. It must never panic, and every completed frame must be counted.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_core::protocol::{FrameDecoder, decode_frame};
use sandjumper_core::{HostMessage, RigMessage};

fuzz_target!(|data: &[u8]| {
    let mut host = FrameDecoder::new();
    let mut rig = FrameDecoder::new();
    let (mut n_host, mut n_rig) = (0u32, 0u32);
    for &b in data {
        n_host += host.push::<HostMessage>(b).is_some() as u32;
        n_rig += rig.push::<RigMessage>(b).is_some() as u32;
    }
    assert_eq!(host.stats().ok + host.stats().rejected, n_host);
    assert_eq!(rig.stats().ok + rig.stats().rejected, n_rig);

    let mut buf = data.to_vec();
    let _ = decode_frame::<HostMessage>(&mut buf);
    let mut buf = data.to_vec();
    let _ = decode_frame::<RigMessage>(&mut buf);
});
