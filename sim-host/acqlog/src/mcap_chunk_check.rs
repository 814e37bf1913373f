//! A check of the plain (uncompressed) chunks of an MCAP file before the `mcap` crate's linear
//! reader reads them.
//!
//! The crate (0.26) counts a plain chunk's bytes down by each inner record's length without
//! checking that the record fits in the chunk: a damaged length overflows the count (a panic
//! where overflow checks are on, a wrapped count that reads past the chunk where they are
//! off). [`first_overrun`] finds the first inner record that does not fit in its chunk, so the
//! reader can be given the file only up to that record: what precedes it is read as from a
//! file cut there, and the record is reported instead.
//!
//! The walk follows the MCAP framing (an 8-byte magic, then records of a 1-byte opcode, a
//! little-endian `u64` length and the body). It stops, reporting nothing, where the file ends
//! (a record's head or a chunk's header cut off), and passes over the chunks the crate refuses
//! itself (compressed ones, whose records it checks as it decompresses them; a chunk whose
//! header or record area is longer than the chunk): what the walk finds after those is never
//! read, since the crate stops first.

use mcap::records::op;

/// Bytes of a record's opcode and length.
const RECORD_HEAD: usize = 1 + 8;

/// A chunk's fields before its compression string: message start and end times, uncompressed
/// size (`u64` each) and uncompressed CRC (`u32`), then the string's `u32` length.
const CHUNK_FIXED_HEAD: usize = 8 + 8 + 8 + 4 + 4;

/// An inner record of a plain chunk that does not fit in the chunk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Overrun {
    /// Byte offset in the file of the record's opcode: the file is readable up to here.
    pub at: usize,
    /// What is wrong, for the reader's `stopped`.
    pub why: String,
}

/// The first inner record of a plain chunk whose head or length overruns its chunk, if any.
/// Only what lies within `bytes` is judged, so a file cut before that record reports nothing,
/// and one cut after its head (or, for a chunk that ends inside the head, after its first byte)
/// reports the same record.
pub(crate) fn first_overrun(bytes: &[u8]) -> Option<Overrun> {
    let mut at = mcap::MAGIC.len();
    if bytes.get(..at)? != mcap::MAGIC {
        return None;
    }
    loop {
        let (opcode, len) = head(bytes, at)?;
        let body = at + RECORD_HEAD;
        let end = body.checked_add(usize::try_from(len).ok()?)?;
        if opcode == op::FOOTER {
            return None;
        }
        if opcode == op::CHUNK
            && let Some(overrun) = chunk_overrun(bytes, body, end)
        {
            return Some(overrun);
        }
        at = end;
    }
}

/// Within the chunk whose body spans `body..end` of the file: the first inner record that
/// does not fit, when the chunk is plain and its header lies within the file.
fn chunk_overrun(bytes: &[u8], body: usize, end: usize) -> Option<Overrun> {
    let fixed = bytes.get(body..body.checked_add(CHUNK_FIXED_HEAD)?)?;
    let compression_len = u32::from_le_bytes(fixed[CHUNK_FIXED_HEAD - 4..].try_into().ok()?);
    if compression_len != 0 {
        // Compressed records are checked by the crate as it decompresses them.
        return None;
    }
    let records_len_at = body + CHUNK_FIXED_HEAD;
    let records_len = u64::from_le_bytes(
        bytes
            .get(records_len_at..records_len_at + 8)?
            .try_into()
            .ok()?,
    );
    let records = records_len_at + 8;
    // A record area longer than the chunk is the crate's own error (an unexpected end of chunk).
    let records_end = records.checked_add(usize::try_from(records_len).ok()?)?;
    if records_end > end {
        return None;
    }
    let mut at = records;
    while at < records_end {
        if at >= bytes.len() {
            return None; // the file is cut before this record
        }
        let left = records_end - at;
        if left < RECORD_HEAD {
            return Some(Overrun {
                at,
                why: format!(
                    "a chunk at byte {} ends {left} bytes into a record's {RECORD_HEAD}-byte head \
                     at byte {at}",
                    body - RECORD_HEAD
                ),
            });
        }
        let (opcode, len) = head(bytes, at)?;
        if len > (left - RECORD_HEAD) as u64 {
            return Some(Overrun {
                at,
                why: format!(
                    "a record (opcode {opcode:#04x}) at byte {at} claims {len} bytes, but its \
                     chunk (at byte {}) has {} bytes left after the record's head",
                    body - RECORD_HEAD,
                    left - RECORD_HEAD
                ),
            });
        }
        at += RECORD_HEAD + len as usize;
    }
    None
}

