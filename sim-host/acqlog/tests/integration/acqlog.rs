//! The acquisition log format: lossless round trip, and a clear, line-numbered refusal for
//! every kind of bad input (never a panic).

use proptest::prelude::*;
use sandjumper_acqlog::{
    AcqLog, AcqLogErrorKind as Kind, Column, JumpConfig, LogMetadata, LogRow, ReadOptions, read_log,
};

fn read(text: &str) -> Result<AcqLog, sandjumper_acqlog::AcqLogError> {
    read_log(text.as_bytes(), &ReadOptions::default())
}

fn refused(text: &str, kind: Kind, line: Option<u64>, words: &str) {
    let err = read(text).expect_err("the log must be refused");
    assert_eq!(err.kind, kind, "{err}");
    assert_eq!(err.line, line, "{err}");
    assert!(
        err.to_string().contains(words),
        "message `{err}` should mention `{words}`"
    );
}

const HEAD: &str = "# rate_hz: 1000\n# counts_per_m: 1e6\n";

fn full_log() -> AcqLog {
    let mut meta = LogMetadata::new(10_000.0, 1.0e6);
    meta.firmware = Some("sandjumper-firmware 0.1.0".into());
    meta.source = Some("test".into());
    meta.jump = Some(JumpConfig {
        kind: "delayed-stutter".into(),
        amplitude_m: Some(0.01875),
        freq_hz: Some(12.0),
        tau_s: Some(0.75),
    });
    meta.phi = Some(0.57);
    meta.dropped_samples = 3;
    meta.measured_jump_height_m = Some(0.0123);
    meta.extra.push(("gain_lowering".into(), "4".into()));
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
    for i in 0..500u64 {
        let t = i as f64 * 1e-4;
        let mut row = LogRow::new(i, t, (18_750.0 * (t * 60.0).cos()).round() as i64);
        row.p_cmd_m = Some(0.01875 * (t * 60.0).cos());
        row.force_cmd_n = Some(13.0 + t * 7.1);
        row.current_a = (i % 3 != 0).then_some(0.1 * t);
        if i % 50 == 0 {
            row.camera_frame = Some(i / 50);
            row.rod_height_m = Some(1e-3 * t);
        }
        row.flags = Some(if i > 400 { 0x11 } else { 0 });
        log.rows.push(row);
    }
    log
}

#[test]
fn write_then_read_gives_back_the_same_log() {
    let log = full_log();
    let bytes = log.write_csv(Vec::new()).unwrap();
    let back = read_log(bytes.as_slice(), &ReadOptions::default()).unwrap();
    assert_eq!(back, log);
    let summary = back.summary();
    assert_eq!(summary.camera_frames, 10);
    assert_eq!(summary.camera_frames_missing, 0);
    assert_eq!(summary.flagged_samples, 99);
    assert_eq!(summary.dropped_samples, 3);
}

proptest! {
    #[test]
    fn any_valid_log_round_trips_exactly(
        counts in prop::collection::vec(-1_000_000i64..1_000_000, 2..200),
        rate_hz in 100.0f64..50_000.0,
        start in -10.0f64..10.0,
        p_cmd in prop::collection::vec(prop::option::of(-0.025f64..0.025), 200),
    ) {
        let mut log = AcqLog::new(LogMetadata::new(rate_hz, 1e6), &[Column::PCmdM]);
        for (i, c) in counts.iter().enumerate() {
            let mut row = LogRow::new(i as u64 + 7, start + i as f64 / rate_hz, *c);
            row.p_cmd_m = p_cmd[i];
            log.rows.push(row);
        }
        let bytes = log.write_csv(Vec::new()).unwrap();
        let back = read_log(bytes.as_slice(), &ReadOptions::default()).unwrap();
        prop_assert_eq!(back, log);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let mut text = HEAD.as_bytes().to_vec();
        text.extend_from_slice(b"t_s,encoder_counts\n");
        text.extend_from_slice(&bytes);
        let _ = read_log(text.as_slice(), &ReadOptions::default());
        let _ = read_log(bytes.as_slice(), &ReadOptions::default());
    }
}

