//! The wire protocol (host <-> firmware, simulator <-> firmware): one versioned message set,
//! serde + postcard, framed with COBS and a CRC-32.
//!
//! Frame on the wire: `COBS(version:u8 ++ postcard(message) ++ crc32_le(version ++ payload)) ++ 0x00`.
//! CRC-32/ISO-HDLC. Frames are at most [`MAX_FRAME`] bytes including the delimiter.
//! A frame that is too long, not valid COBS, fails its CRC, has another version, or does not
//! decode as a message is rejected with a [`FrameError`] and counted ([`DecoderStats`]); the
//! decoder never panics, whatever the input (fuzzed in `shared/fuzz`).
//!
//! Directions: the host sends [`HostMessage`] (commands, lockstep sensor frames); the rig
//! sends [`RigMessage`] (replies, sample batches, status, faults, lockstep actuator frames).

use core::fmt;

use serde::{Serialize, de::DeserializeOwned};

use crate::command::{Command, Rejection, Reply};
use crate::fault::FaultCode;
use crate::replay::CRC32;
use crate::sample::SampleRecord;
use crate::status::{RigState, Status};

/// Protocol version carried in every frame; bump on any change to the message set.
pub const PROTOCOL_VERSION: u8 = 4;
/// Largest unencoded frame body (version + postcard payload + CRC), bytes.
pub const MAX_BODY: usize = 1024;
/// Largest frame on the wire (COBS overhead and the 0x00 delimiter included), bytes.
pub const MAX_FRAME: usize = MAX_BODY + MAX_BODY / 254 + 2;
/// Sample records per [`RigMessage::Samples`] batch.
pub const SAMPLE_BATCH: usize = 16;

/// Lockstep HIL: the plant's sensors for one control tick.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorFrame {
    /// Frame counter (one per tick; gaps are counted as lost frames).
    pub frame: u32,
    /// Raw encoder counter as the hardware would show it (wraps).
    pub encoder_count: u32,
    /// Motor current, A, if simulated.
    pub current_a: Option<f32>,
    /// Fault injection: treat this tick as a deadline overrun.
    pub overrun: bool,
    /// The bed apparatus's inputs (None: the simulated rig has no apparatus).
    pub bed: Option<crate::bed::BedInputs>,
}

/// Lockstep HIL: the controller's outputs for one control tick.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ActuatorFrame {
    /// The sensor frame this answers.
    pub frame: u32,
    /// Force command, N (exactly 0 unless the drive is enabled).
    pub force_n: f32,
    /// Camera trigger level.
    pub trigger: bool,
    /// Drive enable line.
    pub drive_enabled: bool,
    /// Camera frame started on this tick, if any.
    pub camera_frame: Option<u32>,
    /// State after the tick.
    pub state: RigState,
    /// Latched fault.
    pub fault: Option<FaultCode>,
    /// The bed apparatus's outputs.
    pub bed: crate::bed::BedOutputs,
}

/// A latched fault, as reported in telemetry.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultReport {
    /// The fault.
    pub code: FaultCode,
    /// The tick it was latched on.
    pub tick: u32,
}

/// Messages from the host to the rig.
// No heap in no_std: the big variants stay inline; messages live briefly on the stack.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HostMessage {
    /// A command; the reply carries the same `id`.
    Command { id: u16, command: Command },
    /// Lockstep HIL sensor frame.
    Sensor(SensorFrame),
}

/// Messages from the rig to the host.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RigMessage {
    /// Answer to the command with this `id`.
    Reply {
        id: u16,
        result: Result<Reply, Rejection>,
    },
    /// Sample records in sequence order (a gap in `seq` means dropped records, also counted).
    Samples(heapless::Vec<SampleRecord, SAMPLE_BATCH>),
    /// Unsolicited status (e.g. periodically, with the counters).
    Status(Status),
    /// A fault was latched.
    Fault(FaultReport),
    /// Lockstep HIL actuator frame.
    Actuator(ActuatorFrame),
}

/// Why a frame was not produced or not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// Encoding: the message does not fit [`MAX_BODY`] or the output buffer.
    BufferTooSmall,
    /// Decoding: an empty frame (two delimiters in a row).
    Empty,
    /// Decoding: more than [`MAX_FRAME`] bytes before a delimiter.
    TooLong,
    /// Decoding: not valid COBS.
    Cobs,
    /// Decoding: shorter than version + CRC.
    Truncated,
    /// Decoding: CRC mismatch.
    Crc,
    /// Decoding: another protocol version.
    Version { got: u8 },
    /// Decoding: the payload is not a valid message (or has trailing bytes).
    Malformed,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall => write!(
                f,
                "message does not fit the frame buffer ({MAX_BODY} bytes)"
            ),
            Self::Empty => write!(f, "empty frame"),
            Self::TooLong => write!(f, "frame longer than {MAX_FRAME} bytes"),
            Self::Cobs => write!(f, "invalid COBS encoding"),
            Self::Truncated => write!(f, "frame shorter than version + CRC"),
            Self::Crc => write!(f, "CRC mismatch"),
            Self::Version { got } => {
                write!(
                    f,
                    "protocol version {got}, this build speaks {PROTOCOL_VERSION}"
                )
            }
            Self::Malformed => write!(f, "payload is not a valid message"),
        }
    }
}

impl core::error::Error for FrameError {}