/// The opcode and length of the record at `at`, if its head lies within `bytes`.
fn head(bytes: &[u8], at: usize) -> Option<(u8, u64)> {
    let h = bytes.get(at..at.checked_add(RECORD_HEAD)?)?;
    Some((h[0], u64::from_le_bytes(h[1..].try_into().ok()?)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of one plain chunk holding `inner` (records as bytes), with `declared` as the
    /// chunk's record-area length.
    fn file_with_chunk(inner: &[u8], declared: u64) -> Vec<u8> {
        let mut body = Vec::new();
        body.extend_from_slice(&[0; 8 + 8 + 8 + 4]);
        body.extend_from_slice(&0u32.to_le_bytes()); // compression ""
        body.extend_from_slice(&declared.to_le_bytes());
        body.extend_from_slice(inner);
        let mut f = mcap::MAGIC.to_vec();
        f.push(op::CHUNK);
        f.extend_from_slice(&(body.len() as u64).to_le_bytes());
        f.extend_from_slice(&body);
        f
    }

    fn record(opcode: u8, len: u64, body: &[u8]) -> Vec<u8> {
        let mut r = vec![opcode];
        r.extend_from_slice(&len.to_le_bytes());
        r.extend_from_slice(body);
        r
    }

    #[test]
    fn records_that_fit_their_chunk_pass() {
        let mut inner = record(op::MESSAGE, 3, b"abc");
        inner.extend(record(op::MESSAGE, 0, b""));
        let f = file_with_chunk(&inner, inner.len() as u64);
        assert_eq!(first_overrun(&f), None);
    }

    #[test]
    fn a_record_longer_than_what_is_left_of_its_chunk_is_found_at_its_head() {
        let mut inner = record(op::MESSAGE, 3, b"abc");
        let second = 8 + RECORD_HEAD + CHUNK_FIXED_HEAD + 8 + inner.len();
        inner.extend(record(op::MESSAGE, 40, b"xyz"));
        let f = file_with_chunk(&inner, inner.len() as u64);
        let o = first_overrun(&f).expect("the second record overruns");
        assert_eq!(o.at, second);
        assert!(o.why.contains("claims 40 bytes"), "{}", o.why);
        // Cut anywhere before its head ends: nothing is judged yet, or the same record is.
        for cut in 0..f.len() {
            let got = first_overrun(&f[..cut]);
            if cut >= second + RECORD_HEAD {
                assert_eq!(got.as_ref(), Some(&o), "cut at {cut}");
            } else {
                assert_eq!(got, None, "cut at {cut}");
            }
        }
    }

    #[test]
    fn a_chunk_ending_inside_a_record_head_is_found() {
        let mut inner = record(op::MESSAGE, 1, b"a");
        inner.extend_from_slice(&[op::MESSAGE, 0, 0]);
        let f = file_with_chunk(&inner, inner.len() as u64);
        let o = first_overrun(&f).expect("the chunk ends inside a head");
        assert!(o.why.contains("3 bytes into"), "{}", o.why);
    }

    #[test]
    fn what_the_crate_reports_itself_is_left_to_it() {
        // A record area longer than the chunk, and a compressed chunk.
        let inner = record(op::MESSAGE, 40, b"xyz");
        assert_eq!(first_overrun(&file_with_chunk(&inner, 1000)), None);
        let mut f = file_with_chunk(&inner, inner.len() as u64);
        f[8 + RECORD_HEAD + 28] = 4; // compression "zstd"'s length, the string not there
        assert_eq!(first_overrun(&f), None);
        assert_eq!(first_overrun(b"not an mcap file"), None);
    }
}
