use super::*;
use crate::command::REPLAY_CHUNK;
use crate::config::{JumpConfig, TrajectorySpec};
use crate::controller::GainLowering;
use crate::rig::Counters;
use crate::trajectory::JumpKind;
use proptest::prelude::*;

fn sample_messages() -> [HostMessage; 5] {
    let mut jc = JumpConfig::new(TrajectorySpec::Sine {
        kind: JumpKind::DelayedStutter,
        amplitude_m: 0.01875,
        freq_hz: 12.0,
        tau_s: 0.75,
    });
    jc.gain_lowering = Some(GainLowering {
        kp_factor: 0.1,
        kd_factor: 1.0,
        ramp_s: 0.05,
    });
    let chunk: heapless::Vec<f32, REPLAY_CHUNK> =
        (0..REPLAY_CHUNK).map(|k| k as f32 * 1e-4).collect();
    [
        HostMessage::Command {
            id: 1,
            command: Command::Configure(jc),
        },
        HostMessage::Command {
            id: 2,
            command: Command::ReplayChunk {
                offset: 64,
                samples: chunk,
            },
        },
        HostMessage::Command {
            id: 3,
            command: Command::Arm,
        },
        HostMessage::Sensor(SensorFrame {
            frame: 7,
            encoder_count: u32::MAX,
            current_a: Some(1.5),
            overrun: false,
            bed: None,
        }),
        HostMessage::Sensor(SensorFrame {
            frame: 8,
            encoder_count: 0,
            current_a: None,
            overrun: true,
            bed: Some(crate::bed::BedInputs {
                lift_up_limit: false,
                lift_down_limit: true,
                emergency_stop: true,
                height_raw: 4095,
            }),
        }),
    ]
}

fn full_batch() -> RigMessage {
    let rec = SampleRecord {
        seq: u32::MAX,
        tick: u32::MAX,
        encoder_count: i64::MIN,
        commanded_position_m: -0.025,
        force_n: 300.0,
        current_a: Some(-12.5),
        camera_frame: Some(u32::MAX),
        flags: u16::MAX,
    };
    RigMessage::Samples((0..SAMPLE_BATCH).map(|_| rec).collect())
}

#[test]
fn round_trip_through_frames_and_the_streaming_decoder() {
    let mut dec = FrameDecoder::new();
    for msg in sample_messages() {
        let frame = encode_frame_vec(&msg).unwrap();
        assert_eq!(
            frame.iter().filter(|b| **b == 0).count(),
            1,
            "only the delimiter is 0"
        );
        assert_eq!(frame.last(), Some(&0));
        let mut out = None;
        for &b in &frame {
            if let Some(r) = dec.push::<HostMessage>(b) {
                out = Some(r);
            }
        }
        assert_eq!(out, Some(Ok(msg)));
    }
    assert_eq!(dec.stats().ok, 5);
    assert_eq!(dec.stats().rejected, 0);
}

#[test]
fn worst_case_rig_messages_fit_a_frame() {
    let status = Status {
        state: RigState::Faulted,
        phase: crate::profile::Phase::PushOff,
        fault: Some(FaultCode::LinkLost),
        fault_tick: u32::MAX,
        tick: u32::MAX,
        run_tick: u32::MAX,
        camera_frames: u32::MAX,
        configured: true,
        replay_checksum: Some(u32::MAX),
        counters: Counters {
            samples_produced: u32::MAX,
            samples_dropped: u32::MAX,
            frames_ok: u32::MAX,
            frames_rejected: u32::MAX,
            lockstep_frames_lost: u32::MAX,
            commands_rejected: u32::MAX,
            faults_after_latch: u32::MAX,
            max_tick_cycles: u32::MAX,
            ticks_missed: u32::MAX,
            frames_dropped: u32::MAX,
        },
        reset_cause: crate::ResetCause::BrownOut,
        reset_acknowledged: false,
        drive_calibration: crate::DriveCalibration {
            zero_code: u16::MAX,
            codes_per_newton: f32::MAX,
        },
        bed: crate::bed::BedStatus {
            present: true,
            inputs: crate::bed::BedInputs {
                lift_up_limit: true,
                lift_down_limit: true,
                emergency_stop: true,
                height_raw: u16::MAX,
            },
            outputs: crate::bed::BedOutputs {
                blower_v: f32::MAX,
                shaker_duty: f32::MAX,
                lift_enable: true,
                lift_up: true,
            },
            tripped: true,
        },
        emergency_stop: crate::emergency_stop::EmergencyStopStatus {
            fitted: true,
            open: true,
            closed_since_reset: true,
        },
    };
    for msg in [
        full_batch(),
        RigMessage::Status(status),
        RigMessage::Reply {
            id: 9,
            result: Ok(Reply::Status(status)),
        },
        RigMessage::Reply {
            id: 9,
            result: Err(Rejection::Replay {
                actual_checksum: Some(1),
            }),
        },
        RigMessage::Fault(FaultReport {
            code: FaultCode::TrackingError,
            tick: 5,
        }),
    ] {
        let mut frame = encode_frame_vec(&msg).unwrap();
        let n = frame.len() - 1;
        assert_eq!(decode_frame::<RigMessage>(&mut frame[..n]), Ok(msg));
    }
}

