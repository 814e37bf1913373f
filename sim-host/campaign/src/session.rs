//! A campaign session: `campaign run`, `resume` and `status` as calls.
//!
//! A campaign writes into `<out>.incomplete` and becomes `<out>` when its last point is
//! done: a folder named `<out>` is always a finished campaign. The journal
//! (`journal.jsonl`) is locked while a session runs, so two sessions cannot drive one
//! campaign; the lock dies with its process, so a killed session leaves nothing to clean.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::error::CampaignError;
use super::file::{CampaignFile, FailurePolicy};
use super::journal::{Event, Journal, read};
use super::plan::{Point, points};
use super::point::{Connect, Link, run_point, run_point_on_board};
use super::records::{State, write_documents, write_results};
use super::result_row::ResultRow;
use sandjumper_live::{CampaignRecord, LiveBus};
use sandjumper_output::{LockError, Progress, WriterLock};
use sandjumper_rig::hil::open::LinkArg;

/// `campaign run`: a new campaign from its file.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRequest {
    /// The campaign file (TOML).
    pub file: PathBuf,
    /// The controller, `sil` or `pil`, with the simulated bed (used when `port` is `None`).
    pub link: Option<String>,
    /// The rig's board on a serial port, with its bed apparatus.
    pub port: Option<PathBuf>,
    /// Firmware image for `pil`.
    pub firmware: PathBuf,
    /// Output folder (written as `<out>.incomplete` until the campaign finishes).
    pub out: PathBuf,
    /// End this session after this many points (the campaign stays resumable).
    pub stop_after: Option<usize>,
}

impl Default for RunRequest {
    fn default() -> Self {
        Self {
            file: PathBuf::new(),
            link: None,
            port: None,
            firmware: PathBuf::from(sandjumper_rig::firmware_image::EMULATED_ELF),
            out: PathBuf::new(),
            stop_after: None,
        }
    }
}

impl RunRequest {
    /// Refuse a link other than `sil` and `pil` (a board is `port`), a campaign file that
    /// cannot be read or does not fit the target, and an output that exists: everything a
    /// caller can be told before it starts anything (a live page, a link).
    pub fn validate(&self) -> Result<(), CampaignError> {
        match &self.port {
            Some(_) => {}
            None => {
                link_arg(self.link.as_deref().unwrap_or_default())?;
            }
        }
        let file = CampaignFile::read(&self.file).map_err(CampaignError::Input)?;
        if self.port.is_some() {
            file.check_for_board(&self.file.display().to_string())
                .map_err(CampaignError::Input)?;
        }
        let work = work_dir(&self.out);
        for d in [self.out.as_path(), work.as_path()] {
            if d.exists() {
                return Err(CampaignError::input(format!(
                    "--out {}: {} exists (allowed: a new folder; `campaign resume {}` carries on a stopped campaign)",
                    self.out.display(),
                    d.display(),
                    self.out.display()
                )));
            }
        }
        Ok(())
    }

    /// The journal's name of the link and where the jumps happen.
    fn target(&self) -> Result<(String, Target<'static>), CampaignError> {
        Ok(match &self.port {
            Some(port) => {
                let port = port.display().to_string();
                (format!("serial:{port}"), Target::Board(board_connect(port)))
            }
            None => {
                let name = self.link.clone().unwrap_or_default();
                let link = Link {
                    arg: link_arg(&name)?,
                    firmware: self.firmware.clone(),
                };
                (name, Target::Simulated(link))
            }
        })
    }
}

/// `campaign resume`: carry on a campaign that stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct ResumeRequest {
    /// The campaign's output folder (as given to `run`'s `out`).
    pub dir: PathBuf,
    /// Firmware image for a `pil` campaign.
    pub firmware: PathBuf,
    /// End this session after this many points.
    pub stop_after: Option<usize>,
}

impl Default for ResumeRequest {
    fn default() -> Self {
        Self {
            dir: PathBuf::new(),
            firmware: PathBuf::from(sandjumper_rig::firmware_image::EMULATED_ELF),
            stop_after: None,
        }
    }
}

