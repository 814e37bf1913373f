//! Acquisition logs as MCAP files, for Foxglove, Lichtblick and PlotJuggler.
//!
//! One channel per quantity group, each message JSON with a JSON schema (MCAP's `json` message
//! encoding and `jsonschema` schema encoding, both in the MCAP well-known registry):
//!
//! | topic | when | fields |
//! |---|---|---|
//! | `/encoder` | every tick | `tick`, `t_s`, `encoder_counts`, `position_m`, `p_cmd_m` |
//! | `/drive` | every tick, if the log has `force_cmd_n` or `current_a` | `force_cmd_n`, `current_a` |
//! | `/status` | every tick, if the log has `flags` | `flags` and one boolean per flag bit |
//! | `/camera` | ticks with a camera frame or a measured rod height | `frame`, `rod_height_m` |
//! | `/faults` | when the latched-fault flag sets or clears, and each fault the rig reported | `event`, `code`, `name` |
//!
//! Every message also carries `tick` and `t_s` as in the CSV, so each value can be compared
//! with the CSV row it came from. A value the CSV leaves empty is `null`.
//!
//! **Timestamps.** `log_time` and `publish_time` are the control tick times in nanoseconds:
//! `tick × 10⁹ / rate_hz` when the log has a `tick` column, otherwise `t_s` in nanoseconds
//! (shifted so the first sample is at 0 if `t_s` starts below 0). They count from the start of
//! the acquisition, not from the Unix epoch, so Foxglove shows them as times in January 1970.
//!
//! **Metadata.** The log's `# key: value` lines become the MCAP metadata record
//! `sandjumper-acqlog` (same keys, same text); a second record, `sandjumper-conversion`, says
//! what the file was made from and what was filled in or lost on the way.
//!
//! **Layout.** Chunked (about [`CHUNK_SIZE`] bytes per chunk) with message, chunk and metadata
//! indexes and statistics in the summary, so a viewer opens and seeks a long log quickly.
//! Chunks are compressed with zstd by default, as Foxglove's own writer does (the JSON messages
//! shrink about tenfold); [`McapCompression::None`] writes plain chunks, whose complete messages
//! can be read up to the cut when a file is cut short (a recorder killed mid-write): see
//! [`read_messages`]. A cut compressed file yields the messages of its complete chunks.

use super::columns::Column;
use super::error::{AcqLogError, AcqLogErrorKind};
use super::mcap_chunk_check::first_overrun;
use super::{AcqLog, ConvertReport};
use mcap::records::MessageHeader;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use sandjumper_core::sample::flags;
use serde::Serialize;
use serde_json::json;
use std::collections::BTreeMap;
use std::io::{Seek, Write};

/// How the chunks are compressed. Zstd and lz4 need the `compression` feature (on by default):
/// without it they write plain chunks, and the default is plain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum McapCompression {
    /// zstd (the default with the `compression` feature; Foxglove's writer's).
    Zstd,
    /// lz4 (faster, larger).
    Lz4,
    /// None: plain chunks, readable up to a cut.
    None,
}

impl Default for McapCompression {
    fn default() -> Self {
        if cfg!(feature = "compression") {
            Self::Zstd
        } else {
            Self::None
        }
    }
}

impl McapCompression {
    #[cfg(feature = "compression")]
    fn mcap(self) -> Option<mcap::Compression> {
        match self {
            Self::Zstd => Some(mcap::Compression::Zstd),
            Self::Lz4 => Some(mcap::Compression::Lz4),
            Self::None => None,
        }
    }

    #[cfg(not(feature = "compression"))]
    fn mcap(self) -> Option<mcap::Compression> {
        None
    }
}

/// Target uncompressed size of one chunk, bytes (about 0.1 s of a 10 kHz log).
pub const CHUNK_SIZE: u64 = 256 * 1024;

