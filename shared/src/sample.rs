//! Per-tick sample records and the fixed-capacity queue they wait in until telemetry drains
//! them. Every record gets the next sequence number whether or not it fits, so a reader sees a
//! gap exactly where records were dropped; drops are also counted.

/// Bits of [`SampleRecord::flags`].
pub mod flags {
    /// Drive enabled this tick.
    pub const DRIVE_ENABLED: u16 = 1 << 0;
    /// Armed (holding the start position).
    pub const ARMED: u16 = 1 << 1;
    /// Running a trajectory.
    pub const RUNNING: u16 = 1 << 2;
    /// Trajectory finished, holding the final position.
    pub const DONE: u16 = 1 << 3;
    /// A fault is latched.
    pub const FAULTED: u16 = 1 << 4;
    /// The force command was saturated at the drive limit.
    pub const SATURATED: u16 = 1 << 5;
    /// The integrator was held by anti-windup.
    pub const INTEGRATOR_HELD: u16 = 1 << 6;
    /// Gains lowered (gain-lowering damping active).
    pub const GAINS_LOWERED: u16 = 1 << 7;
    /// Camera trigger line high.
    pub const CAMERA_HIGH: u16 = 1 << 8;
    /// The trajectory is in its delay phase.
    pub const DELAY: u16 = 1 << 9;
    /// The trajectory is in its push-off phase.
    pub const PUSH_OFF: u16 = 1 << 10;
}

/// What happened on one control tick.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampleRecord {
    /// Sequence number (consecutive; a gap means dropped records).
    pub seq: u32,
    /// Control tick since start-up.
    pub tick: u32,
    /// Wrap-free encoder count.
    pub encoder_count: i64,
    /// Commanded position, m.
    pub commanded_position_m: f32,
    /// Force command sent to the drive, N (exactly 0 when faulted).
    pub force_n: f32,
    /// Measured motor current, A, if the glue measured one.
    pub current_a: Option<f32>,
    /// Camera frame started on this tick, if any.
    pub camera_frame: Option<u32>,
    /// [`flags`] bits.
    pub flags: u16,
}

/// Fixed-capacity FIFO of sample records with sequence numbers and an overflow count.
#[derive(Debug)]
pub struct SampleQueue<const N: usize> {
    queue: heapless::Deque<SampleRecord, N>,
    next_seq: u32,
    dropped: u32,
}

impl<const N: usize> Default for SampleQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> SampleQueue<N> {
    /// Empty queue; the first record gets sequence number 0.
    pub const fn new() -> Self {
        Self {
            queue: heapless::Deque::new(),
            next_seq: 0,
            dropped: 0,
        }
    }

    /// Stamp `record` with the next sequence number and queue it; if full, drop it and count
    /// the drop. Returns the sequence number.
    pub fn push(&mut self, mut record: SampleRecord) -> u32 {
        let seq = self.next_seq;
        self.next_seq = seq.wrapping_add(1);
        record.seq = seq;
        if self.queue.push_back(record).is_err() {
            self.dropped = self.dropped.wrapping_add(1);
        }
        seq
    }

    /// Oldest record, if any.
    pub fn pop(&mut self) -> Option<SampleRecord> {
        self.queue.pop_front()
    }

    /// Move up to `B` records (as many as `out` has room for) into `out`. Returns how many.
    pub fn drain_into<const B: usize>(
        &mut self,
        out: &mut heapless::Vec<SampleRecord, B>,
    ) -> usize {
        let mut n = 0;
        while !out.is_full() {
            let Some(r) = self.queue.pop_front() else {
                break;
            };
            // Cannot fail: checked `is_full` above.
            let _ = out.push(r);
            n += 1;
        }
        n
    }

    /// Records waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// No records waiting.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Records produced so far (= the next sequence number).
    pub fn produced(&self) -> u32 {
        self.next_seq
    }

    /// Records dropped because the queue was full.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(tick: u32) -> SampleRecord {
        SampleRecord {
            seq: 999,
            tick,
            encoder_count: 0,
            commanded_position_m: 0.0,
            force_n: 0.0,
            current_a: None,
            camera_frame: None,
            flags: 0,
        }
    }

    #[test]
    fn overflow_is_counted_and_visible_as_a_sequence_gap() {
        let mut q = SampleQueue::<4>::new();
        for t in 0..6 {
            q.push(rec(t));
        }
        assert_eq!(q.dropped(), 2);
        assert_eq!(q.produced(), 6);
        let mut out = heapless::Vec::<SampleRecord, 8>::new();
        assert_eq!(q.drain_into(&mut out), 4);
        let seqs: heapless::Vec<u32, 8> = out.iter().map(|r| r.seq).collect();
        assert_eq!(seqs.as_slice(), &[0, 1, 2, 3]);
        q.push(rec(6));
        assert_eq!(q.pop().map(|r| r.seq), Some(6)); // gap 4, 5: the dropped ones
        assert!(q.is_empty());
    }
}