/// `campaign status`: where a campaign stands, without disturbing it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StatusRequest {
    /// The campaign's output folder (as given to `run`'s `out`).
    pub dir: PathBuf,
}

/// Called with a point's row and its line of the table as the point is done.
pub type OnPoint<'a> = dyn FnMut(&ResultRow, &str) + 'a;

/// What a session reports besides its progress: the live view's bus and each point as it
/// is done. The default reports nowhere.
#[derive(Default)]
pub struct Hooks<'a> {
    /// The live view: the campaign's start, the points done before, each point as it is done.
    pub live: Option<&'a mut LiveBus>,
    /// Called with each point's row and its line of the table (the command line prints the
    /// line on stdout) as the point is done.
    pub on_point: Option<Box<OnPoint<'a>>>,
}

/// How a session ended without an error.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "ended", rename_all = "kebab-case")]
pub enum SessionOutcome {
    /// The session stopped after its `stop_after` points; the campaign is resumable.
    Stopped {
        /// Points done in this session.
        this_session: usize,
        /// Points done in all sessions.
        done: usize,
        /// Points of the campaign.
        total: usize,
        /// The campaign's output folder.
        out: PathBuf,
    },
    /// Every point is done and the folder has its final name.
    Finished {
        /// The campaign's name.
        name: String,
        /// Points done.
        done: usize,
        /// Points failed or faulted.
        failed: usize,
        /// Sessions (run and resumes).
        sessions: u32,
        /// Interruptions (points started again after a crash or kill).
        interruptions: u32,
        /// The finished campaign's folder.
        out: PathBuf,
    },
}

impl std::fmt::Display for SessionOutcome {
    /// The line the command line prints on stdout.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Stopped {
                this_session,
                done,
                total,
                out,
            } => write!(
                f,
                "campaign: stopped after {this_session} point(s) this session, {done} of {total} done; `campaign resume {}` carries on",
                out.display()
            ),
            Self::Finished {
                name,
                done,
                failed,
                sessions,
                interruptions,
                out,
            } => write!(
                f,
                "campaign {name}: {done} points done ({failed} failed or faulted) over {sessions} session(s), {interruptions} interruption(s); written to {}",
                out.display()
            ),
        }
    }
}

fn with_suffix(out: &Path, suffix: &str) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

fn work_dir(out: &Path) -> PathBuf {
    with_suffix(out, ".incomplete")
}

fn link_arg(name: &str) -> Result<LinkArg, CampaignError> {
    match name {
        "sil" => Ok(LinkArg::Sil),
        "pil" => Ok(LinkArg::Pil),
        _ => Err(CampaignError::input(format!(
            "--link {name} (allowed: sil, pil; a board is --port PATH)"
        ))),
    }
}

/// Lock the journal for this session (one session writes a campaign at a time).
fn lock(journal: &Path) -> Result<WriterLock, CampaignError> {
    WriterLock::take(journal).map_err(|e| match e {
        LockError::Held { holder, .. } => CampaignError::input(format!(
            "{} is being run by another session ({holder} holds its journal); `campaign status` \
             shows where it stands",
            journal.parent().unwrap_or(journal).display()
        )),
        LockError::Io { .. } => CampaignError::internal(e.to_string()),
    })
}

/// Run a new campaign: plan it from its file into `<out>.incomplete`, run its points (or
/// `stop_after` of them), and give the folder its name when the last is done.
pub fn run(
    request: &RunRequest,
    hooks: Hooks<'_>,
    progress: &dyn Progress,
) -> Result<SessionOutcome, CampaignError> {
    request.validate()?;
    let (link_name, mut target) = request.target()?;
    start(
        request,
        &link_name,
        &mut target,
        &mut Session { hooks, progress },
    )
}