/// The flag bits and the names `/status` gives them.
pub const FLAG_NAMES: [(u16, &str); 11] = [
    (flags::DRIVE_ENABLED, "drive_enabled"),
    (flags::ARMED, "armed"),
    (flags::RUNNING, "running"),
    (flags::DONE, "done"),
    (flags::FAULTED, "faulted"),
    (flags::SATURATED, "saturated"),
    (flags::INTEGRATOR_HELD, "integrator_held"),
    (flags::GAINS_LOWERED, "gains_lowered"),
    (flags::CAMERA_HIGH, "camera_high"),
    (flags::DELAY, "delay"),
    (flags::PUSH_OFF, "push_off"),
];

/// What was written.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct McapReport {
    /// Messages per topic.
    pub messages: BTreeMap<String, u64>,
    /// Chunks in the file.
    pub chunks: u64,
}

fn mcap_err(e: impl std::fmt::Display) -> AcqLogError {
    AcqLogError::whole(AcqLogErrorKind::Io, format!("cannot write MCAP: {e}"))
}

/// A JSON schema for one topic: an object with these `(name, type, description)` properties.
fn schema(title: &str, props: &[(&str, &str, &str)]) -> Vec<u8> {
    let properties: serde_json::Map<String, serde_json::Value> = props
        .iter()
        .map(|(name, ty, description)| {
            let ty = match *ty {
                "number?" => json!(["number", "null"]),
                "integer?" => json!(["integer", "null"]),
                "string?" => json!(["string", "null"]),
                t => json!(t),
            };
            (
                (*name).to_string(),
                json!({ "type": ty, "description": description }),
            )
        })
        .collect();
    let required: Vec<&str> = props.iter().map(|p| p.0).collect();
    serde_json::to_vec(&json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": properties,
        "required": required,
    }))
    .unwrap_or_default()
}

const TICK: (&str, &str, &str) = ("tick", "integer?", "control tick number");
const TIME: (&str, &str, &str) = ("t_s", "number", "sample time, s");

/// Control tick time of a row in nanoseconds (see the module docs).
struct Clock {
    rate_hz: f64,
    t_shift_s: f64,
}

impl Clock {
    fn new(log: &AcqLog) -> Self {
        let t0 = log.rows.first().map_or(0.0, |r| r.t_s);
        Self {
            rate_hz: log.meta.rate_hz,
            t_shift_s: if t0 < 0.0 { -t0 } else { 0.0 },
        }
    }

    fn ns(&self, tick: Option<u64>, t_s: f64) -> u64 {
        let s = match tick {
            Some(k) => k as f64 / self.rate_hz,
            None => t_s + self.t_shift_s,
        };
        // In range: ticks and times of a log that the reader accepted are finite and >= 0.
        (s * 1e9).round().max(0.0) as u64
    }
}

/// One channel being written: its id and the sequence number of its next message.
struct Topic {
    id: u16,
    name: &'static str,
    sequence: u32,
}

struct Out<W: Write + Seek> {
    writer: mcap::Writer<W>,
    report: McapReport,
}

impl<W: Write + Seek> Out<W> {
    fn topic(
        &mut self,
        name: &'static str,
        title: &str,
        props: &[(&str, &str, &str)],
    ) -> Result<Topic, AcqLogError> {
        let schema_id = self
            .writer
            .add_schema(title, "jsonschema", &schema(title, props))
            .map_err(mcap_err)?;
        let id = self
            .writer
            .add_channel(schema_id, name, "json", &BTreeMap::new())
            .map_err(mcap_err)?;
        self.report.messages.insert(name.to_string(), 0);
        Ok(Topic {
            id,
            name,
            sequence: 0,
        })
    }

    fn send(
        &mut self,
        topic: &mut Topic,
        time_ns: u64,
        value: &serde_json::Value,
    ) -> Result<(), AcqLogError> {
        let data = serde_json::to_vec(value).map_err(mcap_err)?;
        self.writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id: topic.id,
                    sequence: topic.sequence,
                    log_time: time_ns,
                    publish_time: time_ns,
                },
                &data,
            )
            .map_err(mcap_err)?;
        topic.sequence = topic.sequence.wrapping_add(1);
        *self
            .report
            .messages
            .entry(topic.name.to_string())
            .or_default() += 1;
        Ok(())
    }
}

