//! The binary form of a log: the protocol's frames exactly as received from the rig, behind a
//! small header, and its lossless conversion to the CSV form.
//!
//! # Container (version 1)
//!
//! | offset | bytes | content |
//! |---|---|---|
//! | 0 | 8 | magic `SJACQBIN` |
//! | 8 | 1 | container version, `1` |
//! | 9 | 1 | protocol version of the frames ([`PROTOCOL_VERSION`]) |
//! | 10 | 4 | metadata length `n`, u32 little-endian (at most [`MAX_METADATA`]) |
//! | 14 | n | metadata: the CSV form's `# key: value` lines, UTF-8 |
//! | 14 + n | rest | the byte stream received from the rig, verbatim: COBS frames each ending in `0x00` ([`sandjumper_core::protocol`]) |
//!
//! Conversion decodes every frame with the core's [`FrameDecoder`]. Each
//! [`RigMessage::Samples`] record becomes one row: `tick` (extended past u32 wrap),
//! `t_s = tick / rate_hz`, `encoder_counts`, `p_cmd_m`, `force_cmd_n`, `current_a`,
//! `camera_frame`, `flags`; the f32 values are widened to f64 exactly and written in
//! shortest round-trip form, so nothing is lost. Sequence numbers must run without a break:
//! a jump in `seq` is lost samples — refused unless `allow_gaps`, which keeps the rows that
//! exist (the tick column then shows the gap) and adds the loss to `dropped_samples`.
//! Rejected frames (bad CRC, bad COBS, ...), fault reports and other messages are counted in
//! the [`ConvertReport`].

use super::AcqLog;
use super::columns::{Column, LogRow};
use super::error::{AcqLogError, AcqLogErrorKind};
use super::metadata::{LogMetadata, MetadataBuilder};
use sandjumper_core::protocol::{FrameDecoder, PROTOCOL_VERSION, RigMessage};
use sandjumper_core::sample::SampleRecord;
use serde::Serialize;
use std::io::{Read, Write};

/// First bytes of a binary log.
pub const MAGIC: &[u8; 8] = b"SJACQBIN";
/// Container version written and read.
pub const CONTAINER_VERSION: u8 = 1;
/// Largest metadata block, bytes.
pub const MAX_METADATA: u32 = 64 * 1024;

fn bin_err(message: impl Into<String>) -> AcqLogError {
    AcqLogError::whole(AcqLogErrorKind::Binary, message)
}

/// Writes a binary log: the header now, then the received bytes as they come.
pub struct BinaryLogWriter<W: Write> {
    out: W,
}

impl<W: Write> BinaryLogWriter<W> {
    /// Writes the header with `meta` (must have the rate and encoder scale).
    pub fn new(mut out: W, meta: &LogMetadata) -> Result<Self, AcqLogError> {
        meta.validate()?;
        let text = meta.to_lines();
        let len = u32::try_from(text.len())
            .ok()
            .filter(|n| *n <= MAX_METADATA)
            .ok_or_else(|| bin_err(format!("metadata longer than {MAX_METADATA} bytes")))?;
        let mut header = Vec::with_capacity(14 + text.len());
        header.extend_from_slice(MAGIC);
        header.push(CONTAINER_VERSION);
        header.push(PROTOCOL_VERSION);
        header.extend_from_slice(&len.to_le_bytes());
        header.extend_from_slice(text.as_bytes());
        out.write_all(&header).map_err(|e| AcqLogError::io(&e))?;
        Ok(Self { out })
    }

    /// Appends bytes exactly as received from the link (any chunking; frames may be split).
    pub fn write_received(&mut self, bytes: &[u8]) -> Result<(), AcqLogError> {
        self.out.write_all(bytes).map_err(|e| AcqLogError::io(&e))
    }

    /// Flushes and returns the underlying writer.
    pub fn finish(mut self) -> Result<W, AcqLogError> {
        self.out.flush().map_err(|e| AcqLogError::io(&e))?;
        Ok(self.out)
    }
}

/// What the conversion saw besides the samples.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ConvertReport {
    /// Frames decoded.
    pub frames_ok: u64,
    /// Frames rejected by the decoder (CRC, COBS, too long, wrong version, malformed).
    pub frames_rejected: u64,
    /// Sample batches.
    pub sample_batches: u64,
    /// Sample records converted to rows.
    pub samples: u64,
    /// Samples missing by sequence number (only with `allow_gaps`).
    pub samples_lost: u64,
    /// Faults reported by the rig: code number, name, tick.
    pub faults: Vec<(u8, &'static str, u32)>,
    /// Other messages (replies, status, lockstep frames).
    pub other_messages: u64,
    /// `samples_dropped` of the last status message, if any (the rig's own count).
    pub rig_samples_dropped: Option<u32>,
}

