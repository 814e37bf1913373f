//! Replay of a sampled position table `p[k]` (e.g. an encoder log), uploaded in chunks.
//!
//! * Fixed capacity [`REPLAY_CAPACITY`] samples of f32 metres (16 KiB), one sample every
//!   `sample_period_ticks` control ticks (at 10 kHz and a 1 kHz log: 4.096 s).
//! * Upload: [`ReplayTable::begin`] (length, period), [`ReplayTable::write_chunk`] in order,
//!   [`ReplayTable::commit`] with the CRC-32 of the whole table ([`replay_checksum`]:
//!   CRC-32/ISO-HDLC over the samples as little-endian f32 bytes), which the host computes the
//!   same way. Only a committed table can be replayed. The table keeps the checksum as chunks
//!   arrive, so every step of an upload costs at most one chunk's work inside a control tick.
//! * Interpolation: Catmull-Rom cubic between samples (position and velocity continuous,
//!   acceleration piecewise linear: a smoothing second difference). Before the first sample
//!   it holds `p[0]`; after the last it holds the last.

use core::fmt;

/// Capacity of the replay table, samples.
pub const REPLAY_CAPACITY: usize = 4096;

/// CRC used for replay checksums (and, in [`crate::protocol`], for frames).
pub const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The CRC a running checksum uses (a static, so its digest can live in the table).
static CRC32_RUNNING: crc::Crc<u32> = CRC32;

/// The checksum of the samples uploaded so far, kept as chunks arrive: committing a full table
/// costs nothing more than a chunk (a control tick on the rig handles commands, and a CRC over
/// 16 KiB at once would take three ticks' budget).
#[derive(Clone)]
struct RunningChecksum(crc::Digest<'static, u32>);

impl RunningChecksum {
    const fn new() -> Self {
        Self(CRC32_RUNNING.digest())
    }

    fn update(&mut self, samples: &[f32]) {
        for s in samples {
            self.0.update(&s.to_le_bytes());
        }
    }

    fn value(&self) -> u32 {
        self.0.clone().finalize()
    }
}

impl fmt::Debug for RunningChecksum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "RunningChecksum({:#010x})", self.value())
    }
}

/// CRC-32/ISO-HDLC of the samples as little-endian f32 bytes.
pub fn replay_checksum(samples: &[f32]) -> u32 {
    let mut d = CRC32.digest();
    for s in samples {
        d.update(&s.to_le_bytes());
    }
    d.finalize()
}

/// Why a replay upload or table was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplayError {
    /// Length 0 or above the capacity.
    Length { len: u32, capacity: u32 },
    /// Sample period 0 ticks.
    ZeroPeriod,
    /// A chunk arrived with no upload in progress (send `ReplayBegin` first).
    NotUploading,
    /// Chunks must arrive in order: expected this offset.
    OutOfOrder { expected: u32, got: u32 },
    /// The chunk runs past the announced length.
    PastEnd { end: u32, len: u32 },
    /// A sample that is NaN/infinite or outside the stroke.
    BadSample { index: u32, value_m: f32 },
    /// Commit before all samples arrived.
    Incomplete { written: u32, len: u32 },
    /// The host's checksum does not match the uploaded samples.
    Checksum { expected: u32, actual: u32 },
    /// Replay requested but no committed table.
    NotCommitted,
}

impl fmt::Display for ReplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Length { len, capacity } => {
                write!(f, "length {len} samples not allowed: 1..={capacity}")
            }
            Self::ZeroPeriod => write!(f, "sample period must be at least 1 tick"),
            Self::NotUploading => write!(f, "chunk without an upload in progress (begin first)"),
            Self::OutOfOrder { expected, got } => {
                write!(
                    f,
                    "chunk at offset {got}, expected offset {expected} (in order)"
                )
            }
            Self::PastEnd { end, len } => {
                write!(f, "chunk ends at {end}, past the announced length {len}")
            }
            Self::BadSample { index, value_m } => write!(
                f,
                "sample {index} = {value_m} m is not finite or outside the stroke"
            ),
            Self::Incomplete { written, len } => {
                write!(f, "commit after {written} of {len} samples")
            }
            Self::Checksum { expected, actual } => write!(
                f,
                "checksum mismatch: host says {expected:#010x}, table has {actual:#010x}"
            ),
            Self::NotCommitted => write!(f, "no committed replay table"),
        }
    }
}

