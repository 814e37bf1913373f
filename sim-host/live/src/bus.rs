//! The bus between the run and the view. [`LiveBus`] is the control loop's end: `sample` is
//! a few comparisons and, every 50 ms of rig time, one attempt at a lock that is never
//! waited for. [`LiveFeed`] is the view's end.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};

use serde::Serialize;

/// Rig time per envelope bin, s: two points a bin, about 1,000 points a second.
pub const BIN_S: f64 = 0.002;
/// Rig time per batch, s.
pub const BATCH_S: f64 = 0.05;
/// Batches the queue holds (10 s of rig time) before it drops the oldest.
pub const QUEUE_BATCHES: usize = 200;

/// Reduced samples over one batch: a shared time axis (s) and one column per channel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Batch {
    /// Rig time of each point, s.
    pub t_s: Vec<f64>,
    /// One column per channel, in the bus's channel order.
    pub columns: Vec<Vec<f64>>,
    /// Full-rate samples this batch reduces.
    pub samples: u64,
}

/// Something that must reach the view: never dropped.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// The run started: what it is.
    RunStarted {
        /// A line saying what runs (link, jump, model).
        title: String,
        /// Rig time, s.
        t_s: f64,
    },
    /// The controller's state changed.
    State {
        /// Rig time, s.
        t_s: f64,
        /// The new state's name.
        state: String,
    },
    /// The controller latched a fault.
    Fault {
        /// Rig time, s.
        t_s: f64,
        /// What it reported.
        fault: String,
    },
    /// The jump's trajectory started (the Start command) or ended.
    Jump {
        /// Rig time, s.
        t_s: f64,
        /// `start` or `end`.
        phase: String,
    },
    /// The run ended.
    RunEnded {
        /// Rig time, s.
        t_s: f64,
        /// One line: the outcome (jump height, faults, or the error).
        outcome: String,
        /// Whether it succeeded.
        ok: bool,
    },
    /// A campaign record.
    Campaign(CampaignRecord),
}

/// A campaign's progress.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "record", rename_all = "snake_case")]
pub enum CampaignRecord {
    /// The campaign started (or resumed) with its plan.
    Start {
        /// The plan, one line.
        plan: String,
        /// Points in the plan.
        points: usize,
        /// The parameter the points sweep (for the height plot), if one.
        swept: Option<String>,
        /// Points done before this start (a resumed campaign's history follows as `Point`s).
        done_before: usize,
    },
    /// One point.
    Point {
        /// Its index in the plan.
        index: usize,
        /// Its parameters, `name = value`.
        params: Vec<(String, f64)>,
        /// Jump height, m (NaN: none).
        height_m: f64,
        /// `ok`, `failed` or `skipped`.
        status: String,
        /// Why it failed.
        reason: Option<String>,
        /// From the campaign's history (before a resume).
        history: bool,
    },
    /// The campaign stopped.
    Stop {
        /// The command's exit status.
        exit_status: i32,
        /// One line.
        message: String,
    },
}

/// The shared queue of batches and its drop count.
#[derive(Default)]
pub(crate) struct Queue {
    pub(crate) batches: Mutex<VecDeque<Batch>>,
    /// Full-rate samples in batches dropped because the queue was full.
    pub(crate) dropped_samples: AtomicU64,
    /// Batches dropped.
    pub(crate) dropped_batches: AtomicU64,
}

/// The run's end of the bus.
pub struct LiveBus {
    channels: usize,
    queue: Arc<Queue>,
    events: mpsc::Sender<Event>,
    /// The bin being filled: its start, and per channel (min, max, t of min, t of max).
    bin_start: f64,
    bin: Vec<(f64, f64, f64, f64)>,
    bin_samples: u64,
    /// The rig time of the bin's last sample, s (its first is `bin_start`).
    bin_last: f64,
    /// The batch being filled.
    batch: Batch,
    batch_start: f64,
    /// Batches the lock was busy for, oldest first (bounded like the queue).
    pending: VecDeque<Batch>,
}

/// The view's end of the bus.
pub struct LiveFeed {
    /// Channel names, in order.
    pub channels: Vec<String>,
    pub(crate) queue: Arc<Queue>,
    pub(crate) events: mpsc::Receiver<Event>,
}

/// A bus for `channels` (their names, with units: `force_n`).
pub fn channel(channels: &[&str]) -> (LiveBus, LiveFeed) {
    let queue = Arc::new(Queue::default());
    let (tx, rx) = mpsc::channel();
    let n = channels.len();
    (
        LiveBus {
            channels: n,
            queue: queue.clone(),
            events: tx,
            bin_start: f64::NAN,
            bin: vec![(f64::NAN, f64::NAN, f64::NAN, f64::NAN); n],
            bin_samples: 0,
            bin_last: f64::NAN,
            batch: Batch {
                t_s: Vec::new(),
                columns: vec![Vec::new(); n],
                samples: 0,
            },
            batch_start: f64::NAN,
            pending: VecDeque::new(),
        },
        LiveFeed {
            channels: channels.iter().map(|c| c.to_string()).collect(),
            queue,
            events: rx,
        },
    )
}