/// Carry on the campaign in `request.dir`: the point a crash or kill interrupted starts
/// again from fluidization (said through `progress.note`).
pub fn resume(
    request: &ResumeRequest,
    hooks: Hooks<'_>,
    progress: &dyn Progress,
) -> Result<SessionOutcome, CampaignError> {
    let (file, work, journal, _lock, link_name) = reopen(&request.dir, progress)?;
    let mut target = match link_name.strip_prefix("serial:") {
        Some(port) => Target::Board(board_connect(port.to_string())),
        None => Target::Simulated(Link {
            arg: link_arg(&link_name)?,
            firmware: request.firmware.clone(),
        }),
    };
    let mut s = Session { hooks, progress };
    drive(
        &file,
        &mut target,
        &work,
        &request.dir,
        journal,
        request.stop_after,
        &mut s,
    )
}

/// Run the campaign file `request.file` on a board reached by `connect` (a fresh link per
/// point), into `request.out` (for boards that are not serial ports, e.g. a stand-in; the
/// request's `link`, `port` and `firmware` are not used).
pub fn run_on_board(
    request: &RunRequest,
    connect: Box<Connect<'_>>,
    hooks: Hooks<'_>,
    progress: &dyn Progress,
) -> Result<SessionOutcome, CampaignError> {
    start(
        request,
        "board",
        &mut Target::Board(connect),
        &mut Session { hooks, progress },
    )
}

/// Resume the campaign in `request.dir` on a board reached by `connect`.
pub fn resume_on_board(
    request: &ResumeRequest,
    connect: Box<Connect<'_>>,
    hooks: Hooks<'_>,
    progress: &dyn Progress,
) -> Result<SessionOutcome, CampaignError> {
    let (file, work, journal, _lock, _) = reopen(&request.dir, progress)?;
    drive(
        &file,
        &mut Target::Board(connect),
        &work,
        &request.dir,
        journal,
        request.stop_after,
        &mut Session { hooks, progress },
    )
}

/// Where the jumps happen.
enum Target<'a> {
    /// A simulated controller (sil, pil) with the simulated bed.
    Simulated(Link),
    /// A board with its own bed apparatus.
    Board(Box<Connect<'a>>),
}

/// What a session reports to.
struct Session<'a, 'p> {
    hooks: Hooks<'a>,
    progress: &'p dyn Progress,
}

impl Session<'_, '_> {
    fn live(&mut self, e: sandjumper_live::Event) {
        if let Some(bus) = self.hooks.live.as_deref_mut() {
            bus.event(e);
        }
    }
}

fn board_connect(port: String) -> Box<Connect<'static>> {
    Box::new(move || {
        sandjumper_rig::hil::serial::start(&port, std::time::Duration::from_secs(2))
            .map(|l| Box::new(l) as Box<dyn sandjumper_rig::hil::link::RigLink>)
            .map_err(|e| format!("cannot open the board on {port}: {e}"))
    })
}

/// Plan a new campaign from `request.file` into `request.out` and drive it.
fn start(
    request: &RunRequest,
    link_name: &str,
    target: &mut Target<'_>,
    session: &mut Session<'_, '_>,
) -> Result<SessionOutcome, CampaignError> {
    let (file_path, out) = (request.file.as_path(), request.out.as_path());
    let file = CampaignFile::read(file_path).map_err(CampaignError::Input)?;
    if matches!(target, Target::Board(_)) {
        file.check_for_board(&file_path.display().to_string())
            .map_err(CampaignError::Input)?;
    }
    // One session starts a campaign at a time: two started at once on one folder would
    // clear and rename each other's plan. The loser is told who holds it.
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| {
            CampaignError::input(format!(
                "--out {}: cannot create {}: {e}",
                out.display(),
                parent.display()
            ))
        })?;
    }
    let _start_lock = StartLock::take(out)?;
    let work = work_dir(out);
    for d in [out, work.as_path()] {
        if d.exists() {
            return Err(CampaignError::input(format!(
                "--out {}: {} exists (allowed: a new folder; `campaign resume {}` carries on a stopped campaign)",
                out.display(),
                d.display(),
                out.display()
            )));
        }
    }
    // The journal's lock is taken in the plan, before the folder gets its resumable name:
    // no `campaign resume` can take it in between. It holds the campaign from here.
    let _lock = plan(file_path, &file, out, &work, link_name)?;
    let jpath = work.join("journal.jsonl");
    let journal = Journal::open(&jpath).map_err(CampaignError::Internal)?;
    drive(
        &file,
        target,
        &work,
        out,
        journal,
        request.stop_after,
        session,
    )
}

