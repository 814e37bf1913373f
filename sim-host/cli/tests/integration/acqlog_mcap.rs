//! Acquisition logs as MCAP (`sandjumper log convert IN OUT.mcap`, `hil --out DIR --mcap`):
//! read back with the mcap crate's own reader, every value equals the CSV's; a file cut at any
//! byte still yields every message that was complete before the cut; bad input is refused with
//! `log check`'s message and exit 2.

use std::collections::BTreeMap;

use sandjumper_acqlog::mcap_file::FLAG_NAMES;
use sandjumper_acqlog::{
    AcqLog, BinaryLogWriter, Column, LogMetadata, LogRow, ReadOptions, read_messages,
};
use sandjumper_core::fault::FaultCode;
use sandjumper_core::protocol::{FaultReport, RigMessage, SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::sample::{SampleRecord, flags};
use serde_json::Value;

use crate::common;
use common::{ok, sandjumper};

/// A 3 s log at 10 kHz with every column, empty cells, camera frames every 50 ticks with a
/// rod height on some, and a fault that latches and clears.
fn rich_log() -> AcqLog {
    let mut meta = LogMetadata::new(10_000.0, 1e6);
    meta.phi = Some(0.6);
    meta.encoder_sign = -1;
    meta.position_offset_m = 0.002;
    meta.extra.push(("operator".into(), "a: b".into()));
    let mut log = AcqLog::new(
        meta,
        &[
            Column::PCmdM,
            Column::ForceCmdN,
            Column::CurrentA,
            Column::CameraFrame,
            Column::Flags,
            Column::RodHeightM,
        ],
    );
    for i in 0..30_000u64 {
        let tick = 5_000 + i;
        let mut row = LogRow::new(tick, tick as f64 / 10_000.0, -18_750 + (i * 7 % 991) as i64);
        row.p_cmd_m = Some(-0.01875 + i as f64 * 1.3e-7);
        row.force_cmd_n = (i % 97 != 0).then_some(11.0 + (i as f64 * 0.37).sin());
        row.current_a = (i % 3 == 0).then_some(0.1 * i as f64 / 7.0);
        row.camera_frame = (i % 50 == 0).then_some(i / 50);
        row.rod_height_m = (i % 150 == 0).then_some(1e-5 * i as f64);
        let mut f = u32::from(flags::DRIVE_ENABLED | flags::RUNNING);
        if (12_000..15_000).contains(&i) {
            f |= u32::from(flags::FAULTED);
        }
        if i % 4 == 0 {
            f |= u32::from(flags::CAMERA_HIGH);
        }
        row.flags = Some(f);
        log.rows.push(row);
    }
    log
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

/// Messages of a whole file through the crate's standard reader, grouped by topic, in order.
fn by_topic(bytes: &[u8]) -> BTreeMap<String, Vec<(u64, Value)>> {
    let mut out: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(bytes).expect("a valid MCAP file") {
        let m = m.expect("every message reads");
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let v: Value = serde_json::from_slice(&m.data).expect("JSON message");
        out.entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, v));
    }
    out
}

