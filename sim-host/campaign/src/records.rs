//! What a campaign's journal adds up to: its state (for `resume` and `status`), the rows of
//! `results.csv`, and the run as Bluesky event-model documents (`documents.jsonl`).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::journal::{Event, Record};
use super::plan::Point;
use sandjumper_output::write_csv;

pub use super::result_row::ResultRow;

/// `results.csv`'s columns (written as the header when no point is done yet).
pub const RESULT_HEADER: &[&str] = &[
    "point",
    "repeat",
    "kind",
    "freq_hz",
    "tau_s",
    "target_phi",
    "achieved_phi",
    "attempts",
    "fluidizations",
    "doses",
    "status",
    "measured_jump_height_m",
    "frames_flagged",
    "predicted_jump_height_m",
    "plant_jump_height_m",
    "faults",
    "folder",
];

/// Where a campaign stands, from its journal.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct State {
    /// Campaign name.
    pub name: String,
    /// Link.
    pub link: String,
    /// The campaign file's text.
    #[serde(skip)]
    pub file_text: String,
    /// Points in run order.
    #[serde(skip)]
    pub points: Vec<Point>,
    /// Rows of the points done, by point.
    #[serde(skip)]
    pub rows: BTreeMap<usize, ResultRow>,
    /// When each point was done, s since the epoch.
    #[serde(skip)]
    pub done_times: BTreeMap<usize, f64>,
    /// The point in progress and its last phase, if any.
    pub in_progress: Option<(usize, String)>,
    /// Sessions so far (1: never resumed).
    pub sessions: u32,
    /// Points interrupted by the end of a session.
    pub interruptions: u32,
    /// How it ended, if it did: (exit status, reason).
    pub finished: Option<(String, String)>,
    /// Time of the first record, s since the epoch.
    pub start_time: f64,
    /// Time of the last record.
    pub last_time: f64,
    /// Records of the journal replayed so far.
    #[serde(skip)]
    pub applied: usize,
}

impl State {
    /// Replay the journal.
    pub fn from_records(records: &[Record]) -> Result<Self, String> {
        let mut s = State::default();
        s.catch_up(records)?;
        Ok(s)
    }

    /// Replay the records of `records` (the same journal, grown since) not replayed yet:
    /// a long campaign does not replay its whole journal after every point.
    pub fn catch_up(&mut self, records: &[Record]) -> Result<(), String> {
        let Some(first) = records.first() else {
            return Err("the journal is empty (the campaign never started)".into());
        };
        if self.applied == 0 {
            self.start_time = first.time;
        }
        let s = self;
        for r in records.get(s.applied..).unwrap_or_default() {
            s.last_time = r.time;
            match &r.event {
                Event::Planned {
                    name,
                    file_text,
                    points,
                    link,
                } => {
                    s.name = name.clone();
                    s.file_text = file_text.clone();
                    s.points = points.clone();
                    s.link = link.clone();
                }
                Event::SessionStarted { session } => s.sessions = *session,
                Event::PointStarted { point } => {
                    s.in_progress = Some((*point, "started".into()));
                }
                Event::BedPrepared { point, .. } => {
                    s.in_progress = Some((*point, "bed-prepared".into()));
                }
                Event::Jumped { point } => s.in_progress = Some((*point, "jumped".into())),
                Event::Analysed { point } => s.in_progress = Some((*point, "analysed".into())),
                Event::Done { row } => {
                    s.rows.insert(row.point, row.clone());
                    s.done_times.insert(row.point, r.time);
                    s.in_progress = None;
                }
                Event::Interrupted { .. } => {
                    s.interruptions += 1;
                    s.in_progress = None;
                }
                Event::Finished {
                    exit_status,
                    reason,
                } => s.finished = Some((exit_status.clone(), reason.clone())),
            }
        }
        s.applied = s.applied.max(records.len());
        if s.points.is_empty() {
            return Err("the journal has no plan (its first record must be `planned`)".into());
        }
        Ok(())
    }

    /// The next point to run (the first not done), if any.
    pub fn next_point(&self) -> Option<&Point> {
        self.points
            .iter()
            .find(|p| !self.rows.contains_key(&p.index))
    }