#[test]
fn the_third_party_minimum_is_enough() {
    let log = read(&format!(
        "{HEAD}t_s,encoder_counts\n0.5,10\n0.501,12\n0.502,15\n"
    ))
    .unwrap();
    assert_eq!(log.rows.len(), 3);
    assert_eq!(log.rows[2].tick, None);
    assert!((log.positions_m()[2] - 15e-6).abs() < 1e-15);
    assert_eq!(log.meta.encoder_sign, 1);
}

#[test]
fn sign_offset_comments_crlf_bom_and_extra_columns_are_understood() {
    let text = "\u{feff}## exported by LabX\r\n# rate_hz: 1000\r\n# counts_per_m: 2000\r\n# encoder_sign: -1\r\n# position_offset_m: 0.01\r\n#\r\nx_volts, t_s ,encoder_counts\r\n1.5,0,100\r\n1.6,0.001,200\r\n\r\n";
    let log = read(text).unwrap();
    let p = log.positions_m();
    assert!((p[0] - (0.01 - 0.05)).abs() < 1e-12);
    assert!((p[1] - (0.01 - 0.1)).abs() < 1e-12);
}

#[test]
fn empty_and_header_only_files_are_refused() {
    refused("", Kind::Empty, None, "empty file");
    refused("\n  \n", Kind::Empty, None, "empty file");
    refused(HEAD, Kind::MissingHeader, Some(2), "header");
    refused(
        &format!("{HEAD}t_s,encoder_counts\n"),
        Kind::NoSamples,
        Some(3),
        "no sample rows",
    );
}

#[test]
fn missing_or_malformed_metadata_is_refused() {
    refused(
        "# counts_per_m: 1e6\nt_s,encoder_counts\n0,0\n",
        Kind::MissingMetadata,
        Some(2),
        "rate_hz",
    );
    refused(
        "# rate: 1000\n# counts_per_m: 1e6\nt_s,encoder_counts\n0,0\n",
        Kind::MissingMetadata,
        Some(3),
        "line 1 has `rate`",
    );
    refused(
        "# rate_hz: 1000\nt_s,encoder_counts\n0,0\n",
        Kind::MissingMetadata,
        Some(2),
        "counts_per_m",
    );
    refused(
        "# rate_hz = 1000\n",
        Kind::MalformedMetadata,
        Some(1),
        "`=` used where `:`",
    );
    refused(
        "# rate_hz: fast\n# counts_per_m: 1\nt_s,encoder_counts\n0,0\n",
        Kind::BadMetadataValue,
        Some(1),
        "not a finite number",
    );
    refused(
        "# rate_hz: -5\n# counts_per_m: 1\nt_s,encoder_counts\n0,0\n",
        Kind::BadMetadataValue,
        Some(1),
        "rate_hz = -5",
    );
    refused(
        "# rate_hz: 1000\n# counts_per_m: 0\nt_s,encoder_counts\n0,0\n",
        Kind::BadMetadataValue,
        Some(2),
        "counts_per_m = 0",
    );
    refused(
        &format!("{HEAD}# rate_hz: 10\nt_s,encoder_counts\n0,0\n"),
        Kind::MalformedMetadata,
        Some(3),
        "given twice (first on line 1)",
    );
    refused(
        &format!("# format: sandjumper-acqlog 2\n{HEAD}t_s,encoder_counts\n0,0\n"),
        Kind::UnsupportedFormat,
        Some(1),
        "sandjumper-acqlog 1",
    );
    refused(
        &format!("{HEAD}# encoder_sign: up\nt_s,encoder_counts\n0,0\n"),
        Kind::BadMetadataValue,
        Some(3),
        "encoder_sign",
    );
    refused(
        &format!("{HEAD}# firmware: a\rb\nt_s,encoder_counts\n0,0\n"),
        Kind::MalformedMetadata,
        Some(3),
        "control character U+000D",
    );
    refused(
        &format!("{HEAD}t_s,encoder_counts\n0,0\n# late: 1\n"),
        Kind::MalformedMetadata,
        Some(5),
        "after the header",
    );
}