/// The lock a session holds while it starts a campaign (`<out>.starting.lock`), removed
/// when the start is over, whether the campaign started or was refused: held when removed,
/// and [`WriterLock::take`] refuses a lock whose file was removed as it was taken.
struct StartLock {
    path: PathBuf,
    _lock: WriterLock,
}

impl StartLock {
    fn take(out: &Path) -> Result<Self, CampaignError> {
        let path = with_suffix(out, ".starting.lock");
        let lock = WriterLock::take_recorded(&path).map_err(|e| match e {
            LockError::Held { holder, .. } => CampaignError::input(format!(
                "--out {}: another session ({holder}) is starting a campaign there",
                out.display()
            )),
            LockError::Io { .. } => CampaignError::internal(e.to_string()),
        })?;
        Ok(Self { path, _lock: lock })
    }
}

impl Drop for StartLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Write the plan (the campaign file and the journal's first record) into `work`; the
/// journal's lock, taken before the folder is renamed to `work`.
fn plan(
    file_path: &Path,
    file: &CampaignFile,
    out: &Path,
    work: &Path,
    link_name: &str,
) -> Result<WriterLock, CampaignError> {
    // The folder takes its `.incomplete` name only once its plan is on the disk, so a
    // campaign killed at its very start leaves no folder that looks resumable.
    let starting = with_suffix(out, ".starting");
    if starting.exists() {
        std::fs::remove_dir_all(&starting).map_err(|e| {
            CampaignError::input(format!("cannot clear {}: {e}", starting.display()))
        })?;
    }
    std::fs::create_dir_all(starting.join("points"))
        .map_err(|e| CampaignError::input(format!("cannot create {}: {e}", starting.display())))?;
    let text = std::fs::read_to_string(file_path)
        .map_err(|e| CampaignError::input(format!("cannot read {}: {e}", file_path.display())))?;
    std::fs::write(starting.join("campaign.toml"), &text)
        .map_err(|e| CampaignError::internal(format!("cannot copy the campaign file: {e}")))?;
    {
        let mut journal =
            Journal::create(&starting.join("journal.jsonl")).map_err(CampaignError::Internal)?;
        journal
            .append(Event::Planned {
                name: file.name.clone(),
                file_text: text,
                points: points(file),
                link: link_name.to_string(),
            })
            .map_err(CampaignError::Internal)?;
    }
    // A lock is on the file, not its name: it goes with the rename.
    let journal_lock = lock(&starting.join("journal.jsonl"))?;
    std::fs::rename(&starting, work).map_err(|e| {
        CampaignError::internal(format!(
            "cannot rename {} to {}: {e}",
            starting.display(),
            work.display()
        ))
    })?;
    Ok(journal_lock)
}

/// A stopped campaign: its file, work folder, journal, the journal's lock and its link.
type Reopened = (CampaignFile, PathBuf, Journal, WriterLock, String);

/// A stopped campaign's file, work folder, journal (the point in progress recorded as
/// interrupted) and its lock.
fn reopen(dir: &Path, progress: &dyn Progress) -> Result<Reopened, CampaignError> {
    let work = work_dir(dir);
    if !work.is_dir() {
        return Err(CampaignError::Input(
            if dir.join("journal.jsonl").is_file() {
                format!(
                    "{}: the campaign is finished; nothing to resume",
                    dir.display()
                )
            } else {
                format!(
                    "{}: no stopped campaign here (no {}; allowed: the --out of a `campaign run`)",
                    dir.display(),
                    work.display()
                )
            },
        ));
    }
    let jpath = work.join("journal.jsonl");
    let lock = lock(&jpath)?;
    let mut journal = Journal::open(&jpath).map_err(CampaignError::Input)?;
    if journal.dropped_partial_bytes > 0 {
        progress.note(&format!(
            "campaign: dropped the journal's last line, cut by the crash ({} bytes)",
            journal.dropped_partial_bytes
        ));
    }
    let state = State::from_records(&journal.records).map_err(CampaignError::Input)?;
    let file = CampaignFile::parse(
        &state.file_text,
        &work.join("campaign.toml").display().to_string(),
    )
    .map_err(CampaignError::Input)?;
    if let Some((point, phase)) = &state.in_progress {
        progress.note(&format!(
            "campaign: point {point} was interrupted after `{phase}`; it starts again from fluidization"
        ));
        journal
            .append(Event::Interrupted {
                point: *point,
                phase: phase.clone(),
            })
            .map_err(CampaignError::Internal)?;
    }
    Ok((file, work, journal, lock, state.link))
}

/// The parameter a campaign's points sweep (the first of frequency, delay, packing fraction
/// that takes more than one value).
fn swept(points: &[Point]) -> Option<String> {
    let varies = |f: &dyn Fn(&Point) -> f64| points.iter().any(|p| f(p) != f(&points[0]));
    if points.is_empty() {
        None
    } else if varies(&|p| p.freq_hz) {
        Some("freq_hz".into())
    } else if varies(&|p| p.tau_s) {
        Some("tau_s".into())
    } else if varies(&|p| p.target_phi) {
        Some("target_phi".into())
    } else {
        None
    }
}

/// A result row as the live view's record.
fn point_record(row: &ResultRow, history: bool) -> sandjumper_live::Event {
    sandjumper_live::Event::Campaign(CampaignRecord::Point {
        index: row.point,
        params: vec![
            ("freq_hz".into(), row.freq_hz),
            ("tau_s".into(), row.tau_s),
            ("target_phi".into(), row.target_phi),
            ("achieved_phi".into(), row.achieved_phi),
        ],
        height_m: row_height(row).unwrap_or(f64::NAN),
        status: if row.status == "done" {
            "ok".into()
        } else {
            row.status.clone()
        },
        reason: (!row.faults.is_empty()).then(|| row.faults.clone()),
        history,
    })
}

/// The point's jump height, m: measured by the camera, else replayed, else the plant's.
fn row_height(row: &ResultRow) -> Option<f64> {
    row.measured_jump_height_m
        .or(row.predicted_jump_height_m)
        .or(row.plant_jump_height_m)
}

/// One line of the campaign's table (`total`: the campaign's points), as the command line
/// prints it on stdout when the point is done.
pub fn point_line(row: &ResultRow, total: usize) -> String {
    format!(
        "point {:>4}/{total}  {:<8} {:>6.2} Hz  tau {:>5.3} s  phi {:.4} -> {:.4}  {:<16} height {}{}",
        row.point + 1,
        row.kind,
        row.freq_hz,
        row.tau_s,
        row.target_phi,
        row.achieved_phi,
        row.status,
        row_height(row).map_or("-".to_string(), |h| format!("{:.2} mm", 1e3 * h)),
        if row.faults.is_empty() {
            String::new()
        } else {
            format!("  ({})", row.faults)
        }
    )
}

/// Bring `state` up to `journal` and rewrite `results.csv` and the Bluesky documents in
/// `work` from it.
fn refresh(
    state: &mut State,
    journal: &Journal,
    work: &Path,
    seed: u64,
) -> Result<(), CampaignError> {
    state
        .catch_up(&journal.records)
        .map_err(CampaignError::Internal)?;
    write_results(work, state).map_err(CampaignError::Internal)?;
    write_documents(work, state, seed).map_err(CampaignError::Internal)
}

/// Tell the live view where the campaign stands: its plan and the points done before.
fn announce(state: &State, session: &mut Session<'_, '_>) {
    if session.hooks.live.is_none() {
        return;
    }
    session.live(sandjumper_live::Event::RunStarted {
        title: format!("campaign {}", state.name),
        t_s: 0.0,
    });
    session.live(sandjumper_live::Event::Campaign(CampaignRecord::Start {
        plan: format!(
            "{}: {} points on {}",
            state.name,
            state.points.len(),
            state.link
        ),
        points: state.points.len(),
        swept: swept(&state.points),
        done_before: state.done(),
    }));
    for row in state.rows.values() {
        session.live(point_record(row, true));
    }
}

/// Run one point through `target`.
fn run_one(
    file: &CampaignFile,
    point: &Point,
    target: &mut Target<'_>,
    work: &Path,
    journal: &mut Journal,
) -> Result<ResultRow, CampaignError> {
    let mut on_phase = |_: &str| {};
    match target {
        Target::Simulated(link) => run_point(file, point, link, work, journal, &mut on_phase),
        Target::Board(connect) => {
            run_point_on_board(file, point, connect.as_mut(), work, journal, &mut on_phase)
        }
    }
    .map_err(CampaignError::Input)
}

/// Run the points not done yet, then finish the campaign.
fn drive(
    file: &CampaignFile,
    target: &mut Target<'_>,
    work: &Path,
    out: &Path,
    mut journal: Journal,
    stop_after: Option<usize>,
    session: &mut Session<'_, '_>,
) -> Result<SessionOutcome, CampaignError> {
    let mut state = State::from_records(&journal.records).map_err(CampaignError::Internal)?;
    announce(&state, session);
    journal
        .append(Event::SessionStarted {
            session: state.sessions + 1,
        })
        .map_err(CampaignError::Internal)?;
    let total = state.points.len();
    let progress = session.progress;
    progress.start("points", Some(total as u64));
    progress.advance(state.done() as u64);
    let mut this_session = 0usize;
    loop {
        refresh(&mut state, &journal, work, file.seed)?;
        let Some(point) = state.next_point().cloned() else {
            break;
        };
        // Asked to stop after N points, or stopped by the caller (Ctrl-C): the journal holds
        // every point done, and `resume` goes on from the next.
        if stop_after.is_some_and(|n| this_session >= n) || progress.cancelled() {
            progress.finish();
            return Ok(SessionOutcome::Stopped {
                this_session,
                done: state.done(),
                total,
                out: out.to_path_buf(),
            });
        }
        let row = run_one(file, &point, target, work, &mut journal)?;
        let failed = row.status == "bed-not-prepared";
        if let Some(on_point) = session.hooks.on_point.as_mut() {
            on_point(&row, &point_line(&row, total));
        }
        session.live(point_record(&row, false));
        journal
            .append(Event::Done { row })
            .map_err(CampaignError::Internal)?;
        this_session += 1;
        progress.advance(1);
        if failed && file.on_failed_preparation == FailurePolicy::Stop {
            refresh(&mut state, &journal, work, file.seed)?;
            progress.finish();
            return Err(CampaignError::internal(format!(
                "campaign: point {} failed its bed preparation and the campaign's policy is `stop`; the failure is recorded, `campaign resume {}` goes on with the next point",
                point.index,
                out.display()
            )));
        }
    }
    progress.finish();
    conclude(file, state, journal, work, out)
}

/// Every point is done: journal the end, write the figure and give the folder its name.
fn conclude(
    file: &CampaignFile,
    mut state: State,
    mut journal: Journal,
    work: &Path,
    out: &Path,
) -> Result<SessionOutcome, CampaignError> {
    state
        .catch_up(&journal.records)
        .map_err(CampaignError::Internal)?;
    if state.finished.is_none() {
        journal
            .append(Event::Finished {
                exit_status: "success".into(),
                reason: String::new(),
            })
            .map_err(CampaignError::Internal)?;
    }
    refresh(&mut state, &journal, work, file.seed)?;
    super::figure::write(work, &state).map_err(CampaignError::Internal)?;
    drop(journal);
    std::fs::rename(work, out).map_err(|e| {
        CampaignError::internal(format!(
            "cannot rename {} to {}: {e}",
            work.display(),
            out.display()
        ))
    })?;
    Ok(SessionOutcome::Finished {
        name: state.name.clone(),
        done: state.done(),
        failed: state.rows.values().filter(|r| r.status != "done").count(),
        sessions: state.sessions,
        interruptions: state.interruptions,
        out: out.to_path_buf(),
    })
}

/// Where a campaign stands (`campaign status --json` prints it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StatusReport {
    /// The folder asked about.
    pub dir: String,
    /// The campaign's name.
    pub name: String,
    /// Its link: `sil`, `pil`, `serial:PORT` or `board`.
    pub link: String,
    /// `finished`, `running` or `stopped (resumable)`.
    pub state: String,
    /// Points of the campaign.
    pub points: usize,
    /// Points done.
    pub done: usize,
    /// Points failed or faulted.
    pub failed: usize,
    /// The point in progress and its last phase.
    pub in_progress: Option<(usize, String)>,
    /// Sessions (run and resumes).
    pub sessions: u32,
    /// Interruptions.
    pub interruptions: u32,
    /// Bytes of a journal line cut by a crash (dropped when the campaign resumes).
    pub dropped_partial_journal_bytes: usize,
}