/// Reads a binary log and converts it to the in-memory log (write it with
/// [`AcqLog::write_csv`]). Never panics; every refusal says what and where.
pub fn convert_binary<R: Read>(
    mut input: R,
    allow_gaps: bool,
    max_rows: usize,
) -> Result<(AcqLog, ConvertReport), AcqLogError> {
    let mut header = [0u8; 14];
    let got = read_full(&mut input, &mut header)?;
    if got < MAGIC.len() || &header[..8] != MAGIC {
        return Err(bin_err(
            "not a binary sandjumper log: it does not start with `SJACQBIN` (CSV logs need no conversion)",
        ));
    }
    if got < header.len() {
        return Err(bin_err("binary log ends inside its 14-byte header"));
    }
    if header[8] != CONTAINER_VERSION {
        return Err(bin_err(format!(
            "binary container version {} not supported: this build reads {CONTAINER_VERSION}",
            header[8]
        )));
    }
    if header[9] != PROTOCOL_VERSION {
        return Err(bin_err(format!(
            "frames use protocol version {}, this build decodes {PROTOCOL_VERSION}",
            header[9]
        )));
    }
    let meta_len = u32::from_le_bytes([header[10], header[11], header[12], header[13]]);
    if meta_len > MAX_METADATA {
        return Err(bin_err(format!(
            "metadata length {meta_len} bytes is over the {MAX_METADATA}-byte limit"
        )));
    }
    let mut meta_bytes = vec![0u8; meta_len as usize];
    if read_full(&mut input, &mut meta_bytes)? < meta_bytes.len() {
        return Err(bin_err("binary log ends inside its metadata block"));
    }
    let meta_text = std::str::from_utf8(&meta_bytes)
        .map_err(|_| bin_err("metadata block is not valid UTF-8"))?;
    let mut builder = MetadataBuilder::default();
    let mut lines = 0;
    for (i, line) in meta_text.lines().enumerate() {
        lines = i as u64 + 1;
        if !line.starts_with('#') {
            return Err(AcqLogError::at(
                lines,
                AcqLogErrorKind::MalformedMetadata,
                "metadata block lines must start with `#`",
            ));
        }
        builder.push_line(lines, line)?;
    }
    let meta = builder.finish(lines + 1)?;
    let mut log = AcqLog::new(meta, &SAMPLE_COLUMNS);
    let mut report = ConvertReport::default();
    let mut decoder = FrameDecoder::new();
    let mut state = SequenceState::default();
    let mut buf = [0u8; 8192];
    let mut frame_no: u64 = 0;
    loop {
        let n = match input.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(AcqLogError::io(&e)),
        };
        for &byte in &buf[..n] {
            let Some(result) = decoder.push::<RigMessage>(byte) else {
                continue;
            };
            frame_no += 1;
            match result {
                Err(_) => report.frames_rejected += 1,
                Ok(RigMessage::Samples(batch)) => {
                    report.frames_ok += 1;
                    report.sample_batches += 1;
                    for record in &batch {
                        state.accept(
                            &mut log,
                            &mut report,
                            record,
                            ("frame", frame_no),
                            allow_gaps,
                            max_rows,
                        )?;
                    }
                }
                Ok(RigMessage::Fault(f)) => {
                    report.frames_ok += 1;
                    report.faults.push((f.code.code(), f.code.name(), f.tick));
                }
                Ok(RigMessage::Status(s)) => {
                    report.frames_ok += 1;
                    report.other_messages += 1;
                    report.rig_samples_dropped = Some(s.counters.samples_dropped);
                }
                Ok(_) => {
                    report.frames_ok += 1;
                    report.other_messages += 1;
                }
            }
        }
    }
    if log.rows.is_empty() {
        return Err(bin_err(format!(
            "no sample records in the binary log ({} frames decoded, {} rejected)",
            report.frames_ok, report.frames_rejected
        )));
    }
    log.meta.dropped_samples += report.samples_lost;
    Ok((log, report))
}