impl LiveBus {
    /// A sender for events from another thread (a campaign's worker, a signal handler).
    pub fn events(&self) -> mpsc::Sender<Event> {
        self.events.clone()
    }

    /// Send an event; it is never dropped (if the view has gone, it is nobody's loss).
    pub fn event(&self, e: Event) {
        let _ = self.events.send(e);
    }

    /// One full-rate sample at rig time `t_s` (values in channel order; extra values are
    /// ignored, missing ones are NaN).
    pub fn sample(&mut self, t_s: f64, values: &[f64]) {
        if !t_s.is_finite() {
            return;
        }
        // A batch boundary first: the bin and the batch close before this sample opens the
        // next ones (rig time never goes back across batches).
        if !self.batch_start.is_nan() && t_s >= self.batch_start + BATCH_S {
            self.close_bin();
            self.flush();
            self.batch_start = t_s;
        }
        if !(t_s >= self.bin_start && t_s < self.bin_start + BIN_S) {
            self.close_bin();
            self.bin_start = t_s;
            if self.batch_start.is_nan() {
                self.batch_start = t_s;
            }
        }
        for (c, slot) in self.bin.iter_mut().enumerate() {
            let v = values.get(c).copied().unwrap_or(f64::NAN);
            // (min, max, t of min, t of max)
            if slot.0.is_nan() || v < slot.0 {
                slot.0 = v;
                slot.2 = t_s;
            }
            if slot.1.is_nan() || v > slot.1 {
                slot.1 = v;
                slot.3 = t_s;
            }
        }
        self.bin_last = t_s;
        self.bin_samples += 1;
    }

    /// Send what is gathered now (the run ended, or the view must catch up).
    pub fn flush_now(&mut self) {
        self.close_bin();
        self.flush();
        self.retry_pending();
    }

    /// Send what is gathered now and wait for the queue's lock if the view holds it: for the
    /// run's end, when waiting costs the run nothing.
    pub fn flush_and_wait(&mut self) {
        self.flush_now();
        if self.pending.is_empty() {
            return;
        }
        let mut q = match self.queue.batches.lock() {
            Ok(q) => q,
            Err(p) => p.into_inner(),
        };
        while let Some(b) = self.pending.pop_front() {
            if q.len() >= QUEUE_BATCHES
                && let Some(old) = q.pop_front()
            {
                self.queue
                    .dropped_samples
                    .fetch_add(old.samples, Ordering::Relaxed);
                self.queue.dropped_batches.fetch_add(1, Ordering::Relaxed);
            }
            q.push_back(b);
        }
    }

    /// Put the bin's envelope into the batch: two points, each channel's extremes in their
    /// order in time, at the times of the bin's first and last samples (one point if they
    /// are one sample). Points never lie outside their samples' times, so rig time only goes
    /// forward however batches and flushes cut the bins.
    fn close_bin(&mut self) {
        if self.bin_samples == 0 {
            return;
        }
        let (t0, t1) = (self.bin_start, self.bin_last);
        let one = t1 <= t0;
        self.batch.t_s.push(t0);
        if !one {
            self.batch.t_s.push(t1);
        }
        for (c, slot) in self.bin.iter_mut().enumerate() {
            let (first, second) = if slot.2 <= slot.3 {
                (slot.0, slot.1)
            } else {
                (slot.1, slot.0)
            };
            self.batch.columns[c].push(first);
            if !one {
                self.batch.columns[c].push(second);
            }
            *slot = (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
        }
        self.batch.samples += self.bin_samples;
        self.bin_samples = 0;
        // The next sample opens a bin of its own (after a flush, too).
        self.bin_start = f64::NAN;
    }

    fn flush(&mut self) {
        if self.batch.t_s.is_empty() {
            return;
        }
        let full = std::mem::replace(
            &mut self.batch,
            Batch {
                t_s: Vec::new(),
                columns: vec![Vec::new(); self.channels],
                samples: 0,
            },
        );
        self.pending.push_back(full);
        self.retry_pending();
    }

    /// Move the pending batches into the queue if its lock is free now; never wait.
    fn retry_pending(&mut self) {
        while self.pending.len() > QUEUE_BATCHES {
            let old = self.pending.pop_front().expect("longer than the bound");
            self.count_drop(&old);
        }
        let Ok(mut q) = self.queue.batches.try_lock() else {
            return;
        };
        while let Some(b) = self.pending.pop_front() {
            if q.len() >= QUEUE_BATCHES {
                let old = q.pop_front().expect("full");
                self.count_drop(&old);
            }
            q.push_back(b);
        }
    }

    fn count_drop(&self, b: &Batch) {
        self.queue
            .dropped_samples
            .fetch_add(b.samples, Ordering::Relaxed);
        self.queue.dropped_batches.fetch_add(1, Ordering::Relaxed);
    }
}

impl Drop for LiveBus {
    fn drop(&mut self) {
        self.flush_now();
        // What is still pending when the run's end is gone cannot be sent: count it.
        while let Some(b) = self.pending.pop_front() {
            self.count_drop(&b);
        }
    }
}

impl LiveFeed {
    /// The batches queued since the last call, and the drop counts (samples, batches).
    pub fn take_batches(&self) -> (Vec<Batch>, u64, u64) {
        let batches = match self.queue.batches.lock() {
            Ok(mut q) => q.drain(..).collect(),
            Err(p) => p.into_inner().drain(..).collect(),
        };
        (
            batches,
            self.queue.dropped_samples.load(Ordering::Relaxed),
            self.queue.dropped_batches.load(Ordering::Relaxed),
        )
    }

