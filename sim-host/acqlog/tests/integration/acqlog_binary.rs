//! The binary form (frames as received) converts losslessly to the CSV form, and its
//! sequence numbers prove nothing was lost.

use proptest::prelude::*;
use sandjumper_acqlog::{
    AcqLog, AcqLogErrorKind, BinaryLogWriter, LogMetadata, ReadOptions, SampleLogBuilder,
    convert_binary, read_log,
};
use sandjumper_core::fault::FaultCode;
use sandjumper_core::protocol::{FaultReport, RigMessage, SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::sample::SampleRecord;

fn record(seq: u32, tick: u32) -> SampleRecord {
    let t = tick as f32 * 1e-4;
    SampleRecord {
        seq,
        tick,
        encoder_count: -18_750 + i64::from(seq) * 3 - 7 * i64::from(seq % 5),
        commanded_position_m: 0.01875 * (t * 62.8).cos(),
        force_n: 13.0 + 1.0e-3 * seq as f32 / 3.0,
        current_a: seq.is_multiple_of(2).then_some(0.1 + seq as f32 * 1e-5),
        camera_frame: tick.is_multiple_of(50).then_some(tick / 50),
        flags: (seq as u16) & 0x7ff,
    }
}

fn frames(records: &[SampleRecord]) -> Vec<u8> {
    let mut bytes = Vec::new();
    for batch in records.chunks(SAMPLE_BATCH) {
        let message = RigMessage::Samples(batch.iter().copied().collect());
        bytes.extend_from_slice(&encode_frame_vec(&message).unwrap());
    }
    bytes
}

fn binary_log(stream: &[u8], chunk: usize) -> Vec<u8> {
    let meta = LogMetadata::new(10_000.0, 1e6);
    let mut w = BinaryLogWriter::new(Vec::new(), &meta).unwrap();
    for piece in stream.chunks(chunk.max(1)) {
        w.write_received(piece).unwrap();
    }
    w.finish().unwrap()
}

fn assert_rows_are_the_records(log: &AcqLog, records: &[SampleRecord]) {
    assert_eq!(log.rows.len(), records.len());
    for (row, rec) in log.rows.iter().zip(records) {
        assert_eq!(row.tick, Some(u64::from(rec.tick)));
        assert_eq!(row.t_s, f64::from(rec.tick) / 10_000.0);
        assert_eq!(row.encoder_counts, rec.encoder_count);
        assert_eq!(
            row.p_cmd_m.map(|v| v as f32),
            Some(rec.commanded_position_m)
        );
        assert_eq!(row.force_cmd_n.map(|v| v as f32), Some(rec.force_n));
        assert_eq!(row.current_a.map(|v| v as f32), rec.current_a);
        assert_eq!(row.camera_frame, rec.camera_frame.map(u64::from));
        assert_eq!(row.flags, Some(u32::from(rec.flags)));
    }
}

proptest! {
    #[test]
    fn frames_convert_to_csv_and_back_without_loss(n in 1usize..300, start in 0u32..1_000_000, chunk in 1usize..700) {
        let records: Vec<SampleRecord> = (0..n as u32).map(|i| record(i + 5, start + i)).collect();
        let file = binary_log(&frames(&records), chunk);
        let (log, report) = convert_binary(file.as_slice(), false, 1_000_000).unwrap();
        prop_assert_eq!(report.samples, n as u64);
        prop_assert_eq!(report.frames_rejected, 0);
        assert_rows_are_the_records(&log, &records);
        let csv = log.write_csv(Vec::new()).unwrap();
        let back = read_log(csv.as_slice(), &ReadOptions::default()).unwrap();
        assert_rows_are_the_records(&back, &records);
        prop_assert_eq!(back, log);
    }

    #[test]
    fn arbitrary_bytes_after_the_header_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let _ = convert_binary(binary_log(&bytes, 64).as_slice(), true, 10_000);
        let _ = convert_binary(bytes.as_slice(), true, 10_000);
    }
}

#[test]
fn lost_samples_are_refused_or_counted_and_other_messages_reported() {
    let mut records: Vec<SampleRecord> = (0..40).map(|i| record(i, 100 + i)).collect();
    records.drain(20..23); // three records lost in transit
    let mut stream = frames(&records);
    let mut corrupt = encode_frame_vec(&RigMessage::Fault(FaultReport {
        code: FaultCode::TrackingError,
        tick: 7,
    }))
    .unwrap()
    .to_vec();
    stream.extend_from_slice(&corrupt);
    corrupt[2] ^= 0x40; // a frame damaged on the line
    stream.extend_from_slice(&corrupt);
    let file = binary_log(&stream, 33);
    let err = convert_binary(file.as_slice(), false, 1000).unwrap_err();
    assert_eq!(err.kind, AcqLogErrorKind::Binary);
    assert!(
        err.message
            .contains("sequence jumps from 19 to 23: 3 sample(s) lost"),
        "{err}"
    );
    let (log, report) = convert_binary(file.as_slice(), true, 1000).unwrap();
    assert_eq!(report.samples_lost, 3);
    assert_eq!(log.meta.dropped_samples, 3);
    assert_eq!(report.frames_rejected, 1);
    assert_eq!(report.faults, vec![(2, FaultCode::TrackingError.name(), 7)]);
    // The CSV shows the gap in its tick column; reading it needs --allow-gaps too.
    let csv = log.write_csv(Vec::new()).unwrap();
    let err = read_log(csv.as_slice(), &ReadOptions::default()).unwrap_err();
    assert_eq!(err.kind, AcqLogErrorKind::Gap);
}

#[test]
fn the_builder_gives_the_same_log_as_the_conversion() {
    let records: Vec<SampleRecord> = (0..50)
        .map(|i| record(i, (u32::MAX - 20).wrapping_add(i)))
        .collect();
    let mut builder = SampleLogBuilder::new(LogMetadata::new(10_000.0, 1e6));
    for r in &records {
        builder.push(r).unwrap();
    }
    let built = builder.finish();
    let (converted, _) =
        convert_binary(binary_log(&frames(&records), 100).as_slice(), false, 1000).unwrap();
    assert_eq!(built, converted);
    // The tick is extended across the u32 wrap.
    assert_eq!(built.rows[49].tick, Some(u64::from(u32::MAX) - 20 + 49));
    let mut backwards = SampleLogBuilder::new(LogMetadata::new(10_000.0, 1e6));
    backwards.push(&record(5, 10)).unwrap();
    let err = backwards.push(&record(4, 11)).unwrap_err();
    assert!(err.message.contains("goes backwards"), "{err}");
}

#[test]
fn bad_containers_are_refused_with_the_reason() {
    let good = binary_log(&frames(&[record(0, 0)]), 8);
    let check = |bytes: &[u8], words: &str| {
        let err = convert_binary(bytes, false, 100).unwrap_err();
        assert!(
            err.to_string().contains(words),
            "`{err}` should say `{words}`"
        );
    };
    check(b"", "does not start with `SJACQBIN`");
    check(b"# rate_hz: 1\n", "does not start with `SJACQBIN`");
    check(&good[..11], "inside its 14-byte header");
    let mut v = good.clone();
    v[8] = 9;
    check(&v, "container version 9");
    let mut v = good.clone();
    v[9] = 77;
    check(&v, "protocol version 77");
    let mut v = good.clone();
    v[10..14].copy_from_slice(&u32::MAX.to_le_bytes());
    check(&v, "over the 65536-byte limit");
    check(&good[..20], "ends inside its metadata block");
    let header_only = binary_log(&[], 1);
    check(&header_only, "no sample records");
}