impl core::error::Error for ReplayError {}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Upload {
    Empty,
    Uploading { written: u32 },
    Committed { crc: u32 },
}

/// The fixed-capacity replay table.
#[derive(Clone, Debug)]
pub struct ReplayTable {
    samples: [f32; REPLAY_CAPACITY],
    len: u32,
    period_ticks: u32,
    /// `1 / period_ticks`, so the tick path multiplies instead of dividing.
    inv_period: f32,
    upload: Upload,
    /// The checksum of the samples written so far.
    running: RunningChecksum,
}

impl Default for ReplayTable {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplayTable {
    /// An empty table.
    pub const fn new() -> Self {
        Self {
            samples: [0.0; REPLAY_CAPACITY],
            len: 0,
            period_ticks: 1,
            inv_period: 1.0,
            upload: Upload::Empty,
            running: RunningChecksum::new(),
        }
    }

    /// Start an upload of `len` samples, one every `period_ticks` control ticks. Discards any
    /// previous table.
    pub fn begin(&mut self, len: u32, period_ticks: u32) -> Result<(), ReplayError> {
        self.upload = Upload::Empty;
        if len == 0 || len as usize > REPLAY_CAPACITY {
            return Err(ReplayError::Length {
                len,
                capacity: REPLAY_CAPACITY as u32,
            });
        }
        if period_ticks == 0 {
            return Err(ReplayError::ZeroPeriod);
        }
        self.len = len;
        self.period_ticks = period_ticks;
        self.inv_period = 1.0 / period_ticks as f32;
        self.upload = Upload::Uploading { written: 0 };
        self.running = RunningChecksum::new();
        Ok(())
    }

    /// Append the chunk that starts at sample `offset` (chunks in order).
    pub fn write_chunk(&mut self, offset: u32, chunk: &[f32]) -> Result<(), ReplayError> {
        let Upload::Uploading { written } = self.upload else {
            return Err(ReplayError::NotUploading);
        };
        if offset != written {
            return Err(ReplayError::OutOfOrder {
                expected: written,
                got: offset,
            });
        }
        let end = offset.saturating_add(chunk.len() as u32);
        if end > self.len {
            return Err(ReplayError::PastEnd { end, len: self.len });
        }
        let stroke = crate::stroke::STROKE_M as f32;
        for (i, &v) in chunk.iter().enumerate() {
            if !(v.is_finite() && v.abs() <= stroke) {
                return Err(ReplayError::BadSample {
                    index: offset + i as u32,
                    value_m: v,
                });
            }
        }
        // Element by element, with no panic path (the firmware's tick handles the upload).
        let Some(dst) = self.samples.get_mut(offset as usize..end as usize) else {
            return Err(ReplayError::PastEnd { end, len: self.len });
        };
        for (d, &v) in dst.iter_mut().zip(chunk) {
            *d = v;
        }
        self.running.update(chunk);
        self.upload = Upload::Uploading { written: end };
        Ok(())
    }

    /// Finish the upload: all samples present and the checksum matches. Returns the checksum.
    /// Constant time: the checksum was kept as the chunks arrived.
    pub fn commit(&mut self, expected_crc: u32) -> Result<u32, ReplayError> {
        let Upload::Uploading { written } = self.upload else {
            return Err(ReplayError::NotUploading);
        };
        if written != self.len {
            return Err(ReplayError::Incomplete {
                written,
                len: self.len,
            });
        }
        let actual = self.running.value();
        if actual != expected_crc {
            return Err(ReplayError::Checksum {
                expected: expected_crc,
                actual,
            });
        }
        self.upload = Upload::Committed { crc: actual };
        Ok(actual)
    }