#[test]
fn corrupted_truncated_and_foreign_frames_are_rejected_and_counted() {
    let msg = &sample_messages()[0];
    let good = encode_frame_vec(msg).unwrap();
    let mut dec = FrameDecoder::new();
    let mut feed = |bytes: &[u8]| -> heapless::Vec<Result<HostMessage, FrameError>, 8> {
        bytes
            .iter()
            .filter_map(|&b| dec.push::<HostMessage>(b))
            .collect()
    };
    // Flip one bit in the middle: CRC (or COBS) rejects it.
    let mut bad = good.clone();
    bad[10] ^= 0x10;
    if bad[10] == 0 {
        bad[10] = 1;
    }
    let r = feed(&bad);
    assert!(
        matches!(r.as_slice(), [Err(FrameError::Crc | FrameError::Cobs)]),
        "{r:?}"
    );
    // Truncated: the last 6 bytes lost, delimiter kept.
    let mut short: heapless::Vec<u8, MAX_FRAME> =
        heapless::Vec::from_slice(&good[..good.len() - 7]).unwrap();
    short.push(0).unwrap();
    assert!(matches!(feed(&short).as_slice(), [Err(_)]));
    // Another protocol version with a valid CRC.
    let mut body = [0u8; 16];
    body[0] = PROTOCOL_VERSION + 1;
    body[1] = 2; // Command::Arm-ish payload, irrelevant
    let crc = CRC32.checksum(&body[..2]);
    body[2..6].copy_from_slice(&crc.to_le_bytes());
    let mut enc = [0u8; 32];
    let n = cobs::try_encode(&body[..6], &mut enc).unwrap();
    assert_eq!(
        feed(&enc[..=n]).as_slice(),
        &[Err(FrameError::Version {
            got: PROTOCOL_VERSION + 1
        })]
    );
    // Too long: MAX_FRAME + 10 non-zero bytes, then a delimiter.
    let long = [0x55u8; MAX_FRAME + 10];
    assert!(feed(&long).is_empty());
    assert_eq!(feed(&[0]).as_slice(), &[Err(FrameError::TooLong)]);
    // And the decoder is back in sync for a good frame.
    assert_eq!(feed(&good).as_slice(), &[Ok(msg.clone())]);
    let s = dec.stats();
    assert_eq!((s.ok, s.rejected, s.too_long), (1, 4, 1));
}