impl<W: Write + Seek> Out<W> {
    /// A fault the rig reported, `(code, name, tick)`, on `/faults` at its tick.
    fn reported_fault(
        &mut self,
        topic: Option<&mut Topic>,
        clock: &Clock,
        (code, name, tick): (u8, &str, u32),
    ) -> Result<(), AcqLogError> {
        let topic = topic.ok_or_else(|| mcap_err("no fault topic"))?;
        let tick = u64::from(tick);
        let value = json!({"tick": tick, "t_s": tick as f64 / clock.rate_hz,
                           "event": "reported", "code": code, "name": name});
        self.send(topic, clock.ns(Some(tick), 0.0), &value)
    }
}

/// The `# key: value` lines of a log as a map (the `sandjumper-acqlog` metadata record).
fn metadata_map(log: &AcqLog) -> BTreeMap<String, String> {
    log.meta
        .to_lines()
        .lines()
        .filter_map(|l| l.strip_prefix("# "))
        .filter_map(|l| l.split_once(": "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// Writes `log` as MCAP to `out` (see the module docs). `conversion` is the report of the binary
/// log it came from, if it came from one: its faults go to `/faults` and its counts to the
/// `sandjumper-conversion` metadata record.
pub fn write_mcap<W: Write + Seek>(
    log: &AcqLog,
    conversion: Option<&ConvertReport>,
    out: W,
) -> Result<(W, McapReport), AcqLogError> {
    write_mcap_compressed(log, conversion, out, McapCompression::default())
}

/// [`write_mcap`] with the chunks compressed as `compression` says.
pub fn write_mcap_compressed<W: Write + Seek>(
    log: &AcqLog,
    conversion: Option<&ConvertReport>,
    out: W,
    compression: McapCompression,
) -> Result<(W, McapReport), AcqLogError> {
    let options = mcap::WriteOptions::new()
        .compression(compression.mcap())
        .profile("")
        .library(concat!("sandjumper ", env!("CARGO_PKG_VERSION")))
        .chunk_size(Some(CHUNK_SIZE));
    let writer = options.create(out).map_err(mcap_err)?;
    let mut out = Out {
        writer,
        report: McapReport::default(),
    };
    let has = |c: Column| log.columns.contains(c);

    let mut encoder = out.topic(
        "/encoder",
        "sandjumper.Encoder",
        &[
            TICK,
            TIME,
            ("encoder_counts", "integer", "encoder count"),
            (
                "position_m",
                "number",
                "motor position relative to the rod, m (from the count and the log's scale)",
            ),
            (
                "p_cmd_m",
                "number?",
                "commanded motor position relative to the rod, m",
            ),
        ],
    )?;
    let mut drive = if has(Column::ForceCmdN) || has(Column::CurrentA) {
        Some(out.topic(
            "/drive",
            "sandjumper.Drive",
            &[
                TICK,
                TIME,
                (
                    "force_cmd_n",
                    "number?",
                    "force command sent to the drive, N",
                ),
                ("current_a", "number?", "measured motor current, A"),
            ],
        )?)
    } else {
        None
    };
    let mut status = if has(Column::Flags) {
        let mut props = vec![TICK, TIME, ("flags", "integer", "status flags word")];
        props.extend(
            FLAG_NAMES
                .iter()
                .map(|(_, name)| (*name, "boolean", "one bit of `flags`")),
        );
        Some(out.topic("/status", "sandjumper.Status", &props)?)
    } else {
        None
    };
    let mut camera = if has(Column::CameraFrame) || has(Column::RodHeightM) {
        Some(out.topic(
            "/camera",
            "sandjumper.Camera",
            &[
                TICK,
                TIME,
                ("frame", "integer?", "camera frame triggered at this tick"),
                (
                    "rod_height_m",
                    "number?",
                    "camera-measured rod height above rest, m",
                ),
            ],
        )?)
    } else {
        None
    };
    let reported_faults = conversion.map_or(&[][..], |c| c.faults.as_slice());
    let mut faults = if has(Column::Flags) || !reported_faults.is_empty() {
        Some(out.topic(
            "/faults",
            "sandjumper.Fault",
            &[
                TICK,
                TIME,
                (
                    "event",
                    "string",
                    "`latched` or `cleared` (the faulted flag) or `reported` (by the rig)",
                ),
                ("code", "integer?", "fault code (reported faults)"),
                ("name", "string?", "fault name (reported faults)"),
            ],
        )?)
    } else {
        None
    };

    let clock = Clock::new(log);
    let mut pending_faults = reported_faults.iter().peekable();
    let mut was_faulted = false;
    for row in &log.rows {
        let ns = clock.ns(row.tick, row.t_s);
        let (tick, t_s) = (row.tick, row.t_s);
        // Faults the rig reported at or before this tick go out first.
        while let Some(&&(code, name, at)) = pending_faults.peek() {
            if row.tick.is_some_and(|k| k < u64::from(at)) {
                break;
            }
            out.reported_fault(faults.as_mut(), &clock, (code, name, at))?;
            pending_faults.next();
        }
        out.send(
            &mut encoder,
            ns,
            &json!({"tick": tick, "t_s": t_s, "encoder_counts": row.encoder_counts,
                    "position_m": log.meta.position_m(row.encoder_counts),
                    "p_cmd_m": row.p_cmd_m}),
        )?;
        if let Some(topic) = drive.as_mut() {
            out.send(
                topic,
                ns,
                &json!({"tick": tick, "t_s": t_s, "force_cmd_n": row.force_cmd_n,
                        "current_a": row.current_a}),
            )?;
        }
        if let Some(word) = row.flags {
            if let Some(topic) = status.as_mut() {
                let mut value = json!({"tick": tick, "t_s": t_s, "flags": word});
                for (bit, name) in FLAG_NAMES {
                    value[name] = json!(word & u32::from(bit) != 0);
                }
                out.send(topic, ns, &value)?;
            }
            let faulted = word & u32::from(flags::FAULTED) != 0;
            if faulted != was_faulted {
                if let Some(topic) = faults.as_mut() {
                    let event = if faulted { "latched" } else { "cleared" };
                    out.send(
                        topic,
                        ns,
                        &json!({"tick": tick, "t_s": t_s, "event": event,
                                "code": null, "name": null}),
                    )?;
                }
                was_faulted = faulted;
            }
        }
        if let Some(topic) = camera
            .as_mut()
            .filter(|_| row.camera_frame.is_some() || row.rod_height_m.is_some())
        {
            out.send(
                topic,
                ns,
                &json!({"tick": tick, "t_s": t_s, "frame": row.camera_frame,
                        "rod_height_m": row.rod_height_m}),
            )?;
        }
    }
    // Faults reported after the last sample (a rig that faulted and stopped streaming).
    for fault in pending_faults {
        out.reported_fault(faults.as_mut(), &clock, *fault)?;
    }

    out.writer
        .write_metadata(&mcap::records::Metadata {
            name: "sandjumper-acqlog".into(),
            metadata: metadata_map(log),
        })
        .map_err(mcap_err)?;
    let mut conv = BTreeMap::new();
    conv.insert(
        "source_form".to_string(),
        if conversion.is_some() {
            "binary"
        } else {
            "csv"
        }
        .to_string(),
    );
    conv.insert("rows".to_string(), log.rows.len().to_string());
    conv.insert("gaps".to_string(), log.gaps.len().to_string());
    conv.insert(
        "interpolated_samples".to_string(),
        log.interpolated_samples().to_string(),
    );
    if let Some(c) = conversion {
        conv.insert("frames_ok".to_string(), c.frames_ok.to_string());
        conv.insert("frames_rejected".to_string(), c.frames_rejected.to_string());
        conv.insert("samples_lost".to_string(), c.samples_lost.to_string());
    }
    out.writer
        .write_metadata(&mcap::records::Metadata {
            name: "sandjumper-conversion".into(),
            metadata: conv,
        })
        .map_err(mcap_err)?;
    let summary = out.writer.finish().map_err(mcap_err)?;
    out.report.chunks = summary.chunk_indexes.len() as u64;
    let report = out.report;
    Ok((out.writer.into_inner(), report))
}

impl AcqLog {
    /// Writes the log as MCAP to `path` (see [`write_mcap`]).
    pub fn write_mcap_file(
        &self,
        path: &std::path::Path,
        conversion: Option<&ConvertReport>,
    ) -> Result<McapReport, AcqLogError> {
        self.write_mcap_file_compressed(path, conversion, McapCompression::default())
    }

    /// [`AcqLog::write_mcap_file`] with the chunks compressed as `compression` says.
    pub fn write_mcap_file_compressed(
        &self,
        path: &std::path::Path,
        conversion: Option<&ConvertReport>,
        compression: McapCompression,
    ) -> Result<McapReport, AcqLogError> {
        let file = std::fs::File::create(path).map_err(|e| AcqLogError::io(&e))?;
        let (file, report) =
            write_mcap_compressed(self, conversion, std::io::BufWriter::new(file), compression)?;
        file.into_inner()
            .map_err(|e| AcqLogError::io(e.error()))?
            .sync_all()
            .map_err(|e| AcqLogError::io(&e))?;
        Ok(report)
    }
}

/// One message read back from an MCAP file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadMessage {
    /// Its channel's topic.
    pub topic: String,
    /// Per-channel sequence number.
    pub sequence: u32,
    /// Log time, ns.
    pub log_time_ns: u64,
    /// The message bytes (JSON for sandjumper's files).
    pub data: Vec<u8>,
}

/// Messages read from an MCAP file in file order, and whether the file ended cleanly.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadBack {
    /// Every complete message, in file order.
    pub messages: Vec<ReadMessage>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Whether the file ended with its footer and closing magic.
    pub complete: bool,
    /// Why reading stopped early (a cut file or a damaged record), if it did.
    pub stopped: Option<String>,
}

/// Whether [`read_messages`] parses records of `opcode`: channels, messages, metadata and the
/// footer; the others it passes over.
fn parsed_here(opcode: u8) -> bool {
    use mcap::records::op;
    matches!(
        opcode,
        op::CHANNEL | op::MESSAGE | op::METADATA | op::FOOTER
    )
}

/// Check that every length prefix of a channel or metadata record (strings, the string map)
/// lies within the record, before the parser allocates what the prefix says.
fn prefixes_fit(opcode: u8, data: &[u8]) -> Result<(), String> {
    use mcap::records::op;
    let mut f = Fields {
        data,
        at: 0,
        base: 0,
    };
    match opcode {
        op::CHANNEL => {
            f.take(4)?; // id, schema id
            f.string()?; // topic
            f.string()?; // message encoding
            f.map()
        }
        op::METADATA => {
            f.string()?; // name
            f.map()
        }
        _ => Ok(()),
    }
    .map_err(|e| format!("a record (opcode {opcode:#04x}, {} bytes): {e}", data.len()))
}

/// A record's fields read in order, each length checked against what is left.
struct Fields<'a> {
    data: &'a [u8],
    at: usize,
    /// Where `data` starts in the record, bytes (for the errors' offsets).
    base: usize,
}