    /// Checksum of the committed table, if there is one.
    pub fn committed_checksum(&self) -> Option<u32> {
        match self.upload {
            Upload::Committed { crc } => Some(crc),
            _ => None,
        }
    }

    /// The samples uploaded so far (all of them once committed), m.
    pub fn samples(&self) -> &[f32] {
        let n = match self.upload {
            Upload::Empty => 0,
            Upload::Uploading { written } => written,
            Upload::Committed { .. } => self.len,
        };
        &self.samples[..n as usize]
    }

    /// Ticks between samples.
    pub fn period_ticks(&self) -> u32 {
        self.period_ticks
    }

    /// Tick of the last sample (the replay's end), or `None` if not committed.
    pub fn end_tick(&self) -> Option<u32> {
        self.committed_checksum()?;
        (self.len - 1).checked_mul(self.period_ticks)
    }

    /// Catmull-Rom evaluation at control tick `n` since the start, in sample units:
    /// `(p, dp/du, d2p/du2)` with `u` = samples. Callers scale by the sample rate.
    pub(crate) fn eval_samples(&self, n: u32) -> (f32, f32, f32) {
        let len = self.len as usize;
        let s = &self.samples[..len.min(REPLAY_CAPACITY)];
        let Some(&last) = s.last() else {
            return (0.0, 0.0, 0.0);
        };
        // Checked arithmetic and `get`: the control tick evaluates this and must have no
        // panic path (a zero period is refused when the table is set up).
        let (Some(i), Some(r)) = (
            n.checked_div(self.period_ticks),
            n.checked_rem(self.period_ticks),
        ) else {
            return (last, 0.0, 0.0);
        };
        let i = i as usize;
        let (Some(&p1), Some(&p2)) = (s.get(i), s.get(i + 1)) else {
            return (last, 0.0, 0.0);
        };
        let u = r as f32 * self.inv_period;
        let p0 = i
            .checked_sub(1)
            .and_then(|k| s.get(k))
            .copied()
            .unwrap_or(p1);
        let p3 = s.get(i + 2).copied().unwrap_or(p2);
        let m1 = 0.5 * (p2 - p0);
        let m2 = 0.5 * (p3 - p1);
        let (u2, u3) = (u * u, u * u * u);
        let p = (2.0 * u3 - 3.0 * u2 + 1.0) * p1
            + (u3 - 2.0 * u2 + u) * m1
            + (3.0 * u2 - 2.0 * u3) * p2
            + (u3 - u2) * m2;
        let v = (6.0 * u2 - 6.0 * u) * (p1 - p2)
            + (3.0 * u2 - 4.0 * u + 1.0) * m1
            + (3.0 * u2 - 2.0 * u) * m2;
        let a = (12.0 * u - 6.0) * (p1 - p2) + (6.0 * u - 4.0) * m1 + (6.0 * u - 2.0) * m2;
        (p, v, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The checksum kept chunk by chunk is the checksum of the whole table, however the
        /// upload is cut into chunks, and a restarted upload starts its checksum afresh.
        #[test]
        fn the_running_checksum_is_the_whole_tables(
            xs in proptest::collection::vec(-0.02f32..0.02, 1..300),
            chunk in 1usize..40,
        ) {
            let mut t = ReplayTable::new();
            t.begin(5, 1).unwrap();
            t.write_chunk(0, &[0.001; 5]).unwrap();
            t.begin(xs.len() as u32, 1).unwrap();
            for (k, c) in xs.chunks(chunk).enumerate() {
                t.write_chunk((chunk * k) as u32, c).unwrap();
            }
            prop_assert_eq!(t.commit(replay_checksum(&xs)), Ok(replay_checksum(&xs)));
        }

        /// Interpolation passes through every sample, and position and velocity are
        /// continuous across the knots (the step over one tick is bounded by the local slope).
        #[test]
        fn catmull_rom_is_c1_through_the_samples(
            xs in proptest::collection::vec(-0.02f32..0.02, 2..60),
            period in 1u32..40,
        ) {
            let mut t = ReplayTable::new();
            upload(&mut t, &xs, period).unwrap();
            for (k, x) in xs.iter().enumerate() {
                prop_assert_eq!(t.eval_samples(k as u32 * period).0, *x);
            }
            let max_dx = xs.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f32::max);
            for k in 1..xs.len() as u32 - 1 {
                let n = k * period;
                let (pl, vl, _) = if period > 1 { t.eval_samples(n - 1) } else { (0.0, 0.0, 0.0) };
                let (p0, v0, _) = t.eval_samples(n);
                if period > 1 {
                    // One tick is 1/period of a sample. With |p1 - p2|, |m1|, |m2| <= max_dx the
                    // Hermite basis bounds |dp/du| <= 3.5 max_dx and |d2p/du2| <= 14 max_dx.
                    prop_assert!((p0 - pl).abs() <= 3.5 * max_dx / period as f32 + 1e-7);
                    prop_assert!((v0 - vl).abs() <= 14.0 * max_dx / period as f32 + 1e-6);
                }
            }
        }
    }