/// Encode `msg` as one complete frame (delimiter included) into `out`. Returns its length.
pub fn encode_frame<M: Serialize>(msg: &M, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut body = [0u8; MAX_BODY];
    let used = postcard::to_slice(msg, &mut body[1..MAX_BODY - 4])
        .map_err(|_| FrameError::BufferTooSmall)?
        .len();
    seal(&mut body, 1 + used, out)
}

/// Frame already-serialized payload bytes (version, CRC, COBS, delimiter) into `out`. For
/// tests and fuzzing (arbitrary payloads that pass the CRC) and for relaying.
pub fn encode_payload_frame(payload: &[u8], out: &mut [u8]) -> Result<usize, FrameError> {
    let mut body = [0u8; MAX_BODY];
    let dst = body
        .get_mut(1..1 + payload.len())
        .filter(|_| payload.len() + 5 <= MAX_BODY);
    dst.ok_or(FrameError::BufferTooSmall)?
        .copy_from_slice(payload);
    seal(&mut body, 1 + payload.len(), out)
}

/// `body[1..n]` holds the payload: add the version and CRC, COBS-encode into `out`, delimit.
fn seal(body: &mut [u8; MAX_BODY], n: usize, out: &mut [u8]) -> Result<usize, FrameError> {
    body[0] = PROTOCOL_VERSION;
    let crc = CRC32.checksum(&body[..n]);
    body[n..n + 4].copy_from_slice(&crc.to_le_bytes());
    let encoded = cobs::try_encode(&body[..n + 4], out).map_err(|_| FrameError::BufferTooSmall)?;
    let end = out.get_mut(encoded).ok_or(FrameError::BufferTooSmall)?;
    *end = 0;
    Ok(encoded + 1)
}

/// Encode `msg` into a fresh buffer.
pub fn encode_frame_vec<M: Serialize>(msg: &M) -> Result<heapless::Vec<u8, MAX_FRAME>, FrameError> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode_frame(msg, &mut buf)?;
    heapless::Vec::from_slice(&buf[..n]).map_err(|_| FrameError::BufferTooSmall)
}

/// Decode one frame's bytes (COBS-encoded, without the 0x00 delimiter), in place.
pub fn decode_frame<M: DeserializeOwned>(encoded: &mut [u8]) -> Result<M, FrameError> {
    if encoded.is_empty() {
        return Err(FrameError::Empty);
    }
    let n = cobs::decode_in_place(encoded).map_err(|_| FrameError::Cobs)?;
    let body = encoded.get(..n).ok_or(FrameError::Cobs)?;
    if body.len() < 5 {
        return Err(FrameError::Truncated);
    }
    let (data, crc_bytes) = body.split_at(body.len() - 4);
    let crc = u32::from_le_bytes([crc_bytes[0], crc_bytes[1], crc_bytes[2], crc_bytes[3]]);
    if CRC32.checksum(data) != crc {
        return Err(FrameError::Crc);
    }
    if data[0] != PROTOCOL_VERSION {
        return Err(FrameError::Version { got: data[0] });
    }
    match postcard::take_from_bytes::<M>(&data[1..]) {
        Ok((msg, [])) => Ok(msg),
        _ => Err(FrameError::Malformed),
    }
}

/// Counts of what the decoder saw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderStats {
    /// Frames decoded.
    pub ok: u32,
    /// Frames rejected, all causes.
    pub rejected: u32,
    /// Of which: CRC mismatches.
    pub crc: u32,
    /// Of which: over-long frames.
    pub too_long: u32,
    /// Of which: bad COBS, truncated, wrong version, malformed payload or empty.
    pub other: u32,
}

/// Streaming frame decoder: feed bytes as they arrive; a complete frame comes out as
/// `Some(Ok(message))` or `Some(Err(why))`. Bounded buffer; never panics.
#[derive(Debug)]
pub struct FrameDecoder {
    buf: heapless::Vec<u8, MAX_FRAME>,
    overflowed: bool,
    stats: DecoderStats,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    /// Empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: heapless::Vec::new(),
            overflowed: false,
            stats: DecoderStats {
                ok: 0,
                rejected: 0,
                crc: 0,
                too_long: 0,
                other: 0,
            },
        }
    }

    /// What the decoder has seen so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Feed one byte.
    pub fn push<M: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<M, FrameError>> {
        if byte != 0 {
            if self.buf.push(byte).is_err() {
                self.overflowed = true;
            }
            return None;
        }
        let result = if self.overflowed {
            Err(FrameError::TooLong)
        } else if self.buf.is_empty() {
            // Back-to-back delimiters (e.g. resynchronisation): not a frame, not an error.
            return None;
        } else {
            decode_frame::<M>(&mut self.buf)
        };
        self.buf.clear();
        self.overflowed = false;
        match &result {
            Ok(_) => self.stats.ok = self.stats.ok.wrapping_add(1),
            Err(e) => {
                self.stats.rejected = self.stats.rejected.wrapping_add(1);
                match e {
                    FrameError::Crc => self.stats.crc = self.stats.crc.wrapping_add(1),
                    FrameError::TooLong => {
                        self.stats.too_long = self.stats.too_long.wrapping_add(1)
                    }
                    _ => self.stats.other = self.stats.other.wrapping_add(1),
                }
            }
        }
        Some(result)
    }
}

#[cfg(test)]
mod tests;