#[test]
fn missing_misnamed_and_duplicated_columns_are_refused() {
    refused(
        &format!("{HEAD}t_s,encoder_count\n0,0\n"),
        Kind::UnknownColumn,
        Some(3),
        "unknown column `encoder_count`",
    );
    refused(
        &format!("{HEAD}tick,encoder_counts\n0,0\n"),
        Kind::MissingColumn,
        Some(3),
        "`t_s` missing",
    );
    refused(
        &format!("{HEAD}t_s,encoder_counts,t_s\n0,0,0\n"),
        Kind::DuplicateColumn,
        Some(3),
        "twice",
    );
}

#[test]
fn bad_fields_are_refused_with_their_line_and_column() {
    let h = format!("{HEAD}tick,t_s,encoder_counts,p_cmd_m,flags\n0,0,0,0,0\n");
    refused(
        &format!("{h}1,0.001,abc,0,0\n"),
        Kind::NotANumber,
        Some(5),
        "`encoder_counts`: `abc`",
    );
    refused(
        &format!("{h}1,0.001,1.5,0,0\n"),
        Kind::NotANumber,
        Some(5),
        "whole number",
    );
    refused(
        &format!("{h}1,NaN,1,0,0\n"),
        Kind::NotFinite,
        Some(5),
        "`t_s` is NaN",
    );
    refused(
        &format!("{h}1,0.001,1,inf,0\n"),
        Kind::NotFinite,
        Some(5),
        "`p_cmd_m`",
    );
    refused(
        &format!("{h}1,0.001,1,0\n"),
        Kind::FieldCount,
        Some(5),
        "4 fields",
    );
    refused(
        &format!("{h}1,,1,0,0\n"),
        Kind::EmptyField,
        Some(5),
        "`t_s` is empty",
    );
    refused(
        &format!("{h}1,0.001,1,0,0xZZ\n"),
        Kind::NotANumber,
        Some(5),
        "`flags`",
    );
    refused(
        &format!("{h}-1,0.001,1,0,0\n"),
        Kind::NotANumber,
        Some(5),
        "`tick`",
    );
    // Empty optional cells are fine.
    assert!(read(&format!("{h}1,0.001,1,,\n")).is_ok());
}

#[test]
fn time_must_increase_on_the_declared_rate() {
    let h = format!("{HEAD}t_s,encoder_counts\n0,0\n0.001,0\n");
    refused(
        &format!("{h}0.001,0\n"),
        Kind::DuplicateTime,
        Some(6),
        "repeats",
    );
    refused(
        &format!("{h}0.0005,0\n"),
        Kind::NonMonotonicTime,
        Some(6),
        "earlier",
    );
    refused(
        &format!("{h}0.0011,0\n"),
        Kind::RateMismatch,
        Some(6),
        "rate_hz = 1000 disagrees",
    );
    refused(
        &format!("{h}0.0025,0\n"),
        Kind::IrregularInterval,
        Some(6),
        "1.500 sampling periods",
    );
    // Every interval 0.8 % long: each is within tolerance but the mean rate is not.
    let mut drift = String::from(HEAD);
    drift.push_str("t_s,encoder_counts\n");
    for i in 0..100 {
        drift.push_str(&format!("{},0\n", i as f64 * 0.00102));
    }
    refused(&drift, Kind::RateMismatch, None, "mean rate is 980.392");
    // Ticks must follow time.
    refused(
        &format!("{HEAD}tick,t_s,encoder_counts\n0,0,0\n2,0.001,0\n"),
        Kind::TickMismatch,
        Some(5),
        "tick 2 after tick 0",
    );
}