    fn upload(t: &mut ReplayTable, xs: &[f32], period: u32) -> Result<u32, ReplayError> {
        t.begin(xs.len() as u32, period)?;
        for (k, c) in xs.chunks(7).enumerate() {
            t.write_chunk(7 * k as u32, c)?;
        }
        t.commit(replay_checksum(xs))
    }

    #[test]
    fn upload_in_chunks_and_interpolate() {
        let xs: heapless::Vec<f32, 50> = (0..50).map(|k| 1e-4 * k as f32).collect();
        let mut t = ReplayTable::new();
        upload(&mut t, &xs, 10).unwrap();
        assert_eq!(t.end_tick(), Some(490));
        // A straight line is reproduced exactly by Catmull-Rom inside.
        let (p, v, a) = t.eval_samples(255);
        assert!((p - 2.55e-3).abs() < 1e-8);
        assert!((v - 1e-4).abs() < 1e-8);
        assert!(a.abs() < 1e-6);
        assert_eq!(t.eval_samples(10_000), (4.9e-3, 0.0, 0.0));
        // Hits every sample exactly.
        for k in 0..50 {
            assert_eq!(t.eval_samples(10 * k).0, xs[k as usize]);
        }
    }

    #[test]
    fn refuses_bad_uploads() {
        let mut t = ReplayTable::new();
        assert_eq!(t.write_chunk(0, &[0.0]), Err(ReplayError::NotUploading));
        assert_eq!(
            t.begin(0, 1),
            Err(ReplayError::Length {
                len: 0,
                capacity: 4096
            })
        );
        assert_eq!(
            t.begin(5000, 1),
            Err(ReplayError::Length {
                len: 5000,
                capacity: 4096
            })
        );
        assert_eq!(t.begin(3, 0), Err(ReplayError::ZeroPeriod));
        t.begin(3, 1).unwrap();
        assert_eq!(
            t.write_chunk(1, &[0.0]),
            Err(ReplayError::OutOfOrder {
                expected: 0,
                got: 1
            })
        );
        assert_eq!(
            t.write_chunk(0, &[0.0; 4]),
            Err(ReplayError::PastEnd { end: 4, len: 3 })
        );
        assert!(matches!(
            t.write_chunk(0, &[0.0, f32::NAN]),
            Err(ReplayError::BadSample { index: 1, .. })
        ));
        assert!(matches!(
            t.write_chunk(0, &[0.0, 0.1]),
            Err(ReplayError::BadSample { index: 1, .. })
        ));
        t.write_chunk(0, &[0.0, 0.001]).unwrap();
        assert_eq!(
            t.commit(0),
            Err(ReplayError::Incomplete { written: 2, len: 3 })
        );
        t.write_chunk(2, &[0.002]).unwrap();
        let good = replay_checksum(&[0.0, 0.001, 0.002]);
        assert!(matches!(
            t.commit(good ^ 1),
            Err(ReplayError::Checksum { .. })
        ));
        assert_eq!(t.commit(good), Ok(good));
        assert_eq!(t.committed_checksum(), Some(good));
    }
}
