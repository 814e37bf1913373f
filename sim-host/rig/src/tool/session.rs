//! One program (a sine jump, the slow intrusion, a replay) run on the controller, the same way
//! whichever link reaches it:
//!
//! - **Lockstep** (`--link sil|pil`): the host plays the rig. One sensor frame per control
//!   period from a [`Fixture`] (the robot on simulated sand, or the clamped intrusion fixture),
//!   one actuator frame back, applied to the fixture.
//! - **Free-running** (`--port PATH`): the board ticks on its own timer against the real rig;
//!   the host sends the same commands, keeps the watchdog fed with status queries and collects
//!   the sample batches it streams.
//!
//! Sequence in both: `Configure`, one Idle period, `Arm`, hold the start position for
//! `settle_s`, `Start`, run until the controller reports `Done` (then `tail_s` more) or a fault
//! (then [`POST_FAULT_PERIODS`]), never longer than `max_run_s` after the start.
//!
//! These times are the rig's: control periods in lockstep, the board's own ticks when it runs
//! free (a real board's ticks are real time; a virtual board's are its virtual time, however
//! slowly a busy machine runs it). The wall clock only catches a board whose tick stops
//! ([`STALLED_TICK`]).

use std::time::{Duration, Instant};

use crate::hil::rig_model::RigModel;
use crate::protocol::link::{LinkError, LinkReport, RigLink};
pub use crate::protocol::{bring_to_idle, query_status};
use sandjumper_core::protocol::FaultReport;
use sandjumper_core::{
    ActuatorFrame, Command, JumpConfig, RigState, SampleRecord, SensorFrame, Status,
};
use sandjumper_model::error::SimError;

/// Periods simulated after a fault is latched (the force stays zero).
pub const POST_FAULT_PERIODS: u64 = 20;
/// Free-running: how often the host asks for the status (also feeds the 500 ms watchdog).
pub const POLL_INTERVAL: Duration = Duration::from_millis(50);
/// Free-running: a board whose tick has not moved for this long (wall clock) while it answers
/// is hung.
pub const STALLED_TICK: Duration = Duration::from_secs(10);

/// What the host plays in lockstep: sensors for one period, then the actuator's outputs.
pub trait Fixture {
    /// The sensor frame for this period.
    fn sense(&mut self, frame: u32) -> SensorFrame;
    /// Apply the controller's outputs and advance one control period.
    fn actuate(&mut self, out: &ActuatorFrame) -> Result<(), SimError>;
    /// The plant as a live view shows it (`None`: a fixture with nothing more to show than
    /// the frames).
    fn plant(&self) -> Option<PlantView> {
        None
    }
}

/// What a live view shows of a simulated plant after a period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantView {
    /// Motor position relative to the rod, m.
    pub p_m: f64,
    /// Rod height above rest, m.
    pub rod_height_m: f64,
    /// Foot depth below the surface, m.
    pub depth_m: f64,
    /// Spring force, N.
    pub spring_force_n: f64,
}

/// One step of a program as a live view sees it.
#[derive(Clone, Copy, Debug)]
pub struct ProgramView<'a> {
    /// Rig time: periods (lockstep) or the board's ticks (free running) since `Start`, s
    /// (negative while armed before it).
    pub t_s: f64,
    /// The controller's state.
    pub state: RigState,
    /// Its latched fault.
    pub fault: Option<sandjumper_core::fault::FaultCode>,
    /// The controller's answer (lockstep).
    pub actuator: Option<&'a ActuatorFrame>,
    /// The sensor frame it answered (lockstep).
    pub sensor: Option<&'a SensorFrame>,
    /// The simulated plant (lockstep with a fixture that shows it).
    pub plant: Option<PlantView>,
    /// `Start` went out at this step.
    pub started: bool,
    /// Free running: the sample records the board streamed since the previous poll, with
    /// their rig time (s since `Start`, from the poll's `tick` and `run_tick`). Empty in
    /// lockstep (the actuator and sensor frames carry the period).
    pub board_samples: &'a [(f64, SampleRecord)],
}

