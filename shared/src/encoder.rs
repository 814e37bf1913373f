//! Encoder extension: a 16- or 32-bit hardware quadrature counter made wrap-free (i64).
//!
//! Each tick the signed difference between the new and the previous raw reading, taken modulo
//! the counter width, is added to the 64-bit count. The direction bit of the timer is never
//! used: a reversal between two reads is just a negative delta. This is exact as long as the
//! motor moves less than half the counter range per tick; a delta larger than
//! `max_counts_per_tick` (what the motor can physically do in one tick) is an encoder fault.

/// Width of the hardware counter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CounterWidth {
    /// 16-bit timer (only the low 16 bits of the raw value are used).
    Bits16,
    /// 32-bit timer (TIM2/TIM5 on the F407).
    Bits32,
}

/// The encoder moved more than physically possible in one tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EncoderJump {
    /// The signed delta seen, counts.
    pub delta_counts: i64,
    /// The allowed magnitude, counts.
    pub max_counts_per_tick: u32,
}

/// Extends a wrapping hardware counter to a wrap-free i64 count.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EncoderExtender {
    width: CounterWidth,
    max_counts_per_tick: u32,
    last_raw: u32,
    count: i64,
    started: bool,
}

impl EncoderExtender {
    /// `max_counts_per_tick`: largest plausible |delta| per tick. It is capped below half the
    /// counter range (beyond that a delta cannot be told from a wrap).
    pub fn new(width: CounterWidth, max_counts_per_tick: u32) -> Self {
        let cap = match width {
            CounterWidth::Bits16 => (1u32 << 15) - 1,
            CounterWidth::Bits32 => (1u32 << 31) - 1,
        };
        Self {
            width,
            max_counts_per_tick: max_counts_per_tick.min(cap),
            last_raw: 0,
            count: 0,
            started: false,
        }
    }

    /// A first reading has been taken (before it, there is no delta to speak of).
    pub fn is_started(&self) -> bool {
        self.started
    }

    /// The extended count, counts (0 before the first reading).
    pub fn count(&self) -> i64 {
        self.count
    }

    /// Forget the counter's history: the next reading sets the count, as the first reading
    /// after start-up does (entering lockstep, where the host's counter replaces the board's).
    pub fn restart(&mut self) {
        self.started = false;
    }

    /// Feed one raw reading. The first reading is taken as a signed value of the counter's
    /// width (so a counter reset to 0 at the rig's zero position reads 0, and one step below
    /// reads -1). On a jump the count is left unchanged (last good value) and the raw value is
    /// still remembered, so the next delta is measured from it.
    pub fn update(&mut self, raw: u32) -> Result<i64, EncoderJump> {
        let delta: i64 = match self.width {
            CounterWidth::Bits16 => {
                let r = raw as u16;
                if !self.started {
                    self.started = true;
                    self.last_raw = r as u32;
                    self.count = r as i16 as i64;
                    return Ok(self.count);
                }
                r.wrapping_sub(self.last_raw as u16) as i16 as i64
            }
            CounterWidth::Bits32 => {
                if !self.started {
                    self.started = true;
                    self.last_raw = raw;
                    self.count = raw as i32 as i64;
                    return Ok(self.count);
                }
                raw.wrapping_sub(self.last_raw) as i32 as i64
            }
        };
        self.last_raw = raw;
        if delta.unsigned_abs() > self.max_counts_per_tick as u64 {
            return Err(EncoderJump {
                delta_counts: delta,
                max_counts_per_tick: self.max_counts_per_tick,
            });
        }
        self.count += delta;
        Ok(self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn first_reading_is_signed() {
        let mut e = EncoderExtender::new(CounterWidth::Bits16, 100);
        assert_eq!(e.update(0xFFFF), Ok(-1));
        assert_eq!(e.update(2), Ok(2));
        let mut e = EncoderExtender::new(CounterWidth::Bits32, 100);
        assert_eq!(e.update(u32::MAX - 4), Ok(-5));
        assert_eq!(e.update(5), Ok(5));
    }

    #[test]
    fn jump_beyond_limit_is_a_fault() {
        let mut e = EncoderExtender::new(CounterWidth::Bits32, 100);
        e.update(0).unwrap();
        assert_eq!(e.update(100), Ok(100));
        assert_eq!(
            e.update(201),
            Err(EncoderJump {
                delta_counts: 101,
                max_counts_per_tick: 100
            })
        );
        assert_eq!(e.count(), 100);
    }

    fn raw_of(true_count: i64, width: CounterWidth) -> u32 {
        match width {
            CounterWidth::Bits16 => (true_count as u16) as u32 | 0xABCD_0000, // junk high bits
            CounterWidth::Bits32 => true_count as u32,
        }
    }

    proptest! {
        /// Random walks with reversals and many wraps: the extended count equals the true one.
        #[test]
        fn extension_tracks_random_walk(
            start in -5_000_000_000i64..5_000_000_000,
            steps in proptest::collection::vec(-30_000i64..=30_000, 1..400),
            wide in any::<bool>(),
        ) {
            let width = if wide { CounterWidth::Bits32 } else { CounterWidth::Bits16 };
            let mut e = EncoderExtender::new(width, 30_000);
            let first = e.update(raw_of(start, width)).unwrap();
            let mut truth = first;
            for s in steps {
                truth += s;
                prop_assert_eq!(e.update(raw_of(truth, width)), Ok(truth));
            }
        }
    }
}