#[test]
fn csv_to_mcap_every_value_equals_the_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("run.csv");
    let mcap_path = tmp.path().join("run.mcap");
    rich_log().write_file(&csv).unwrap();
    ok(&[
        "log",
        "convert",
        csv.to_str().unwrap(),
        mcap_path.to_str().unwrap(),
    ]);
    let log = AcqLog::read_file(&csv, &ReadOptions::default()).unwrap();
    let bytes = std::fs::read(&mcap_path).unwrap();
    let topics = by_topic(&bytes);

    // Encoder, drive, status: one message per tick, timestamps from the tick.
    for topic in ["/encoder", "/drive", "/status"] {
        assert_eq!(topics[topic].len(), log.rows.len(), "{topic}");
    }
    for (i, row) in log.rows.iter().enumerate() {
        let tick = row.tick.unwrap();
        let t_ns = tick * 100_000;
        let (time, e) = &topics["/encoder"][i];
        assert_eq!(*time, t_ns);
        assert_eq!(e["tick"], tick);
        assert_eq!(num(&e["t_s"]), Some(row.t_s));
        assert_eq!(e["encoder_counts"], row.encoder_counts);
        assert_eq!(
            num(&e["position_m"]),
            Some(log.meta.position_m(row.encoder_counts))
        );
        assert_eq!(num(&e["p_cmd_m"]), row.p_cmd_m);
        let (time, d) = &topics["/drive"][i];
        assert_eq!(*time, t_ns);
        assert_eq!(num(&d["force_cmd_n"]), row.force_cmd_n);
        assert_eq!(num(&d["current_a"]), row.current_a);
        assert_eq!(d["force_cmd_n"].is_null(), row.force_cmd_n.is_none());
        let (_, s) = &topics["/status"][i];
        let word = row.flags.unwrap();
        assert_eq!(s["flags"], word);
        for (bit, name) in FLAG_NAMES {
            assert_eq!(s[name], word & u32::from(bit) != 0, "{name} at tick {tick}");
        }
    }
    // Camera: exactly the rows with a frame or a height.
    let camera_rows: Vec<&LogRow> = log
        .rows
        .iter()
        .filter(|r| r.camera_frame.is_some() || r.rod_height_m.is_some())
        .collect();
    assert_eq!(topics["/camera"].len(), camera_rows.len());
    assert_eq!(camera_rows.len(), 600);
    for ((time, c), row) in topics["/camera"].iter().zip(&camera_rows) {
        assert_eq!(*time, row.tick.unwrap() * 100_000);
        assert_eq!(c["frame"].as_u64(), row.camera_frame);
        assert_eq!(num(&c["rod_height_m"]), row.rod_height_m);
    }
    // Faults: latched at 12 000, cleared at 15 000 (rows counted from 0).
    let faults: Vec<(u64, &str)> = topics["/faults"]
        .iter()
        .map(|(_, f)| (f["tick"].as_u64().unwrap(), f["event"].as_str().unwrap()))
        .collect();
    assert_eq!(faults, [(17_000, "latched"), (20_000, "cleared")]);

    // The metadata record holds the CSV's `# key: value` lines, verbatim.
    let back = read_messages(&bytes);
    assert!(back.complete, "{:?}", back.stopped);
    let text = std::fs::read_to_string(&csv).unwrap();
    let csv_meta: BTreeMap<String, String> = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .filter_map(|l| l.strip_prefix("# ")?.split_once(": "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    assert_eq!(back.metadata["sandjumper-acqlog"], csv_meta);
    assert_eq!(csv_meta["operator"], "a: b");
    assert_eq!(back.metadata["sandjumper-conversion"]["source_form"], "csv");
    assert_eq!(back.metadata["sandjumper-conversion"]["rows"], "30000");

    // Chunked and indexed: several chunks, each with message indexes; statistics agree.
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a summary section");
    assert!(
        summary.chunk_indexes.len() > 10,
        "{} chunks",
        summary.chunk_indexes.len()
    );
    // Compressed with zstd by default, as Foxglove's writer does.
    let (packed, plain): (u64, u64) = summary
        .chunk_indexes
        .iter()
        .map(|c| (c.compressed_size, c.uncompressed_size))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    assert!(4 * packed < plain, "{packed} compressed of {plain} bytes");
    for chunk in &summary.chunk_indexes {
        assert_eq!(chunk.compression, "zstd");
        let indexes = summary.read_message_indexes(&bytes, chunk).unwrap();
        assert!(!indexes.is_empty());
    }
    let stats = summary.stats.as_ref().expect("statistics");
    let total: usize = topics.values().map(Vec::len).sum();
    assert_eq!(stats.message_count, total as u64);
    assert_eq!(stats.channel_count, 5);
    assert_eq!(stats.metadata_count, 2);
    assert_eq!(summary.metadata_indexes.len(), 2);
    assert_eq!(stats.message_start_time, 5_000 * 100_000);
}

/// Where each message's record ends in an uncompressed file, found without the MCAP reader:
/// each JSON payload is unique and the writer writes them in order, so a forward search for
/// its bytes finds it.
fn payload_ends(bytes: &[u8], payloads: &[Vec<u8>]) -> Vec<usize> {
    let mut from = 0;
    payloads
        .iter()
        .map(|p| {
            let at = bytes[from..]
                .windows(p.len())
                .position(|w| w == p.as_slice())
                .expect("every payload is in the file")
                + from;
            from = at + p.len();
            from
        })
        .collect()
}

#[test]
fn a_cut_file_yields_every_message_complete_before_the_cut() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("run.mcap");
    let mut log = rich_log();
    log.rows.truncate(6_000);
    // Plain chunks: their messages are records of their own, readable up to any cut.
    log.write_mcap_file_compressed(&path, None, sandjumper_acqlog::McapCompression::None)
        .unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let whole = read_messages(&bytes);
    assert!(whole.complete);
    let payloads: Vec<Vec<u8>> = whole.messages.iter().map(|m| m.data.clone()).collect();
    let ends = payload_ends(&bytes, &payloads);
    // Cuts at pseudo-random bytes, plus the edges of the first record and the last message.
    let mut cuts = vec![0, 1, 8, 9, bytes.len() - 1, ends[ends.len() - 1]];
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    for _ in 0..60 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        cuts.push((x % bytes.len() as u64) as usize);
    }
    for cut in cuts {
        let got = read_messages(&bytes[..cut]);
        let expected = ends.iter().filter(|e| **e <= cut).count();
        assert_eq!(
            got.messages.len(),
            expected,
            "cut at byte {cut} of {}: stopped by {:?}",
            bytes.len(),
            got.stopped
        );
        assert_eq!(got.messages[..], whole.messages[..expected]);
        assert!(cut == bytes.len() || !got.complete);
        assert!(got.stopped.is_some() || got.complete);
    }
}