impl Fixture for RigModel {
    fn sense(&mut self, frame: u32) -> SensorFrame {
        RigModel::sense(self, frame)
    }
    fn plant(&self) -> Option<PlantView> {
        let s = self.state();
        Some(PlantView {
            p_m: s.p,
            rod_height_m: self.rod_height_m(),
            depth_m: s.depth_m,
            spring_force_n: s.f_s,
        })
    }
    fn actuate(&mut self, out: &ActuatorFrame) -> Result<(), SimError> {
        RigModel::actuate(self, f64::from(out.force_n), out.drive_enabled, out.trigger)
    }
}

/// How to run one program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Program {
    /// What the controller runs.
    pub config: JumpConfig,
    /// Control rate, Hz.
    pub tick_hz: u32,
    /// Armed, holding the start position, before `Start`, s.
    pub settle_s: f64,
    /// Kept running after `Done`, s.
    pub tail_s: f64,
    /// Longest run after `Start` before the host gives up, s.
    pub max_run_s: f64,
}

impl Program {
    /// The program of one sine jump (docs/model.md section 2) as `rig jump` runs it: the jump's
    /// controller configuration, the spec's settle time, 0.5 s kept running after `Done`,
    /// and up to 5 s past the trajectory's end before the host gives up.
    /// `traj` is the jump's trajectory (`rig::hil::run::trajectory`).
    pub fn jump(
        params: &sandjumper_model::params::Params,
        spec: &crate::hil::run::HilSpec,
        traj: &sandjumper_core::trajectory::SineJump,
        tick_hz: u32,
    ) -> Self {
        Self {
            config: crate::hil::run::jump_config(params, spec),
            tick_hz,
            settle_s: spec.settle_s,
            tail_s: 0.5,
            max_run_s: traj.end_s() + 5.0,
        }
    }
}

/// What a run leaves behind.
#[derive(Debug, Default)]
pub struct RunRecord {
    /// The controller's sample records, in sequence order.
    pub samples: Vec<SampleRecord>,
    /// Faults reported.
    pub faults: Vec<FaultReport>,
    /// The link's closing report (final status, exit code).
    pub report: LinkReport,
    /// The controller reached `Done`.
    pub completed: bool,
    /// Control periods the host played (lockstep) or ticks the run took (board).
    pub periods: u64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
}

impl RunRecord {
    /// The first fault reported, if any.
    pub fn first_fault(&self) -> Option<FaultReport> {
        self.faults.first().copied()
    }
}

/// Run `program` through `link`. With a fixture the host plays the rig in lockstep; without
/// one the board runs free on its own rig.
pub fn run_program(
    link: &mut dyn RigLink,
    fixture: Option<&mut dyn Fixture>,
    program: &Program,
) -> Result<RunRecord, LinkError> {
    run_program_observed(link, fixture, program, None)
}

