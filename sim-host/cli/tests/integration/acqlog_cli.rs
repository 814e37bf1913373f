//! `sandjumper log convert` and `sandjumper log check` on files: a binary log converts to the
//! same CSV the library produces, refuses to overwrite, and a loss in sequence numbers is an
//! error (exit 2) unless --allow-gaps.

use sandjumper_acqlog::{AcqLog, BinaryLogWriter, LogMetadata, ReadOptions};
use sandjumper_core::protocol::{RigMessage, SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::sample::SampleRecord;

use crate::common;
use common::sandjumper;

fn records(skip: Option<u32>) -> Vec<SampleRecord> {
    (0..100u32)
        .filter(|i| Some(*i) != skip)
        .map(|i| SampleRecord {
            seq: i,
            tick: 1000 + i,
            encoder_count: -18_750 + i64::from(i * i),
            commanded_position_m: -0.01875 + i as f32 * 1e-5,
            force_n: 11.0 + i as f32 * 0.25,
            current_a: None,
            camera_frame: i.is_multiple_of(50).then_some(i / 50),
            flags: 0x5,
        })
        .collect()
}

fn write_binary(path: &std::path::Path, records: &[SampleRecord]) {
    let mut meta = LogMetadata::new(10_000.0, 1e6);
    meta.phi = Some(0.6);
    let mut w = BinaryLogWriter::new(Vec::new(), &meta).unwrap();
    for batch in records.chunks(SAMPLE_BATCH) {
        let message = RigMessage::Samples(batch.iter().copied().collect());
        w.write_received(&encode_frame_vec(&message).unwrap())
            .unwrap();
    }
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

#[test]
fn convert_then_check_and_refusals() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("run.bin");
    let csv = tmp.path().join("run.csv");
    write_binary(&bin, &records(None));
    let (b, c) = (bin.to_str().unwrap(), csv.to_str().unwrap());
    let out = sandjumper(&["log", "convert", b, c]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let log = AcqLog::read_file(&csv, &ReadOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 100);
    assert_eq!(log.rows[99].encoder_counts, -18_750 + 99 * 99);
    assert_eq!(log.meta.phi, Some(0.6));
    // Both forms pass `log check`, with the same sample count.
    for f in [b, c] {
        let out = sandjumper(&["log", "check", f, "--json"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["samples"], 100);
        assert_eq!(v["camera_frames"], 2);
    }
    // No silent overwrite; a CSV is not converted.
    let again = sandjumper(&["log", "convert", b, c]);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    let csv_in = sandjumper(&[
        "log",
        "convert",
        c,
        tmp.path().join("x.csv").to_str().unwrap(),
    ]);
    assert_eq!(csv_in.status.code(), Some(2));
    // One record lost in transit: refused, or converted with the loss counted.
    write_binary(&bin, &records(Some(40)));
    let lossy = sandjumper(&["log", "convert", b, c, "--force"]);
    assert_eq!(lossy.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&lossy.stderr).contains("sequence jumps from 39 to 41"),
        "{}",
        String::from_utf8_lossy(&lossy.stderr)
    );
    let allowed = sandjumper(&["log", "convert", b, c, "--force", "--allow-gaps"]);
    assert!(allowed.status.success());
    let log = AcqLog::read_file(
        &csv,
        &ReadOptions {
            allow_gaps: true,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(log.meta.dropped_samples, 1);
    assert_eq!(log.interpolated_samples(), 1);
}