    /// Jumps done (including recorded failures).
    pub fn done(&self) -> usize {
        self.rows.len()
    }
}

/// Write `results.csv` (one row per point done, in point order) atomically.
pub fn write_results(dir: &Path, state: &State) -> Result<(), String> {
    let tmp = dir.join("results.csv.tmp");
    let rows: Vec<&ResultRow> = state.rows.values().collect();
    write_csv(&tmp, &rows, RESULT_HEADER)?;
    std::fs::rename(&tmp, dir.join("results.csv"))
        .map_err(|e| format!("cannot write results.csv: {e}"))
}

/// A UUID-shaped identifier from `seed` and `what` (stable across resumes).
fn uid(seed: u64, what: &str) -> String {
    let mut h: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d ^ u128::from(seed);
    for b in what.bytes() {
        h ^= u128::from(b);
        h = h.wrapping_mul(0x0000_0000_0100_0000_0000_0000_0000_013b);
    }
    let x = format!("{h:032x}");
    format!(
        "{}-{}-4{}-a{}-{}",
        &x[0..8],
        &x[8..12],
        &x[13..16],
        &x[17..20],
        &x[20..32]
    )
}

/// The event-model documents of the run so far, as `[name, document]` pairs: one `start`,
/// one `descriptor` (stream `primary`, with units), an `event` per jump done, and a `stop`
/// once the campaign ended.
pub fn documents(state: &State, seed: u64) -> Vec<serde_json::Value> {
    use serde_json::json;
    let start_uid = uid(seed, &format!("start/{}/{}", state.name, state.start_time));
    let desc_uid = uid(seed, &format!("descriptor/{start_uid}"));
    let mut out = vec![json!(["start", {
        "uid": start_uid,
        "time": state.start_time,
        "scan_id": 1,
        "plan_name": "sandjumper campaign",
        "campaign": state.name,
        "link": state.link,
        "num_points": state.points.len(),
        "sessions": state.sessions,
        "versions": {"sandjumper": env!("CARGO_PKG_VERSION")},
    }])];
    let key = |dtype: &str, units: Option<&str>, source: &str| {
        let mut k = json!({"dtype": dtype, "shape": [], "source": source});
        if let Some(u) = units {
            k["units"] = json!(u);
        }
        k
    };
    out.push(json!(["descriptor", {
        "uid": desc_uid,
        "time": state.start_time,
        "run_start": start_uid,
        "name": "primary",
        "data_keys": {
            "point": key("integer", None, "campaign plan"),
            "repeat": key("integer", None, "campaign plan"),
            "kind": key("string", None, "campaign plan"),
            "freq_hz": key("number", Some("Hz"), "campaign plan"),
            "tau_s": key("number", Some("s"), "campaign plan"),
            "target_phi": key("number", Some("dimensionless"), "campaign plan"),
            "achieved_phi": key("number", Some("dimensionless"), "bed height sensor"),
            "attempts": key("integer", None, "bed preparation"),
            "status": key("string", None, "campaign"),
            "measured_jump_height_m": key("number", Some("m"), "rod camera (tracked)"),
            "frames_flagged": key("integer", None, "rod camera (tracked)"),
            "predicted_jump_height_m": key("number", Some("m"), "encoder log replayed in the simulator"),
            "faults": key("string", None, "controller"),
            "folder": key("string", None, "campaign"),
        },
        "object_keys": {},
        "configuration": {},
        "hints": {"fields": ["measured_jump_height_m", "predicted_jump_height_m"]},
    }]));
    for (k, row) in state.rows.values().enumerate() {
        let t = state
            .done_times
            .get(&row.point)
            .copied()
            .unwrap_or(state.last_time);
        let nan = |v: Option<f64>| v.map_or(json!(null), |x| json!(x));
        let data = json!({
            "point": row.point,
            "repeat": row.repeat,
            "kind": row.kind,
            "freq_hz": row.freq_hz,
            "tau_s": row.tau_s,
            "target_phi": row.target_phi,
            "achieved_phi": row.achieved_phi,
            "attempts": row.attempts,
            "status": row.status,
            "measured_jump_height_m": nan(row.measured_jump_height_m),
            "frames_flagged": row.frames_flagged.map_or(json!(null), |n| json!(n)),
            "predicted_jump_height_m": nan(row.predicted_jump_height_m),
            "faults": row.faults,
            "folder": row.folder,
        });
        let stamps: serde_json::Map<String, serde_json::Value> = data
            .as_object()
            .map(|m| m.keys().map(|k| (k.clone(), json!(t))).collect())
            .unwrap_or_default();
        out.push(json!(["event", {
            "uid": uid(seed, &format!("event/{start_uid}/{}", row.point)),
            "time": t,
            "descriptor": desc_uid,
            "seq_num": k + 1,
            "data": data,
            "timestamps": stamps,
            "filled": {},
        }]));
    }
    if let Some((status, reason)) = &state.finished {
        out.push(json!(["stop", {
            "uid": uid(seed, &format!("stop/{start_uid}")),
            "time": state.last_time,
            "run_start": start_uid,
            "exit_status": status,
            "reason": reason,
            "num_events": {"primary": state.rows.len()},
        }]));
    }
    out
}

