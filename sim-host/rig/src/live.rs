//! A rig run on a live view ([`sandjumper_live`]): [`RigLiveView`] is the [`RunWatch`] that
//! puts every control period of a jump through the loop and every step of a rig program on
//! the view's bus (the [`JUMP_CHANNELS`] samples; jump start and end, state and fault
//! events), paced as the view says. Starting the view's server and keeping its page up after
//! the run are the caller's.

use sandjumper_core::RigState;
use sandjumper_core::fault::FaultCode;
use sandjumper_live::{Event, LiveBus, LiveView};
use sandjumper_output::parse::number_within;

use crate::hil::run::PeriodView;
use crate::tool::session::ProgramView;
use crate::watch::RunWatch;

/// The jump view's channels: commanded and measured motor position, rod height, foot
/// position, the drive's force command and the spring force.
pub const JUMP_CHANNELS: [&str; 6] = [
    "p_cmd_mm",
    "p_mm",
    "rod_height_mm",
    "foot_mm",
    "drive_force_n",
    "spring_force_n",
];

/// `--pace X`: a simulated run's pace on a live view, times real time (0: as fast as
/// possible, or 0.01..=1000).
pub fn parse_pace(s: &str) -> Result<f64, String> {
    number_within(s, |v| v == 0.0 || (0.01..=1000.0).contains(&v)).ok_or_else(|| {
        format!(
            "`{s}` is not a pace (allowed: 0, as fast as possible, or 0.01..=1000 times real time)"
        )
    })
}

/// `--linger S`: how long a live view's page stays up after the run, s (0..=86400).
pub fn parse_linger(s: &str) -> Result<f64, String> {
    number_within(s, |v| (0.0..=86_400.0).contains(&v))
        .ok_or_else(|| format!("`{s}` is not a linger time (allowed: 0..=86400 s)"))
}

/// A live view ([`sandjumper_live::LiveView`]: its bus, server and pacing) and the rig's
/// state as last shown.
pub struct RigLiveView {
    view: LiveView,
    last_state: Option<RigState>,
    fault_sent: bool,
}

impl RigLiveView {
    /// Show rig runs on `view`.
    pub fn new(view: LiveView) -> Self {
        Self {
            view,
            last_state: None,
            fault_sent: false,
        }
    }

    /// The view.
    pub fn view(&self) -> &LiveView {
        &self.view
    }

    /// The view, to change (e.g. [`LiveView::unpaced`] for a board keeping its own time).
    pub fn view_mut(&mut self) -> &mut LiveView {
        &mut self.view
    }

    /// The bus, for events of the caller's own.
    pub fn bus(&mut self) -> &mut LiveBus {
        self.view.bus()
    }

    /// The run is over at rig time `t_s`, s: send what is left, then `outcome` (ok or not).
    pub fn end(&mut self, t_s: f64, outcome: String, ok: bool) {
        self.view.end(t_s, outcome, ok);
    }

    fn jump_started(&mut self, t_s: f64) {
        self.bus().event(Event::Jump {
            t_s,
            phase: "start".into(),
        });
    }

    /// Events for a state (on change) and the first fault; names are formatted only then,
    /// not every control period.
    fn state_and_fault(&mut self, t: f64, state: RigState, fault: Option<FaultCode>) {
        if self.last_state != Some(state) {
            if state == RigState::Done {
                self.bus().event(Event::Jump {
                    t_s: t,
                    phase: "end".into(),
                });
            }
            self.bus().event(Event::State {
                t_s: t,
                state: format!("{state:?}"),
            });
            self.last_state = Some(state);
        }
        if let Some(f) = fault
            && !self.fault_sent
        {
            self.fault_sent = true;
            self.bus().event(Event::Fault {
                t_s: t,
                fault: format!("{f:?}"),
            });
        }
    }
}

impl RunWatch for RigLiveView {
    fn started(&mut self, title: &str, t_s: f64) {
        self.bus().event(Event::RunStarted {
            title: title.to_string(),
            t_s,
        });
    }

    /// One control period of a jump through the loop: its samples (mm, N), then the pace.
    fn period(&mut self, v: &PeriodView) {
        let r = &v.row;
        let t = r.t_s;
        if v.started {
            self.jump_started(t);
        }
        if let Some(st) = v.state {
            self.state_and_fault(t, st, v.fault);
        }
        let samples = [
            1e3 * v.p_ref_m,
            1e3 * r.p_m,
            1e3 * r.rod_height_m,
            -1e3 * r.depth_m,
            r.drive_command_n,
            r.spring_force_n,
        ];
        self.bus().sample(t, &samples);
        self.view.keep_pace(t);
    }

    /// One step of a `rig` program: a lockstep period (samples: the commanded position when
    /// the host knows it, the plant when simulated, else the encoder; the drive's command)
    /// or a free-running board's status poll (its state and faults, and the samples it
    /// streamed since the previous poll: commanded position, encoder, drive force).
    fn program(&mut self, v: &ProgramView<'_>, p_cmd_m: Option<f64>, metres_per_count: f64) {
        let t = v.t_s;
        if v.started {
            self.jump_started(t);
        }
        self.state_and_fault(t, v.state, v.fault);
        let nan = f64::NAN;
        for (ts, r) in v.board_samples {
            let encoder_m = r.encoder_count as f64 * metres_per_count;
            let p_cmd_mm = 1e3 * f64::from(r.commanded_position_m);
            let samples = [
                p_cmd_mm,
                1e3 * encoder_m,
                nan,
                nan,
                f64::from(r.force_n),
                nan,
            ];
            self.bus().sample(*ts, &samples);
        }
        let Some(a) = v.actuator else {
            return;
        };
        let encoder_m = v.sensor.map_or(nan, |s| {
            f64::from(s.encoder_count as i32) * metres_per_count
        });
        let (p, rod, foot, spring) = v.plant.map_or((encoder_m, nan, nan, nan), |pl| {
            (pl.p_m, pl.rod_height_m, -pl.depth_m, pl.spring_force_n)
        });
        let p_cmd = p_cmd_m.unwrap_or(nan);
        let samples = [
            1e3 * p_cmd,
            1e3 * p,
            1e3 * rod,
            1e3 * foot,
            f64::from(a.force_n),
            spring,
        ];
        self.bus().sample(t, &samples);
        self.view.keep_pace(t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pace_and_linger_say_what_is_allowed() {
        assert_eq!(parse_pace("0"), Ok(0.0));
        assert_eq!(parse_pace("2.5"), Ok(2.5));
        assert!(parse_pace("0.001").unwrap_err().contains("0.01..=1000"));
        assert_eq!(parse_linger("86400"), Ok(86_400.0));
        assert!(parse_linger("-1").unwrap_err().contains("0..=86400 s"));
    }
}