fn write_binary(path: &std::path::Path) {
    let records: Vec<SampleRecord> = (0..400u32)
        .map(|i| SampleRecord {
            seq: i,
            tick: 1000 + i,
            encoder_count: -18_750 + i64::from(i * i),
            commanded_position_m: -0.01875 + i as f32 * 1e-5,
            force_n: if i >= 300 {
                0.0
            } else {
                11.0 + i as f32 * 0.25
            },
            current_a: None,
            camera_frame: i.is_multiple_of(50).then_some(i / 50),
            flags: if i >= 300 {
                flags::FAULTED
            } else {
                flags::RUNNING
            },
        })
        .collect();
    let mut w = BinaryLogWriter::new(Vec::new(), &LogMetadata::new(10_000.0, 1e6)).unwrap();
    for batch in records.chunks(SAMPLE_BATCH) {
        let message = RigMessage::Samples(batch.iter().copied().collect());
        w.write_received(&encode_frame_vec(&message).unwrap())
            .unwrap();
    }
    let fault = RigMessage::Fault(FaultReport {
        code: FaultCode::TrackingError,
        tick: 1300,
    });
    w.write_received(&encode_frame_vec(&fault).unwrap())
        .unwrap();
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

#[test]
fn binary_to_mcap_carries_the_rigs_fault_reports() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("run.bin");
    let csv = tmp.path().join("run.csv");
    let out = tmp.path().join("run.mcap");
    write_binary(&bin);
    let (b, c, o) = (
        bin.to_str().unwrap(),
        csv.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    ok(&["log", "convert", b, c]);
    ok(&["log", "convert", b, o]);
    let log = AcqLog::read_file(&csv, &ReadOptions::default()).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let topics = by_topic(&bytes);
    assert_eq!(topics["/encoder"].len(), log.rows.len());
    for ((_, e), row) in topics["/encoder"].iter().zip(&log.rows) {
        assert_eq!(e["encoder_counts"], row.encoder_counts);
        assert_eq!(num(&e["p_cmd_m"]), row.p_cmd_m);
    }
    let faults: Vec<(u64, &str, Option<u64>)> = topics["/faults"]
        .iter()
        .map(|(_, f)| {
            (
                f["tick"].as_u64().unwrap(),
                f["event"].as_str().unwrap(),
                f["code"].as_u64(),
            )
        })
        .collect();
    assert_eq!(
        faults,
        [
            (
                1300,
                "reported",
                Some(u64::from(FaultCode::TrackingError.code()))
            ),
            (1300, "latched", None)
        ]
    );
    let back = read_messages(&bytes);
    assert_eq!(
        back.metadata["sandjumper-conversion"]["source_form"],
        "binary"
    );
    assert_eq!(
        back.metadata["sandjumper-conversion"]["frames_rejected"],
        "0"
    );
}

#[test]
fn hil_writes_the_mcap_beside_the_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    ok(&[
        "hil",
        "--kind",
        "stutter",
        "--freq",
        "12",
        "--out",
        dir.to_str().unwrap(),
        "--mcap",
    ]);
    let log = AcqLog::read_file(&dir.join("acquisition.csv"), &ReadOptions::default()).unwrap();
    let topics = by_topic(&std::fs::read(dir.join("acquisition.mcap")).unwrap());
    assert_eq!(topics["/encoder"].len(), log.rows.len());
    for ((_, e), row) in topics["/encoder"].iter().zip(&log.rows) {
        assert_eq!(e["encoder_counts"], row.encoder_counts);
        assert_eq!(num(&e["t_s"]), Some(row.t_s));
    }
    let frames = log.rows.iter().filter(|r| r.camera_frame.is_some()).count();
    assert!(frames > 0);
    let camera_frames = topics["/camera"]
        .iter()
        .filter(|(_, c)| !c["frame"].is_null())
        .count();
    assert_eq!(camera_frames, frames);
    // --mcap needs --out.
    let no_out = sandjumper(&["hil", "--kind", "single", "--freq", "10", "--mcap"]);
    assert_eq!(no_out.status.code(), Some(2));
}