/// Sequence-number and tick bookkeeping across batches.
#[derive(Default)]
struct SequenceState {
    last: Option<(u32, u64)>,
}

impl SequenceState {
    fn accept(
        &mut self,
        log: &mut AcqLog,
        report: &mut ConvertReport,
        record: &SampleRecord,
        at: (&str, u64),
        allow_gaps: bool,
        max_rows: usize,
    ) -> Result<(), AcqLogError> {
        let (what, index) = at;
        let tick = match self.last {
            None => u64::from(record.tick),
            Some((seq, tick)) => {
                let expected = seq.wrapping_add(1);
                let lost = record.seq.wrapping_sub(expected);
                if lost > u32::MAX / 2 {
                    return Err(bin_err(format!(
                        "{what} {index}: sequence number {} after {seq} goes backwards (duplicated or reordered samples)",
                        record.seq
                    )));
                }
                if lost > 0 {
                    if !allow_gaps {
                        return Err(bin_err(format!(
                            "{what} {index}: sequence jumps from {seq} to {}: {lost} sample(s) lost; pass --allow-gaps to convert what exists",
                            record.seq
                        )));
                    }
                    report.samples_lost += u64::from(lost);
                }
                let advance = record.tick.wrapping_sub(tick as u32);
                if advance == 0 || advance > u32::MAX / 2 {
                    return Err(bin_err(format!(
                        "{what} {index}: tick {} after tick {} does not increase",
                        record.tick, tick as u32
                    )));
                }
                tick + u64::from(advance)
            }
        };
        if log.rows.len() >= max_rows {
            return Err(bin_err(format!(
                "more than {max_rows} samples (the converter's cap): split the recording"
            )));
        }
        log.rows.push(LogRow {
            tick: Some(tick),
            t_s: tick as f64 / log.meta.rate_hz,
            encoder_counts: record.encoder_count,
            p_cmd_m: Some(f64::from(record.commanded_position_m)),
            force_cmd_n: Some(f64::from(record.force_n)),
            current_a: record.current_a.map(f64::from),
            camera_frame: record.camera_frame.map(u64::from),
            flags: Some(u32::from(record.flags)),
            rod_height_m: None,
        });
        self.last = Some((record.seq, tick));
        report.samples += 1;
        Ok(())
    }
}

fn read_full<R: Read>(input: &mut R, buf: &mut [u8]) -> Result<usize, AcqLogError> {
    let mut filled = 0;
    while filled < buf.len() {
        match input.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(AcqLogError::io(&e)),
        }
    }
    Ok(filled)
}

/// Builds a log from the core's sample records as they arrive (what `sandjumper hil --out`
/// and the rig tool call). Columns: `tick,t_s,encoder_counts,p_cmd_m,force_cmd_n,current_a,
/// camera_frame,flags`; `t_s = tick / rate_hz` (tick extended past u32 wrap).
pub struct SampleLogBuilder {
    log: AcqLog,
    state: SequenceState,
    report: ConvertReport,
}

impl SampleLogBuilder {
    /// An empty log with `meta` (`rate_hz` = the control rate, `counts_per_m` = the encoder
    /// scale).
    pub fn new(meta: LogMetadata) -> Self {
        Self {
            log: AcqLog::new(meta, &SAMPLE_COLUMNS),
            state: SequenceState::default(),
            report: ConvertReport::default(),
        }
    }

    /// Appends one record. A jump in sequence numbers is counted as dropped samples (the tick
    /// column shows where); a sequence number or tick going backwards is an error.
    pub fn push(&mut self, record: &SampleRecord) -> Result<(), AcqLogError> {
        let at = ("record", self.report.samples + 1);
        self.state.accept(
            &mut self.log,
            &mut self.report,
            record,
            at,
            true,
            usize::MAX,
        )
    }

    /// Samples lost so far by sequence number.
    pub fn samples_lost(&self) -> u64 {
        self.report.samples_lost
    }

    /// The finished log; `dropped_samples` includes the sequence gaps seen.
    pub fn finish(mut self) -> AcqLog {
        self.log.meta.dropped_samples += self.report.samples_lost;
        self.log
    }
}

/// The columns a log of sample records has beyond `tick,t_s,encoder_counts`.
const SAMPLE_COLUMNS: [Column; 5] = [
    Column::PCmdM,
    Column::ForceCmdN,
    Column::CurrentA,
    Column::CameraFrame,
    Column::Flags,
];