impl std::fmt::Display for StatusReport {
    /// The line `campaign status` prints without `--json`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "campaign {} ({}): {}; {} of {} points done, {} failed or faulted; {} session(s), {} interruption(s){}",
            self.name,
            self.link,
            self.state,
            self.done,
            self.points,
            self.failed,
            self.sessions,
            self.interruptions,
            self.in_progress
                .as_ref()
                .map(|(p, ph)| format!("; point {p} at `{ph}`"))
                .unwrap_or_default()
        )
    }
}

/// Refuse a live view's pace (`--pace`, a speed factor): a campaign's points are not paced,
/// each is shown when it is done.
pub fn check_pace(pace: Option<f64>) -> Result<(), CampaignError> {
    match pace {
        Some(p) => Err(CampaignError::input(format!(
            "--pace {p}: a campaign's points are not paced, each is shown when it is done (allowed: --live and --linger only)"
        ))),
        None => Ok(()),
    }
}

/// The live view's last event of a session: how it ended (exit status 0: normally) and why.
pub fn stop_event(exit_status: i32, message: String) -> sandjumper_live::Event {
    sandjumper_live::Event::Campaign(CampaignRecord::Stop {
        exit_status,
        message,
    })
}

impl StatusReport {
    /// What `campaign status --json` prints (pretty-printed JSON).
    pub fn json(&self) -> Result<String, CampaignError> {
        serde_json::to_string_pretty(self).map_err(CampaignError::internal)
    }
}

