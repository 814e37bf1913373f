//! Fuzz the frame decoder: arbitrary bytes, streamed and as one frame, in both directions'
//! message types, and as payloads behind a valid CRC. It must never panic, and every completed
//! frame must be counted.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_core::protocol::{FrameDecoder, MAX_FRAME, decode_frame, encode_payload_frame};
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

    // The same bytes as a payload behind a valid CRC: exercises the message deserializer.
    let mut frame = [0u8; MAX_FRAME];
    if let Ok(n) = encode_payload_frame(data, &mut frame) {
        let _ = decode_frame::<HostMessage>(&mut frame[..n - 1]);
        let n = encode_payload_frame(data, &mut frame).unwrap_or(1);
        let _ = decode_frame::<RigMessage>(&mut frame[..n - 1]);
    }
});