    /// The events sent since the last call.
    pub fn take_events(&self) -> Vec<Event> {
        self.events.try_iter().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_kilohertz_becomes_an_envelope_of_a_thousand_points_that_keeps_a_spike() {
        let (mut bus, feed) = channel(&["a_n", "b_m"]);
        for k in 0..10_000u32 {
            let t = f64::from(k) * 1e-4;
            let spike = if k == 4321 { 100.0 } else { 0.0 };
            bus.sample(t, &[t.sin() + spike, -t]);
        }
        bus.flush_now();
        let (batches, dropped, _) = feed.take_batches();
        assert_eq!(dropped, 0);
        let points: usize = batches.iter().map(|b| b.t_s.len()).sum();
        assert!((900..=1100).contains(&points), "{points}");
        let samples: u64 = batches.iter().map(|b| b.samples).sum();
        assert_eq!(samples, 10_000);
        // Rig time only goes forward, across batches too.
        let t: Vec<f64> = batches.iter().flat_map(|b| b.t_s.iter().copied()).collect();
        assert!(t.windows(2).all(|w| w[1] > w[0]), "time goes back");
        // 50 ms of rig time a batch.
        assert!((19..=21).contains(&batches.len()), "{}", batches.len());
        let max = batches
            .iter()
            .flat_map(|b| b.columns[0].iter().copied())
            .fold(f64::MIN, f64::max);
        assert!(max > 99.0, "the spike survives the reduction: {max}");
    }

    #[test]
    fn time_never_goes_back_when_a_batch_ends_inside_a_bin() {
        // Bins open at a sample's time and batches end 50 ms after their first sample: with
        // gaps in the stream (a free-running board's telemetry) a batch can end in the middle
        // of a bin, and the bin's points must still come before the next bin's.
        let (mut bus, feed) = channel(&["x"]);
        let mut t = -0.3713;
        for k in 0..20_000u32 {
            bus.sample(t, &[f64::from(k % 7)]);
            t += if k % 97 == 0 { 1.37e-3 } else { 1e-4 };
        }
        bus.flush_now();
        let (batches, dropped, _) = feed.take_batches();
        assert_eq!(dropped, 0);
        assert_eq!(batches.iter().map(|b| b.samples).sum::<u64>(), 20_000);
        let t: Vec<f64> = batches.iter().flat_map(|b| b.t_s.iter().copied()).collect();
        if let Some(k) = t.windows(2).position(|w| w[1] <= w[0]) {
            panic!("time goes back at point {k}: {:?}", &t[k..k + 2]);
        }
    }

    #[test]
    fn a_view_that_never_reads_loses_the_oldest_samples_counted_but_no_event() {
        let (mut bus, feed) = channel(&["x"]);
        for k in 0..300_000u32 {
            let t = f64::from(k) * 1e-4; // 30 s of rig time, three times the queue
            bus.sample(t, &[1.0]);
            if k % 10_000 == 0 {
                bus.event(Event::State {
                    t_s: t,
                    state: format!("s{k}"),
                });
            }
        }
        bus.flush_now();
        let (batches, dropped, dropped_batches) = feed.take_batches();
        assert_eq!(batches.len(), QUEUE_BATCHES);
        let kept: u64 = batches.iter().map(|b| b.samples).sum();
        assert_eq!(kept + dropped, 300_000, "every sample kept or counted");
        assert!(dropped_batches > 0);
        // The newest are kept.
        assert!(batches.last().unwrap().t_s.last().unwrap() > &29.9);
        assert_eq!(feed.take_events().len(), 30, "every event arrives");
    }

    #[test]
    fn the_run_never_waits_for_a_view_holding_the_lock() {
        let (mut bus, feed) = channel(&["x"]);
        let guard = feed.queue.batches.lock().unwrap();
        // The same thread holds the lock: a bus that waited for it would never return.
        for k in 0..20_000u32 {
            bus.sample(f64::from(k) * 1e-4, &[0.0]);
        }
        drop(guard);
        bus.flush_now();
        let (batches, dropped, _) = feed.take_batches();
        let kept: u64 = batches.iter().map(|b| b.samples).sum();
        assert_eq!(kept + dropped, 20_000);
    }
}