#[test]
fn bad_input_is_refused_with_the_csv_readers_message() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = tmp.path().join("bad.csv");
    std::fs::write(
        &bad,
        "# rate_hz: 1000\n# counts_per_m: 1e6\nt_s,encoder_counts\n0,1\n0.001,2\n0.001,3\n",
    )
    .unwrap();
    let out = tmp.path().join("bad.mcap");
    let (b, o) = (bad.to_str().unwrap(), out.to_str().unwrap());
    let check = sandjumper(&["log", "check", b]);
    let convert = sandjumper(&["log", "convert", b, o]);
    assert_eq!(check.status.code(), Some(2));
    assert_eq!(convert.status.code(), Some(2));
    let (check_err, convert_err) = (
        String::from_utf8_lossy(&check.stderr),
        String::from_utf8_lossy(&convert.stderr),
    );
    assert!(check_err.contains("line 6"), "{check_err}");
    assert_eq!(check_err, convert_err);
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
    // An existing output is not overwritten without --force; --to csv from a CSV is refused.
    let good = tmp.path().join("good.csv");
    rich_log().write_file(&good).unwrap();
    let g = good.to_str().unwrap();
    std::fs::write(&out, b"keep").unwrap();
    let exists = sandjumper(&["log", "convert", g, o]);
    assert_eq!(exists.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&exists.stderr).contains("--force"));
    assert_eq!(std::fs::read(&out).unwrap(), b"keep");
    ok(&["log", "convert", g, o, "--force"]);
    assert!(read_messages(&std::fs::read(&out).unwrap()).complete);
    let to_csv = sandjumper(&["log", "convert", g, o, "--force", "--to", "csv"]);
    assert_eq!(to_csv.status.code(), Some(2));
    let wrong_form = sandjumper(&["log", "convert", g, o, "--to", "parquet"]);
    assert_eq!(wrong_form.status.code(), Some(2));
}