/// [`run_program`], calling `observe` after every lockstep period or status poll.
pub fn run_program_observed(
    link: &mut dyn RigLink,
    fixture: Option<&mut dyn Fixture>,
    program: &Program,
    observe: Option<&mut dyn FnMut(&ProgramView<'_>)>,
) -> Result<RunRecord, LinkError> {
    let wall = Instant::now();
    let mut nothing = |_: &ProgramView<'_>| {};
    let watched = observe.is_some();
    let observe: &mut dyn FnMut(&ProgramView<'_>) = match observe {
        Some(o) => o,
        None => &mut nothing,
    };
    bring_to_idle(link)?;
    link.command(&Command::Configure(program.config))?;
    let mut record = match fixture {
        Some(f) => lockstep(link, f, program, watched, observe)?,
        None => free_running(link, program, observe, STALLED_TICK)?,
    };
    record.report = link.finish()?;
    record.samples.extend(link.take_samples());
    record.samples.sort_by_key(|s| s.seq);
    record.samples.dedup_by_key(|s| s.seq);
    record.faults.extend(link.take_faults());
    record.wall_time_s = wall.elapsed().as_secs_f64();
    Ok(record)
}

fn lockstep(
    link: &mut dyn RigLink,
    fixture: &mut dyn Fixture,
    program: &Program,
    watched: bool,
    observe: &mut dyn FnMut(&ProgramView<'_>),
) -> Result<RunRecord, LinkError> {
    let hz = f64::from(program.tick_hz);
    let settle = ((program.settle_s * hz).round() as u64).max(1);
    let tail = (program.tail_s * hz).round() as u64;
    let cap = settle + (program.max_run_s * hz).ceil() as u64;
    let sim = |e: SimError| LinkError::Protocol(format!("the simulated rig failed: {e}"));
    let mut frame: u32 = 0;
    let mut step = |link: &mut dyn RigLink, fixture: &mut dyn Fixture| {
        let sensor = fixture.sense(frame);
        frame = frame.wrapping_add(1);
        let a = link.exchange(&sensor)?;
        if a.frame != sensor.frame {
            return Err(LinkError::Protocol(format!(
                "actuator frame {} answers sensor frame {}",
                a.frame, sensor.frame
            )));
        }
        fixture.actuate(&a).map_err(sim)?;
        Ok((a, sensor))
    };
    // One Idle period: the encoder's first reading is not a movement.
    step(link, fixture)?;
    let t = |period: u64| (period as f64 - settle as f64) / hz;
    link.command(&Command::Arm)?;
    let mut record = RunRecord::default();
    let mut stop_at: Option<u64> = None;
    let mut period = 1u64;
    loop {
        if period == settle {
            link.command(&Command::Start)?;
        }
        let (a, sensor) = step(link, fixture)?;
        // Without a view nothing is built for one.
        if watched {
            observe(&ProgramView {
                t_s: t(period),
                state: a.state,
                fault: a.fault,
                actuator: Some(&a),
                sensor: Some(&sensor),
                plant: fixture.plant(),
                started: period == settle,
                board_samples: &[],
            });
        }
        period += 1;
        if stop_at.is_none() {
            if a.fault.is_some() {
                stop_at = Some(period + POST_FAULT_PERIODS);
            } else if a.state == RigState::Done {
                record.completed = true;
                stop_at = Some(period + tail);
            }
        }
        if stop_at.is_some_and(|s| period >= s) {
            break;
        }
        if period > cap {
            return Err(LinkError::Protocol(format!(
                "the controller did not finish the program within {} s",
                program.max_run_s
            )));
        }
    }
    record.periods = period;
    Ok(record)
}

/// The board's time as its status polls show it: its ticks counted across the polls (after a
/// reset, which restarts the tick, on from the new count), and the wall time the tick last
/// moved.
struct BoardTime {
    hz: f64,
    /// The longest the tick may stand still, wall time.
    stalled: Duration,
    last_tick: Option<u32>,
    ticks: u64,
    moved_at: Instant,
}

impl BoardTime {
    fn new(hz: f64, stalled: Duration) -> Self {
        Self {
            hz,
            stalled,
            last_tick: None,
            ticks: 0,
            moved_at: Instant::now(),
        }
    }

    /// Count the ticks since the last poll; fail when the tick has stood still too long
    /// (`waiting_for`: what the host was waiting for).
    fn poll(&mut self, s: &Status, waiting_for: &str) -> Result<(), LinkError> {
        let now = Instant::now();
        let moved = match self.last_tick {
            None => 0,
            // A reset restarts the tick: the new count is the time since.
            Some(last) => match s.tick.wrapping_sub(last) as i32 {
                d if d >= 0 => d as u64,
                _ => u64::from(s.tick),
            },
        };
        if self.last_tick.is_none() || moved > 0 {
            self.moved_at = now;
        }
        self.last_tick = Some(s.tick);
        self.ticks += moved;
        let still = now.saturating_duration_since(self.moved_at);
        if still >= self.stalled {
            return Err(LinkError::Io {
                what: format!("waiting for {waiting_for}"),
                message: format!(
                    "the board's tick stood still at {} for {:.1} s of wall time (controller \
                     hung?)",
                    s.tick,
                    still.as_secs_f64()
                ),
            });
        }
        Ok(())
    }

    /// The board's time since `from_ticks`, s.
    fn since(&self, from_ticks: u64) -> f64 {
        self.ticks.saturating_sub(from_ticks) as f64 / self.hz
    }
}

/// A free-running board's program: `stalled` is how long its tick may stand still (wall time).
fn free_running(
    link: &mut dyn RigLink,
    program: &Program,
    observe: &mut dyn FnMut(&ProgramView<'_>),
    stalled: Duration,
) -> Result<RunRecord, LinkError> {
    let hz = f64::from(program.tick_hz);
    let mut clock = BoardTime::new(hz, stalled);
    // The samples the board streamed, taken at every poll so that a view sees them while the
    // run goes on; the record keeps them all.
    let mut streamed: Vec<SampleRecord> = Vec::new();
    let mut timed: Vec<(f64, SampleRecord)> = Vec::new();
    // The rig's time is the board's ticks since `Start`: the tick it started at is known from
    // the first poll with a run tick (`tick - run_tick`; the run tick stays 0 while armed and
    // stops at `Done`, so it is no clock of its own). Samples streamed before that wait, and
    // go to the view with the settle's negative times once it is known.
    let mut start_tick: Option<u32> = None;
    let mut pending: Vec<SampleRecord> = Vec::new();
    let mut seen = |link: &mut dyn RigLink, s: &Status, started: bool| {
        let fresh = link.take_samples();
        streamed.extend(fresh.iter().copied());
        if start_tick.is_none() && s.run_tick > 0 {
            start_tick = Some(s.tick.wrapping_sub(s.run_tick));
        }
        timed.clear();
        match start_tick {
            Some(t0) => {
                let at = |r: &SampleRecord| f64::from(r.tick.wrapping_sub(t0) as i32) / hz;
                timed.extend(pending.drain(..).map(|r| (at(&r), r)));
                timed.extend(fresh.into_iter().map(|r| (at(&r), r)));
            }
            None => pending.extend(fresh),
        }
        let t_s = start_tick.map_or(0.0, |t0| f64::from(s.tick.wrapping_sub(t0) as i32) / hz);
        observe(&ProgramView {
            t_s,
            state: s.state,
            fault: s.fault,
            actuator: None,
            sensor: None,
            plant: None,
            started,
            board_samples: &timed,
        });
    };
    // Polls until `seconds` of the board's time have passed (one poll for 0), for
    // `waiting_for`. `first_after_start`: this wait's first poll is the first after `Start`.
    let mut wait = |link: &mut dyn RigLink,
                    clock: &mut BoardTime,
                    seconds: f64,
                    waiting_for: &str,
                    first_after_start: bool|
     -> Result<Status, LinkError> {
        let mut status = query_status(link)?;
        clock.poll(&status, waiting_for)?;
        let from = clock.ticks;
        seen(link, &status, first_after_start);
        while clock.since(from) < seconds {
            std::thread::sleep(POLL_INTERVAL);
            status = query_status(link)?;
            clock.poll(&status, waiting_for)?;
            seen(link, &status, false);
        }
        Ok(status)
    };
    link.command(&Command::Arm)?;
    wait(
        link,
        &mut clock,
        program.settle_s,
        "the settle's end",
        false,
    )?;
    let start = query_status(link)?;
    clock.poll(&start, "the start")?;
    let started_at = clock.ticks;
    if let (RigState::Faulted, Some(fault)) = (start.state, start.fault) {
        return Err(LinkError::Protocol(format!(
            "the board latched {fault:?} at tick {} while armed, before the start",
            start.fault_tick
        )));
    }
    link.command(&Command::Start)?;
    let finish = "the board to finish the program";
    let mut record = RunRecord::default();
    let mut first = true;
    let last = loop {
        let s = wait(link, &mut clock, 0.0, finish, std::mem::take(&mut first))?;
        if s.state == RigState::Faulted {
            break s;
        }
        if s.state == RigState::Done {
            record.completed = true;
            break wait(link, &mut clock, program.tail_s, "the tail's end", false)?;
        }
        if clock.since(started_at) > program.max_run_s {
            let _ = link.command(&Command::Abort);
            return Err(LinkError::Timeout {
                waiting_for: format!("{finish} (counted in the board's ticks)"),
                seconds: program.max_run_s,
            });
        }
        std::thread::sleep(POLL_INTERVAL);
    };
    if last.state != RigState::Faulted {
        link.command(&Command::Abort)?;
    }
    record.periods = u64::from(last.tick.wrapping_sub(start.tick));
    record.samples = streamed;
    Ok(record)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_core::{JumpKind, Reply, Rig, RigConfig, TrajectorySpec};

    /// A free-running board that answers at once and whose tick moves `per_poll` ticks per
    /// status query (a board the machine runs slowly, or a fast one), finishing its program
    /// `run_ticks` after `Start`.
    struct PolledBoard {
        status: Status,
        per_poll: u32,
        run_ticks: u32,
        /// Its tick at `Arm`, `Start` and `Abort`.
        armed_at: Option<u32>,
        started_at: Option<u32>,
        aborted_at: Option<u32>,
    }

    /// A fresh controller's status (Idle).
    fn idle_status() -> Status {
        let rig: Rig = Rig::new(RigConfig::default()).expect("a rig");
        rig.status()
    }

    impl PolledBoard {
        fn new(per_poll: u32, run_ticks: u32) -> Self {
            let mut status = idle_status();
            status.tick = 1000;
            Self {
                status,
                per_poll,
                run_ticks,
                armed_at: None,
                started_at: None,
                aborted_at: None,
            }
        }
    }

    impl RigLink for PolledBoard {
        fn name(&self) -> String {
            "polled".into()
        }
        fn command(&mut self, command: &Command) -> Result<Reply, LinkError> {
            let s = &mut self.status;
            match command {
                Command::StatusQuery => {
                    s.tick = s.tick.wrapping_add(self.per_poll);
                    if let (RigState::Running, Some(t0)) = (s.state, self.started_at) {
                        s.run_tick = s.tick.wrapping_sub(t0);
                        if s.run_tick >= self.run_ticks {
                            s.state = RigState::Done;
                        }
                    }
                    return Ok(Reply::Status(*s));
                }
                Command::Arm => {
                    s.state = RigState::Armed;
                    self.armed_at = Some(s.tick);
                }
                Command::Start => {
                    s.state = RigState::Running;
                    self.started_at = Some(s.tick);
                }
                Command::Abort => {
                    s.state = RigState::Idle;
                    self.aborted_at = Some(s.tick);
                }
                _ => {}
            }
            Ok(Reply::Ack)
        }
        fn exchange(&mut self, _frame: &SensorFrame) -> Result<ActuatorFrame, LinkError> {
            Err(LinkError::Protocol("a free-running board".into()))
        }
        fn send_corrupted(&mut self, _frame: &SensorFrame) -> Result<(), LinkError> {
            Ok(())
        }
        fn silent_period(&mut self) -> Result<Option<ActuatorFrame>, LinkError> {
            Ok(None)
        }
        fn take_samples(&mut self) -> Vec<SampleRecord> {
            Vec::new()
        }
        fn take_faults(&mut self) -> Vec<FaultReport> {
            Vec::new()
        }
        fn finish(&mut self) -> Result<LinkReport, LinkError> {
            Ok(LinkReport::default())
        }
    }

    /// A 10 kHz program: `settle_s`, 1 ms of tail, `max_run_s`.
    fn program(settle_s: f64, max_run_s: f64) -> Program {
        Program {
            config: JumpConfig::new(TrajectorySpec::Sine {
                kind: JumpKind::Single,
                amplitude_m: 0.01,
                freq_hz: 10.0,
                tau_s: 0.0,
            }),
            tick_hz: 10_000,
            settle_s,
            tail_s: 0.001,
            max_run_s,
        }
    }

    fn run(
        board: &mut PolledBoard,
        p: &Program,
        stalled: Duration,
    ) -> Result<RunRecord, LinkError> {
        free_running(board, p, &mut |_| {}, stalled)
    }

    #[test]
    fn a_slow_boards_settle_and_deadline_are_counted_in_its_ticks() {
        // 5 ticks (0.5 ms) per 50 ms poll: 0.01x real time. The 3 ms program takes ~0.3 s of
        // wall time, far past its 10 ms deadline on the wall clock.
        let mut board = PolledBoard::new(5, 30);
        let wall = Instant::now();
        let record = run(&mut board, &program(0.002, 0.01), STALLED_TICK).expect("completes");
        assert!(record.completed);
        assert!(
            wall.elapsed() > Duration::from_millis(10),
            "{:?}",
            wall.elapsed()
        );
        let (armed, started) = (board.armed_at.unwrap(), board.started_at.unwrap());
        // Armed for the settle's 20 ticks, give or take a poll's.
        assert!(
            (20..=30).contains(&(started - armed)),
            "{armed} -> {started}"
        );
        // Done after 30 ticks, then the 10 ticks' tail.
        assert!((40..=55).contains(&record.periods), "{}", record.periods);
    }

    #[test]
    fn a_program_past_its_deadline_in_the_boards_ticks_is_aborted() {
        // 1000 ticks (0.1 s) per poll: the 0.5 s deadline passes in ~5 polls.
        let mut board = PolledBoard::new(1000, u32::MAX);
        let e = run(&mut board, &program(0.0, 0.5), STALLED_TICK).expect_err("never done");
        assert!(
            matches!(&e, LinkError::Timeout { seconds, .. } if *seconds == 0.5),
            "{e}"
        );
        assert!(
            e.to_string().contains("counted in the board's ticks"),
            "{e}"
        );
        let ran = board.aborted_at.unwrap() - board.started_at.unwrap();
        assert!((5000..=7000).contains(&ran), "aborted after {ran} ticks");
    }

    #[test]
    fn a_board_whose_tick_stands_still_is_reported_hung() {
        let mut board = PolledBoard::new(0, 30);
        let wall = Instant::now();
        let e = run(&mut board, &program(0.1, 1.0), Duration::from_millis(200))
            .expect_err("a stalled tick");
        let text = e.to_string();
        assert!(
            text.contains("waiting for the settle's end")
                && text.contains("tick stood still at 1000"),
            "{text}"
        );
        assert!(
            wall.elapsed() < Duration::from_secs(5),
            "{:?}",
            wall.elapsed()
        );
    }

    #[test]
    fn the_boards_time_counts_on_across_a_reset() {
        let mut t = BoardTime::new(10_000.0, STALLED_TICK);
        let mut s = idle_status();
        for tick in [100, 300, 50, 80] {
            s.tick = tick;
            t.poll(&s, "a test").expect("moving");
        }
        // 200 ticks, then 50 since the reset, then 30.
        assert_eq!(t.ticks, 280);
        assert!((t.since(200) - 0.008).abs() < 1e-12);
        // The tick wraps around without a jump.
        s.tick = u32::MAX - 5;
        t.poll(&s, "a test").expect("moving");
        let before = t.ticks;
        s.tick = 4;
        t.poll(&s, "a test").expect("moving");
        assert_eq!(t.ticks - before, 10);
    }
}