#[test]
fn gaps_are_refused_unless_allowed_then_interpolated_and_reported() {
    let text =
        format!("{HEAD}tick,t_s,encoder_counts\n0,0,0\n1,0.001,10\n5,0.005,50\n6,0.006,60\n");
    refused(
        &text,
        Kind::Gap,
        Some(6),
        "3 sample(s) missing between t_s = 0.001 and t_s = 0.005",
    );
    let opts = ReadOptions {
        allow_gaps: true,
        ..ReadOptions::default()
    };
    let log = read_log(text.as_bytes(), &opts).unwrap();
    assert_eq!(log.rows.len(), 7);
    assert_eq!(log.interpolated_samples(), 3);
    assert_eq!(log.gaps.len(), 1);
    let counts: Vec<i64> = log.rows.iter().map(|r| r.encoder_counts).collect();
    assert_eq!(counts, [0, 10, 20, 30, 40, 50, 60]);
    let ticks: Vec<u64> = log.rows.iter().map(|r| r.tick.unwrap()).collect();
    assert_eq!(ticks, [0, 1, 2, 3, 4, 5, 6]);
    assert_eq!(log.summary().interpolated_samples, 3);
}

#[test]
fn huge_inputs_hit_the_caps_with_a_message() {
    let opts = ReadOptions {
        max_rows: 100,
        ..ReadOptions::default()
    };
    let mut text = format!("{HEAD}t_s,encoder_counts\n");
    for i in 0..200 {
        text.push_str(&format!("{},0\n", i as f64 / 1000.0));
    }
    let err = read_log(text.as_bytes(), &opts).unwrap_err();
    assert_eq!(err.kind, Kind::TooManyRows);
    assert_eq!(err.line, Some(104));
    // A gap so large it would exceed the cap is refused before allocating it.
    let gap = format!("{HEAD}t_s,encoder_counts\n0,0\n1e9,0\n");
    let err = read_log(
        gap.as_bytes(),
        &ReadOptions {
            allow_gaps: true,
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(err.kind, Kind::TooManyRows);
    // One endless line is cut at the line cap.
    let long = format!("{HEAD}t_s,encoder_counts\n{}", "1".repeat(1 << 20));
    let err = read(&long).unwrap_err();
    assert_eq!(err.kind, Kind::LineTooLong);
    assert_eq!(err.line, Some(4));
    let bad_utf8 = [HEAD.as_bytes(), b"t_s,encoder_counts\n0,\xff\n"].concat();
    let err = read_log(bad_utf8.as_slice(), &ReadOptions::default()).unwrap_err();
    assert_eq!((err.kind, err.line), (Kind::NotUtf8, Some(4)));
}

#[test]
fn the_writer_refuses_what_the_reader_would_refuse() {
    let mut log = AcqLog::new(LogMetadata::new(1000.0, 1e6), &[]);
    log.rows.push(LogRow::new(0, 0.0, 0));
    log.rows.push(LogRow::new(1, 0.0, 0));
    assert_eq!(log.write_csv(Vec::new()).unwrap_err().kind, Kind::BadRow);
    log.rows[1] = LogRow::new(1, f64::NAN, 0);
    assert_eq!(log.write_csv(Vec::new()).unwrap_err().kind, Kind::BadRow);
    log.rows[1] = LogRow::new(1, 0.001, 0);
    log.rows[1].p_cmd_m = Some(0.0);
    let err = log.write_csv(Vec::new()).unwrap_err();
    assert!(err.message.contains("without that column"), "{err}");
    let mut meta = LogMetadata::new(1000.0, 1e6);
    meta.firmware = Some("two\nlines".into());
    assert_eq!(
        AcqLog::new(meta, &[])
            .write_csv(Vec::new())
            .unwrap_err()
            .kind,
        Kind::BadMetadataValue
    );
}