/// Write `documents.jsonl` (one `[name, document]` per line) atomically.
pub fn write_documents(dir: &Path, state: &State, seed: u64) -> Result<(), String> {
    let mut text = String::new();
    for d in documents(state, seed) {
        text.push_str(&d.to_string());
        text.push('\n');
    }
    let tmp = dir.join("documents.jsonl.tmp");
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, dir.join("documents.jsonl")))
        .map_err(|e| format!("cannot write documents.jsonl: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::journal::{Event, Record};
    use crate::plan::Point;

    fn point(index: usize) -> Point {
        Point {
            index,
            kind: "single".into(),
            freq_hz: 10.0 + index as f64,
            tau_s: 0.0,
            target_phi: 0.58,
            repeat: 0,
        }
    }

    fn row(index: usize) -> ResultRow {
        let p = point(index);
        ResultRow {
            point: index,
            repeat: 0,
            kind: "single".into(),
            freq_hz: p.freq_hz,
            tau_s: 0.0,
            target_phi: 0.58,
            achieved_phi: 0.5801,
            attempts: 1,
            fluidizations: 1,
            doses: 3,
            status: "ok".into(),
            measured_jump_height_m: Some(0.01 * index as f64),
            frames_flagged: Some(0),
            predicted_jump_height_m: None,
            plant_jump_height_m: None,
            faults: String::new(),
            folder: p.folder(),
        }
    }

    #[test]
    fn catching_up_record_by_record_equals_replaying_the_whole_journal() {
        let mut events = vec![
            Event::Planned {
                name: "c".into(),
                file_text: "name = \"c\"".into(),
                points: (0..3).map(point).collect(),
                link: "sil".into(),
            },
            Event::SessionStarted { session: 1 },
        ];
        for p in 0..2 {
            events.push(Event::PointStarted { point: p });
            events.push(Event::Jumped { point: p });
            events.push(Event::Done { row: row(p) });
        }
        events.push(Event::PointStarted { point: 2 });
        events.push(Event::Interrupted {
            point: 2,
            phase: "started".into(),
        });
        events.push(Event::SessionStarted { session: 2 });
        let records: Vec<Record> = events
            .into_iter()
            .enumerate()
            .map(|(k, event)| Record {
                seq: k as u64,
                time: 100.0 + k as f64,
                event,
            })
            .collect();
        let whole = State::from_records(&records).unwrap();
        assert_eq!(whole.done(), 2);
        assert_eq!(whole.sessions, 2);
        assert_eq!(whole.interruptions, 1);
        assert_eq!(whole.next_point().map(|p| p.index), Some(2));
        // Grown one record at a time, as `campaign run` appends them.
        let mut grown = State::from_records(&records[..1]).unwrap();
        for n in 2..=records.len() {
            grown.catch_up(&records[..n]).unwrap();
        }
        assert_eq!(grown, whole);
        // Nothing new: nothing changes.
        grown.catch_up(&records).unwrap();
        assert_eq!(grown, whole);
    }
}