impl<'a> Fields<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.data.len())
            .ok_or_else(|| {
                format!(
                    "a field claims {n} bytes at byte {} of the record",
                    self.base + self.at
                )
            })?;
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn prefix(&mut self) -> Result<usize, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    }

    fn string(&mut self) -> Result<(), String> {
        let n = self.prefix()?;
        self.take(n).map(|_| ())
    }

    fn map(&mut self) -> Result<(), String> {
        let n = self.prefix()?;
        let base = self.base + self.at;
        let mut entries = Fields {
            data: self.take(n)?,
            at: 0,
            base,
        };
        // The crate reads a key and its value while any of the map is left: both must fit.
        while entries.at < entries.data.len() {
            entries.string()?;
            entries.string()?;
        }
        Ok(())
    }
}

/// The longest record [`read_messages`] reads, bytes: a longer one (a damaged length) stops
/// the reading there.
pub const MAX_RECORD_BYTES: usize = 64 << 20;

/// Reads every complete message of an MCAP file with the crate's linear reader, in file order,
/// recovering what a cut file holds: reading stops at the first incomplete or damaged record
/// and keeps every message before it (in an uncompressed chunk, messages are records too, so a
/// chunk cut in the middle still yields its complete messages). Chunk CRCs are not checked (a
/// cut chunk has no valid CRC to check against). Every message is kept in memory (64 bytes
/// each beside its data): a compressed chunk of millions of tiny messages, a few kilobytes on
/// disk, takes memory in proportion to what it holds, not to the file's size.
pub fn read_messages(bytes: &[u8]) -> ReadBack {
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_validate_chunk_crcs(false)
            .with_validate_data_section_crc(false)
            .with_validate_summary_section_crc(false)
            // A damaged length field must not size an allocation: no record sandjumper
            // writes comes near it (messages are a few hundred bytes).
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    let mut out = ReadBack::default();
    // The crate misreads a plain chunk whose inner record overruns it: read up to that record.
    let overrun = first_overrun(bytes);
    let bytes = &bytes[..overrun.as_ref().map_or(bytes.len(), |o| o.at)];
    let mut topics: BTreeMap<u16, String> = BTreeMap::new();
    let mut fed = 0usize;
    let mut saw_footer = false;
    while let Some(event) = reader.next_event() {
        match event {
            Err(e) => {
                out.stopped = Some(e.to_string());
                return out;
            }
            Ok(LinearReadEvent::ReadRequest(n)) => {
                let take = n.min(bytes.len() - fed);
                if take == 0 {
                    out.stopped = Some(match overrun {
                        Some(o) => o.why,
                        None => format!("the file ends after {} bytes", bytes.len()),
                    });
                    return out;
                }
                reader.insert(take).copy_from_slice(&bytes[fed..fed + take]);
                reader.notify_read(take);
                fed += take;
            }
            Ok(LinearReadEvent::Record { data, opcode }) => {
                // Only the records read here are parsed, and only once their length prefixes
                // fit in the record: the parser sizes a string's buffer from its prefix.
                if !parsed_here(opcode) {
                    continue;
                }
                if let Err(e) = prefixes_fit(opcode, data) {
                    out.stopped = Some(e);
                    return out;
                }
                match mcap::parse_record(opcode, data) {
                    Ok(mcap::records::Record::Channel(c)) => {
                        topics.insert(c.id, c.topic);
                    }
                    Ok(mcap::records::Record::Message { header, data }) => {
                        out.messages.push(ReadMessage {
                            topic: topics.get(&header.channel_id).cloned().unwrap_or_default(),
                            sequence: header.sequence,
                            log_time_ns: header.log_time,
                            data: data.into_owned(),
                        });
                    }
                    Ok(mcap::records::Record::Metadata(m)) => {
                        out.metadata.insert(m.name, m.metadata);
                    }
                    Ok(mcap::records::Record::Footer(_)) => saw_footer = true,
                    Ok(_) => {}
                    Err(e) => {
                        out.stopped = Some(e.to_string());
                        return out;
                    }
                }
            }
        }
    }
    out.complete = saw_footer;
    out
}

