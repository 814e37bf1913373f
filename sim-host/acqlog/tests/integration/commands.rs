//! `log check` and `log convert` called as a library: a binary log converted to CSV and to
//! MCAP, checked, with the typed outcomes and the refusals the command line prints.

use std::path::Path;

use sandjumper_acqlog::{
    BinaryLogWriter, CheckRequest, ConvertOutcome, ConvertRequest, LogError, LogForm, LogMetadata,
    check, convert,
};
use sandjumper_core::protocol::{RigMessage, SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::sample::SampleRecord;
use sandjumper_output::{Blame, Blamed, Silent};

/// A binary log of 100 samples, one missing when `skip` says which.
fn write_binary(path: &Path, skip: Option<u32>) {
    let mut w = BinaryLogWriter::new(Vec::new(), &LogMetadata::new(10_000.0, 1e6)).unwrap();
    let records: Vec<SampleRecord> = (0..100u32)
        .filter(|i| Some(*i) != skip)
        .map(|i| SampleRecord {
            seq: i,
            tick: 1000 + i,
            encoder_count: -18_750 + i64::from(i),
            commanded_position_m: -0.01875,
            force_n: 11.0,
            current_a: None,
            camera_frame: None,
            flags: 0,
        })
        .collect();
    for batch in records.chunks(SAMPLE_BATCH) {
        let m = RigMessage::Samples(batch.iter().copied().collect());
        w.write_received(&encode_frame_vec(&m).unwrap()).unwrap();
    }
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

#[test]
fn a_binary_log_converts_to_csv_and_mcap_and_both_check() {
    let tmp = tempfile::tempdir().unwrap();
    let (bin, csv) = (tmp.path().join("run.bin"), tmp.path().join("run.csv"));
    write_binary(&bin, None);
    let to_csv = ConvertRequest {
        input: bin.clone(),
        output: csv.clone(),
        ..ConvertRequest::default()
    };
    assert_eq!(to_csv.form(), LogForm::Csv);
    let ConvertOutcome::Csv { report, .. } = convert::run(&to_csv, &Silent).unwrap() else {
        panic!("not CSV");
    };
    assert_eq!((report.samples, report.samples_lost), (100, 0));
    for (f, form) in [(&bin, "binary"), (&csv, "csv")] {
        let c = check::run(
            &CheckRequest {
                file: f.clone(),
                allow_gaps: false,
            },
            &Silent,
        )
        .unwrap();
        assert_eq!((c.form, c.log.rows.len()), (form, 100));
        assert!(c.json().unwrap().contains(&format!("\"form\": \"{form}\"")));
    }
    // An existing output is refused without `force`; a CSV input is not converted to CSV.
    let e = convert::run(&to_csv, &Silent).unwrap_err();
    assert_eq!(e, LogError::Exists { path: csv.clone() });
    assert_eq!(e.blame(), Blame::Input);
    let again = ConvertRequest {
        input: csv.clone(),
        output: tmp.path().join("again.csv"),
        ..ConvertRequest::default()
    };
    assert!(
        convert::run(&again, &Silent)
            .unwrap_err()
            .to_string()
            .contains("not a binary log")
    );
    let to_mcap = ConvertRequest {
        output: tmp.path().join("run.mcap"),
        ..to_csv
    };
    let o = convert::run(&to_mcap, &Silent).unwrap();
    let ConvertOutcome::Mcap {
        samples, report, ..
    } = &o
    else {
        panic!("not MCAP");
    };
    assert_eq!(*samples, 100);
    assert!(report.chunks > 0);
    assert!(o.to_string().starts_with("wrote "), "{o}");
}

#[test]
fn a_lost_sample_is_refused_unless_gaps_are_allowed() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = tmp.path().join("gap.bin");
    write_binary(&bin, Some(40));
    let mut r = CheckRequest {
        file: bin,
        allow_gaps: false,
    };
    let e = check::run(&r, &Silent).unwrap_err();
    assert!(matches!(e, LogError::Bad { .. }), "{e}");
    r.allow_gaps = true;
    let c = check::run(&r, &Silent).unwrap();
    assert_eq!(c.conversion.unwrap().samples_lost, 1);
}