/// Where the campaign in `request.dir` stands, read without disturbing a session that runs it.
pub fn status(request: &StatusRequest) -> Result<StatusReport, CampaignError> {
    let work = work_dir(&request.dir);
    let (dir, finished_dir) = if work.is_dir() {
        (work, false)
    } else {
        (request.dir.clone(), true)
    };
    let jpath = dir.join("journal.jsonl");
    if !jpath.is_file() {
        return Err(CampaignError::input(format!(
            "{}: no campaign here (no journal.jsonl in it or in {}.incomplete)",
            request.dir.display(),
            request.dir.display()
        )));
    }
    let (records, dropped) = read(&jpath).map_err(CampaignError::Input)?;
    let st = State::from_records(&records).map_err(CampaignError::Input)?;
    let running = WriterLock::is_held(&jpath);
    let state = if finished_dir {
        "finished"
    } else if running {
        "running"
    } else {
        "stopped (resumable)"
    };
    Ok(StatusReport {
        dir: request.dir.display().to_string(),
        name: st.name.clone(),
        link: st.link.clone(),
        state: state.to_string(),
        points: st.points.len(),
        done: st.done(),
        failed: st.rows.values().filter(|r| r.status != "done").count(),
        in_progress: st.in_progress.clone(),
        sessions: st.sessions,
        interruptions: st.interruptions,
        dropped_partial_journal_bytes: dropped,
    })
}