#[cfg(test)]
mod tests {
    use super::read_messages;

    /// The fuzzer's first find (`fuzz/corpus/mcap_reader/huge-record-length`): a chunk whose
    /// record claims ~2.5e18 bytes. The reader stops there with a reason, where it once asked
    /// for the whole length at once and the process died.
    #[test]
    fn a_damaged_record_length_stops_the_reading_instead_of_sizing_an_allocation() {
        let bytes = include_bytes!("../fuzz/corpus/mcap_reader/huge-record-length");
        let back = read_messages(bytes);
        assert!(!back.complete);
        let why = back.stopped.expect("it stops at the damaged record");
        assert!(!why.is_empty());
    }

    /// Found in CI (`fuzz/corpus/mcap_reader/chunk-record-overrun`): a plain chunk whose inner
    /// record claims more than is left of the chunk. The crate subtracted past zero (a panic
    /// with overflow checks on); the reading now stops at that record and says why.
    #[test]
    fn a_record_overrunning_its_plain_chunk_stops_the_reading_there() {
        let bytes = include_bytes!("../fuzz/corpus/mcap_reader/chunk-record-overrun");
        let back = read_messages(bytes);
        assert!(!back.complete);
        let why = back.stopped.expect("it stops at the overrunning record");
        assert!(why.contains("chunk"), "{why}");
    }

