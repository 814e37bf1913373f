//! What the page shows, gathered from the bus: the samples of the last [`WINDOW_S`] of rig
//! time, every event, the campaign's points, the drop counts. Served whole as `state.json`
//! and as a stream of what is new.

use std::collections::VecDeque;

use serde::Serialize;

use super::bus::{Batch, CampaignRecord, Event, LiveFeed};

/// Rig time the page's charts keep, s.
pub const WINDOW_S: f64 = 30.0;

/// The most events the state keeps (the newest; those dropped are counted): a `rig status
/// --watch` left running for days, or a long campaign, does not grow the page without
/// bound.
pub const MAX_EVENTS: usize = 2000;

/// The campaign as the page shows it.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CampaignView {
    /// The plan, one line.
    pub plan: String,
    /// Points in the plan.
    pub points: usize,
    /// The swept parameter's name.
    pub swept: Option<String>,
    /// Points done, failed.
    pub done: usize,
    /// Points failed.
    pub failed: usize,
    /// Every point record so far (history first on a resume).
    pub records: Vec<CampaignRecord>,
    /// The stop record's exit status, once stopped.
    pub exit_status: Option<i32>,
    /// The stop record's message.
    pub message: Option<String>,
}

/// Everything the page knows.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LiveState {
    /// What runs.
    pub title: String,
    /// Channel names, in column order.
    pub channels: Vec<String>,
    /// Rig time of each point in the window, s.
    pub t_s: VecDeque<f64>,
    /// The window's columns.
    pub columns: Vec<VecDeque<f64>>,
    /// Full-rate samples received.
    pub samples_received: u64,
    /// Full-rate samples dropped by the bus (queue full), and batches.
    pub samples_dropped: u64,
    /// Batches dropped.
    pub batches_dropped: u64,
    /// The newest [`MAX_EVENTS`] events (state transitions, faults, jump start and end, run
    /// start and end); campaign records are in [`LiveState::campaign`] only.
    pub events: VecDeque<Event>,
    /// Events dropped from [`LiveState::events`] (the oldest first).
    pub events_dropped: u64,
    /// The latest controller state.
    pub controller_state: Option<String>,
    /// The first fault, for the banner.
    pub fault: Option<String>,
    /// Whether the run has ended, and how.
    pub ended: Option<String>,
    /// The campaign, if this is one.
    pub campaign: Option<CampaignView>,
    /// The number of the last update folded in: a page applies only the streamed updates
    /// numbered above its snapshot's.
    pub seq: u64,
}

/// What is new since the last [`LiveState::absorb`], for the stream.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Update {
    /// Reduced samples.
    Batch {
        /// Its number (see [`LiveState::seq`]).
        seq: u64,
        /// The batch.
        batch: Batch,
        /// Samples and batches dropped so far.
        samples_dropped: u64,
        /// Batches dropped so far.
        batches_dropped: u64,
    },
    /// An event.
    Event {
        /// Its number.
        seq: u64,
        /// The event.
        event: Event,
    },
}

impl LiveState {
    /// An empty state for `feed`'s channels.
    pub fn new(feed: &LiveFeed) -> Self {
        Self {
            channels: feed.channels.clone(),
            columns: vec![VecDeque::new(); feed.channels.len()],
            ..Self::default()
        }
    }

    /// Take what the bus has, fold it in, and return it as updates.
    pub fn absorb(&mut self, feed: &LiveFeed) -> Vec<Update> {
        let mut out = Vec::new();
        let (batches, dropped, dropped_batches) = feed.take_batches();
        self.samples_dropped = dropped;
        self.batches_dropped = dropped_batches;
        for b in batches {
            self.samples_received += b.samples;
            for (k, &t) in b.t_s.iter().enumerate() {
                self.t_s.push_back(t);
                for (c, col) in self.columns.iter_mut().enumerate() {
                    col.push_back(
                        b.columns
                            .get(c)
                            .and_then(|v| v.get(k))
                            .copied()
                            .unwrap_or(f64::NAN),
                    );
                }
            }
            self.seq += 1;
            out.push(Update::Batch {
                seq: self.seq,
                batch: b,
                samples_dropped: dropped,
                batches_dropped: dropped_batches,
            });
        }
        if let Some(&last) = self.t_s.back() {
            while self.t_s.front().is_some_and(|&t| t < last - WINDOW_S) {
                self.t_s.pop_front();
                for col in &mut self.columns {
                    col.pop_front();
                }
            }
        }
        for e in feed.take_events() {
            self.apply(&e);
            self.seq += 1;
            out.push(Update::Event {
                seq: self.seq,
                event: e,
            });
        }
        out
    }