proptest! {
    /// Random bytes never panic the decoder, and every reported frame is counted.
    #[test]
    fn random_garbage_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..4000)) {
        let mut dec = FrameDecoder::new();
        let mut results = 0u32;
        for b in bytes {
            if dec.push::<HostMessage>(b).is_some() {
                results += 1;
            }
        }
        let s = dec.stats();
        prop_assert_eq!(s.ok + s.rejected, results);
    }

    /// Garbage inside a well-formed COBS frame (valid framing, random body) is rejected, not
    /// misread: without the right CRC nothing decodes.
    #[test]
    fn random_bodies_fail_crc(body in proptest::collection::vec(any::<u8>(), 5..600)) {
        let mut enc = [0u8; MAX_FRAME];
        let n = cobs::try_encode(&body, &mut enc).unwrap();
        let crc_ok = CRC32.checksum(&body[..body.len() - 4]).to_le_bytes() == body[body.len() - 4..];
        let r = decode_frame::<RigMessage>(&mut enc[..n]);
        if !crc_ok {
            prop_assert_eq!(r, Err(FrameError::Crc));
        }
    }

    /// Arbitrary payloads behind a valid CRC reach the deserializer: they decode or are
    /// `Malformed`, never a panic; a message that decodes survives a round trip.
    #[test]
    fn random_payloads_with_valid_crc(payload in proptest::collection::vec(any::<u8>(), 0..300)) {
        let mut f = [0u8; MAX_FRAME];
        let n = encode_payload_frame(&payload, &mut f).unwrap();
        match decode_frame::<HostMessage>(&mut f[..n - 1]) {
            Ok(msg) => {
                let mut again = encode_frame_vec(&msg).unwrap();
                let m = again.len() - 1;
                let back = decode_frame::<HostMessage>(&mut again[..m]).unwrap();
                // Compare encodings (NaN payloads make `==` on the values unreliable).
                prop_assert_eq!(encode_frame_vec(&back).unwrap(), encode_frame_vec(&msg).unwrap());
            }
            Err(e) => prop_assert_eq!(e, FrameError::Malformed),
        }
    }

    /// Sensor frames round-trip bit-exactly.
    #[test]
    fn sensor_frames_round_trip(frame in any::<u32>(), count in any::<u32>(), cur in proptest::option::of(-100f32..100.0), overrun in any::<bool>()) {
        let msg = HostMessage::Sensor(SensorFrame { frame, encoder_count: count, current_a: cur, overrun, bed: None });
        let mut f = encode_frame_vec(&msg).unwrap();
        let n = f.len() - 1;
        prop_assert_eq!(decode_frame::<HostMessage>(&mut f[..n]), Ok(msg));
    }
}

/// `MAX_FRAME` is COBS's worst case for the largest body, delimiter included: a body of
/// `MAX_BODY` bytes with no zero encodes to one byte less. Found by `cargo mutants` (its
/// arithmetic changed passed every test).
#[test]
fn max_frame_is_coboss_worst_case_for_the_largest_body() {
    let body = [0x55u8; MAX_BODY];
    let mut enc = [0u8; MAX_FRAME + 16];
    let n = cobs::try_encode(&body, &mut enc).unwrap();
    assert_eq!(n + 1, MAX_FRAME, "encoded {n} bytes + the delimiter");
}

/// Each frame error says what it is, in its own words (the host counts and prints them).
#[test]
fn each_frame_error_has_its_own_message() {
    extern crate std;
    use std::string::{String, ToString};
    use std::vec::Vec;
    let all = [
        FrameError::BufferTooSmall,
        FrameError::Empty,
        FrameError::TooLong,
        FrameError::Cobs,
        FrameError::Truncated,
        FrameError::Crc,
        FrameError::Version { got: 9 },
        FrameError::Malformed,
    ];
    let texts: Vec<String> = all.iter().map(ToString::to_string).collect();
    let mut distinct = texts.clone();
    distinct.sort();
    distinct.dedup();
    assert_eq!(distinct.len(), all.len(), "{texts:?}");
    assert!(texts.iter().all(|t| t.len() > 8), "{texts:?}");
    assert!(texts[2].contains(&MAX_FRAME.to_string()), "{}", texts[2]);
    assert!(texts[6].contains('9'), "{}", texts[6]);
}

/// A frame whose CRC does not match is refused as such and counted under `crc` (the link's
/// health the host shows), not under `other`. Found by `cargo mutants` (the count's arm deleted
/// passed every test).
#[test]
fn a_crc_mismatch_is_counted_as_one() {
    let good = encode_frame_vec(&sample_messages()[0]).unwrap();
    let mut body = [0u8; MAX_BODY];
    let n = cobs::decode(&good[..good.len() - 1], &mut body)
        .unwrap()
        .frame_size();
    body[n - 1] ^= 0xFF; // the CRC's last byte
    let mut enc = [0u8; MAX_FRAME];
    let m = cobs::try_encode(&body[..n], &mut enc).unwrap();
    let mut dec = FrameDecoder::new();
    let got: heapless::Vec<Result<HostMessage, FrameError>, 2> = enc[..=m]
        .iter()
        .filter_map(|&b| dec.push::<HostMessage>(b))
        .collect();
    assert_eq!(got.as_slice(), &[Err(FrameError::Crc)]);
    let s = dec.stats();
    assert_eq!(
        (s.ok, s.rejected, s.crc, s.too_long, s.other),
        (0, 1, 1, 0, 0)
    );
}