    /// A plain chunk of three messages whose second claims more than the chunk holds: the
    /// first is read, and the reading stops at the second, naming it.
    #[test]
    fn the_messages_before_a_record_overrunning_its_chunk_are_kept() {
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .create(std::io::Cursor::new(Vec::new()))
            .unwrap();
        let schema = w.add_schema("s", "jsonschema", b"{}").unwrap();
        let channel = w
            .add_channel(schema, "/t", "json", &Default::default())
            .unwrap();
        for sequence in 0..3 {
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence,
                log_time: u64::from(sequence),
                publish_time: 0,
            };
            w.write_to_known_channel(&header, b"{\"v\":12345}").unwrap();
        }
        w.finish().unwrap();
        let mut bytes = w.into_inner().into_inner();
        assert_eq!(read_messages(&bytes).messages.len(), 3);
        // The second message record's head and first fields: opcode, length (a 22-byte
        // header: channel id, sequence, log and publish times; then the 11-byte payload),
        // channel id, sequence 1. Its length is then damaged.
        let message = |seq: u32| {
            let mut m = vec![mcap::records::op::MESSAGE];
            m.extend_from_slice(&(22u64 + 11).to_le_bytes());
            m.extend_from_slice(&channel.to_le_bytes());
            m.extend_from_slice(&seq.to_le_bytes());
            m
        };
        let at = bytes
            .windows(15)
            .position(|w| w == message(1))
            .expect("the second message record");
        bytes[at + 1..at + 9].copy_from_slice(&4000u64.to_le_bytes());
        let back = read_messages(&bytes);
        assert_eq!(back.messages.len(), 1);
        assert_eq!(back.messages[0].sequence, 0);
        let why = back.stopped.expect("it stops at the damaged record");
        assert!(
            why.contains(&format!("at byte {at} claims 4000 bytes")),
            "{why}"
        );
    }

    /// Its second (`fuzz/corpus/mcap_reader/huge-string-length`): a header record whose
    /// string claims 3.8 GB. Records other than channels, messages, metadata and the footer
    /// are passed over, and the strings of those are checked against their record first.
    #[test]
    fn a_damaged_string_length_never_sizes_an_allocation() {
        let bytes = include_bytes!("../fuzz/corpus/mcap_reader/huge-string-length");
        let _ = read_messages(bytes);
        let mut channel = vec![1, 0, 0, 0];
        channel.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(super::prefixes_fit(mcap::records::op::CHANNEL, &channel).is_err());
        let mut metadata = 4u32.to_le_bytes().to_vec();
        metadata.extend_from_slice(b"name");
        metadata.extend_from_slice(&8u32.to_le_bytes());
        metadata.extend_from_slice(&(1u32 << 30).to_le_bytes());
        metadata.extend_from_slice(b"abcd");
        let e = super::prefixes_fit(mcap::records::op::METADATA, &metadata).unwrap_err();
        assert!(e.contains("claims 1073741824 bytes"), "{e}");
        // A map ending after a key: the crate reads the value past the map (found by the
        // fuzzer, `fuzz/corpus/mcap_reader/map-key-without-value`, in a zstd chunk).
        let mut metadata = 4u32.to_le_bytes().to_vec();
        metadata.extend_from_slice(b"name");
        metadata.extend_from_slice(&5u32.to_le_bytes());
        metadata.extend_from_slice(&1u32.to_le_bytes());
        metadata.extend_from_slice(b"k");
        metadata.extend_from_slice(&u32::MAX.to_le_bytes());
        let e = super::prefixes_fit(mcap::records::op::METADATA, &metadata).unwrap_err();
        assert!(e.contains("claims 4 bytes at byte 17 of the record"), "{e}");
        let bytes = include_bytes!("../fuzz/corpus/mcap_reader/map-key-without-value");
        assert!(read_messages(bytes).stopped.is_some());
    }
}