    fn apply(&mut self, e: &Event) {
        match e {
            Event::RunStarted { title, .. } => {
                self.title.clone_from(title);
                self.ended = None;
            }
            Event::State { state, .. } => self.controller_state = Some(state.clone()),
            Event::Fault { fault, .. } => {
                if self.fault.is_none() {
                    self.fault = Some(fault.clone());
                }
            }
            Event::Jump { .. } => {}
            Event::RunEnded { outcome, .. } => self.ended = Some(outcome.clone()),
            Event::Campaign(r) => {
                // Stored once, in the campaign's view.
                self.apply_campaign(r);
                return;
            }
        }
        self.events.push_back(e.clone());
        while self.events.len() > MAX_EVENTS {
            self.events.pop_front();
            self.events_dropped += 1;
        }
    }

    fn apply_campaign(&mut self, r: &CampaignRecord) {
        let c = self.campaign.get_or_insert_with(CampaignView::default);
        match r {
            CampaignRecord::Start {
                plan,
                points,
                swept,
                ..
            } => {
                c.plan.clone_from(plan);
                c.points = *points;
                c.swept.clone_from(swept);
                c.exit_status = None;
                c.message = None;
            }
            CampaignRecord::Point { status, .. } => {
                c.done += 1;
                if status != "ok" {
                    c.failed += 1;
                }
                c.records.push(r.clone());
            }
            CampaignRecord::Stop {
                exit_status,
                message,
            } => {
                c.exit_status = Some(*exit_status);
                c.message = Some(message.clone());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::channel;

    #[test]
    fn the_state_keeps_a_window_counts_points_and_shows_the_first_fault() {
        let (mut bus, feed) = channel(&["x"]);
        let mut st = LiveState::new(&feed);
        for k in 0..400_000u32 {
            bus.sample(f64::from(k) * 1e-4, &[1.0]);
            if k % 50_000 == 0 {
                st.absorb(&feed);
            }
        }
        bus.event(Event::Fault {
            t_s: 40.0,
            fault: "TrackingError".into(),
        });
        bus.event(Event::Fault {
            t_s: 40.1,
            fault: "Later".into(),
        });
        bus.event(Event::Campaign(CampaignRecord::Point {
            index: 0,
            params: vec![("freq_hz".into(), 10.0)],
            height_m: f64::NAN,
            status: "failed".into(),
            reason: Some("no bed".into()),
            history: false,
        }));
        bus.flush_now();
        st.absorb(&feed);
        assert_eq!(st.samples_received + st.samples_dropped, 400_000);
        let span = st.t_s.back().unwrap() - st.t_s.front().unwrap();
        assert!(span <= WINDOW_S && span > WINDOW_S - 1.0, "{span}");
        assert_eq!(st.fault.as_deref(), Some("TrackingError"));
        let c = st.campaign.as_ref().unwrap();
        assert_eq!((c.done, c.failed), (1, 1));
        // The campaign record is in the campaign's view only.
        assert_eq!(st.events.len(), 2);
        // Events are bounded, the dropped counted.
        for k in 0..MAX_EVENTS + 7 {
            bus.event(Event::State {
                t_s: 50.0 + k as f64,
                state: "Running".into(),
            });
        }
        bus.flush_now();
        st.absorb(&feed);
        assert_eq!(st.events.len(), MAX_EVENTS);
        assert_eq!(st.events_dropped, 9);
        // state.json holds NaN as null, not as invalid JSON.
        let json = serde_json::to_string(&st).unwrap();
        assert!(json.contains("\"height_m\":null"), "{json}");
    }
}
