//! `sandjumper campaign run|resume|status`.
//!
//! A campaign writes into `<out>.incomplete` and becomes `<out>` when its last point is
//! done: a folder named `<out>` is always a finished campaign. The journal
//! (`journal.jsonl`) is locked while a session runs, so two sessions cannot drive one
//! campaign; the lock dies with its process, so a killed session leaves nothing to clean.

use std::fs::File;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use serde::Serialize;

use super::file::{CampaignFile, FailurePolicy};
use super::journal::{Event, Journal, read};
use super::plan::points;
use super::point::{Connect, Link, run_point, run_point_on_board};
use super::records::{State, write_documents, write_results};
use crate::rig::hil::command::LinkArg;
use sandjumper_output::CliError;

/// `campaign`.
#[derive(Args, Debug)]
pub struct CampaignArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: CampaignCommand,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum CampaignCommand {
    /// Run a campaign file: for each point prepare the bed, jump, record, analyse.
    Run(RunArgs),
    /// Carry on a campaign that stopped (crash, kill, power cut, `--stop-after`).
    Resume(ResumeArgs),
    /// Where a campaign stands, without disturbing it.
    Status(StatusArgs),
}

/// `campaign run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// The campaign file (TOML).
    pub file: PathBuf,
    /// The controller: `sil` (the core in this process) or `pil` (the firmware in QEMU),
    /// with the simulated bed.
    #[arg(
        long,
        value_name = "sil|pil",
        conflicts_with = "port",
        required_unless_present = "port"
    )]
    pub link: Option<String>,
    /// The rig's board on a serial port, with its bed apparatus (needs `[bed.height_sensor]`;
    /// tracking needs `camera.capture_dir`, where the lab's camera writes the frames).
    #[arg(long, value_name = "PATH")]
    pub port: Option<PathBuf>,
    /// Firmware image for `--link pil`.
    #[arg(long, value_name = "ELF", default_value = sandjumper_rig::firmware_image::EMULATED_ELF)]
    pub firmware: PathBuf,
    /// Output folder (written as `<out>.incomplete` until the campaign finishes).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// End this session after N points (the campaign stays resumable).
    #[arg(long, value_name = "N")]
    pub stop_after: Option<usize>,
    /// The live view of the campaign.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
}

/// `campaign resume`.
#[derive(Args, Debug)]
pub struct ResumeArgs {
    /// The campaign's output folder (as given to `run --out`).
    pub dir: PathBuf,
    /// Firmware image for a `pil` campaign.
    #[arg(long, value_name = "ELF", default_value = sandjumper_rig::firmware_image::EMULATED_ELF)]
    pub firmware: PathBuf,
    /// End this session after N points.
    #[arg(long, value_name = "N")]
    pub stop_after: Option<usize>,
    /// The live view of the campaign (its history first).
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
}

/// `campaign status`.
#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The campaign's output folder (as given to `run --out`).
    pub dir: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Run `campaign`.
pub fn run(a: &CampaignArgs) -> Result<(), CliError> {
    match &a.command {
        CampaignCommand::Run(r) => run_new(r),
        CampaignCommand::Resume(r) => resume(r),
        CampaignCommand::Status(s) => status(s),
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

fn link_arg(name: &str) -> Result<LinkArg, CliError> {
    match name {
        "sil" => Ok(LinkArg::Sil),
        "pil" => Ok(LinkArg::Pil),
        _ => Err(CliError::input(format!(
            "--link {name} (allowed: sil, pil; a board is --port PATH)"
        ))),
    }
}

/// Lock the journal for this session.
fn lock(journal: &Path) -> Result<File, CliError> {
    let f = File::open(journal)
        .map_err(|e| CliError::input(format!("cannot open {}: {e}", journal.display())))?;
    match f.try_lock() {
        Ok(()) => Ok(f),
        Err(std::fs::TryLockError::WouldBlock) => Err(CliError::input(format!(
            "{} is being run by another session (its journal is locked); `campaign status` shows where it stands",
            journal.parent().unwrap_or(journal).display()
        ))),
        Err(std::fs::TryLockError::Error(e)) => Err(CliError::internal(format!(
            "cannot lock {}: {e}",
            journal.display()
        ))),
    }
}

fn run_new(a: &RunArgs) -> Result<(), CliError> {
    let (link_name, mut target) = match &a.port {
        Some(port) => {
            let port = port.display().to_string();
            (format!("serial:{port}"), Target::Board(board_connect(port)))
        }
        None => {
            let name = a.link.clone().unwrap_or_default();
            let link = Link {
                arg: link_arg(&name)?,
                firmware: a.firmware.clone(),
            };
            (name, Target::Simulated(link))
        }
    };
    refuse_pace(&a.live)?;
    let mut live = crate::live::LiveView::start(&a.live, &[])?;
    let result = start(
        &a.file,
        &a.out,
        &link_name,
        &mut target,
        a.stop_after,
        live.as_mut(),
    );
    finish_live(live, &result);
    result
}

/// A campaign's points are not paced (each arrives when it is done): `--pace` is refused.
fn refuse_pace(live: &crate::live::LiveArgs) -> Result<(), CliError> {
    match live.pace {
        Some(p) => Err(CliError::input(format!(
            "--pace {p}: a campaign's points are not paced, each is shown when it is done (allowed: --live and --linger only)"
        ))),
        None => Ok(()),
    }
}

/// Tell the live view how the campaign ended, and keep its page up.
fn finish_live(live: Option<crate::live::LiveView>, result: &Result<(), CliError>) {
    let Some(mut v) = live else {
        return;
    };
    let (exit_status, message) = match result {
        Ok(()) => (0, "the session ended".to_string()),
        Err(e) => (i32::from(e.exit), e.message.clone()),
    };
    v.bus().event(sandjumper_live::Event::Campaign(
        sandjumper_live::CampaignRecord::Stop {
            exit_status,
            message: message.clone(),
        },
    ));
    v.finish(0.0, message, exit_status == 0);
}

/// Run the campaign file `file` on a board reached by `connect` (a fresh link per point),
/// into `out` (the library entry for boards that are not serial ports, e.g. a stand-in).
pub fn run_on_board(
    file: &Path,
    out: &Path,
    connect: Box<Connect<'_>>,
    stop_after: Option<usize>,
) -> Result<(), CliError> {
    start(
        file,
        out,
        "board",
        &mut Target::Board(connect),
        stop_after,
        None,
    )
}

/// Resume the campaign in `dir` on a board reached by `connect`.
pub fn resume_on_board(
    dir: &Path,
    connect: Box<Connect<'_>>,
    stop_after: Option<usize>,
) -> Result<(), CliError> {
    let (file, work, journal, _lock, _) = reopen(dir)?;
    drive(
        &file,
        &mut Target::Board(connect),
        &work,
        dir,
        journal,
        stop_after,
        None,
    )
}

/// Where the jumps happen.
enum Target<'a> {
    /// A simulated controller (sil, pil) with the simulated bed.
    Simulated(Link),
    /// A board with its own bed apparatus.
    Board(Box<Connect<'a>>),
}

fn board_connect(port: String) -> Box<Connect<'static>> {
    Box::new(move || {
        sandjumper_rig::hil::serial::start(&port, std::time::Duration::from_secs(2))
            .map(|l| Box::new(l) as Box<dyn sandjumper_rig::hil::link::RigLink>)
            .map_err(|e| format!("cannot open the board on {port}: {e}"))
    })
}

/// Plan a new campaign from `file` into `out` and drive it.
fn start(
    file_path: &Path,
    out: &Path,
    link_name: &str,
    target: &mut Target<'_>,
    stop_after: Option<usize>,
    live: Option<&mut crate::live::LiveView>,
) -> Result<(), CliError> {
    let file = CampaignFile::read(file_path).map_err(CliError::input)?;
    if matches!(target, Target::Board(_)) {
        file.check_for_board(&file_path.display().to_string())
            .map_err(CliError::input)?;
    }
    let work = work_dir(out);
    for d in [out, work.as_path()] {
        if d.exists() {
            return Err(CliError::input(format!(
                "--out {}: {} exists (allowed: a new folder; `campaign resume {}` carries on a stopped campaign)",
                out.display(),
                d.display(),
                out.display()
            )));
        }
    }
    // The folder takes its `.incomplete` name only once its plan is on the disk, so a
    // campaign killed at its very start leaves no folder that looks resumable.
    let starting = with_suffix(out, ".starting");
    if starting.exists() {
        std::fs::remove_dir_all(&starting)
            .map_err(|e| CliError::input(format!("cannot clear {}: {e}", starting.display())))?;
    }
    std::fs::create_dir_all(starting.join("points"))
        .map_err(|e| CliError::input(format!("cannot create {}: {e}", starting.display())))?;
    let text = std::fs::read_to_string(file_path)
        .map_err(|e| CliError::input(format!("cannot read {}: {e}", file_path.display())))?;
    std::fs::write(starting.join("campaign.toml"), &text)
        .map_err(|e| CliError::internal(format!("cannot copy the campaign file: {e}")))?;
    {
        let mut journal =
            Journal::create(&starting.join("journal.jsonl")).map_err(CliError::internal)?;
        journal
            .append(Event::Planned {
                name: file.name.clone(),
                file_text: text,
                points: points(&file),
                link: link_name.to_string(),
            })
            .map_err(CliError::internal)?;
    }
    std::fs::rename(&starting, &work).map_err(|e| {
        CliError::internal(format!(
            "cannot rename {} to {}: {e}",
            starting.display(),
            work.display()
        ))
    })?;
    let jpath = work.join("journal.jsonl");
    let _lock = lock(&jpath)?;
    let journal = Journal::open(&jpath).map_err(CliError::internal)?;
    drive(&file, target, &work, out, journal, stop_after, live)
}

/// A stopped campaign's file, work folder, journal (the point in progress recorded as
/// interrupted) and its lock.
fn reopen(dir: &Path) -> Result<(CampaignFile, PathBuf, Journal, File, String), CliError> {
    let work = work_dir(dir);
    if !work.is_dir() {
        return Err(CliError::input(if dir.join("journal.jsonl").is_file() {
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
        }));
    }
    let jpath = work.join("journal.jsonl");
    let lock = lock(&jpath)?;
    let mut journal = Journal::open(&jpath).map_err(CliError::input)?;
    if journal.dropped_partial_bytes > 0 {
        eprintln!(
            "campaign: dropped the journal's last line, cut by the crash ({} bytes)",
            journal.dropped_partial_bytes
        );
    }
    let state = State::from_records(&journal.records).map_err(CliError::input)?;
    let file = CampaignFile::parse(
        &state.file_text,
        &work.join("campaign.toml").display().to_string(),
    )
    .map_err(CliError::input)?;
    if let Some((point, phase)) = &state.in_progress {
        eprintln!(
            "campaign: point {point} was interrupted after `{phase}`; it starts again from fluidization"
        );
        journal
            .append(Event::Interrupted {
                point: *point,
                phase: phase.clone(),
            })
            .map_err(CliError::internal)?;
    }
    Ok((file, work, journal, lock, state.link))
}

fn resume(a: &ResumeArgs) -> Result<(), CliError> {
    refuse_pace(&a.live)?;
    let mut live = crate::live::LiveView::start(&a.live, &[])?;
    let result = (|| {
        let (file, work, journal, _lock, link_name) = reopen(&a.dir)?;
        let mut target = match link_name.strip_prefix("serial:") {
            Some(port) => Target::Board(board_connect(port.to_string())),
            None => Target::Simulated(Link {
                arg: link_arg(&link_name)?,
                firmware: a.firmware.clone(),
            }),
        };
        drive(
            &file,
            &mut target,
            &work,
            &a.dir,
            journal,
            a.stop_after,
            live.as_mut(),
        )
    })();
    finish_live(live, &result);
    result
}

/// The parameter a campaign's points sweep (the first of frequency, delay, packing fraction
/// that takes more than one value).
fn swept(points: &[super::plan::Point]) -> Option<String> {
    let varies =
        |f: &dyn Fn(&super::plan::Point) -> f64| points.iter().any(|p| f(p) != f(&points[0]));
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
fn point_record(
    row: &super::result_row::ResultRow,
    history: bool,
) -> sandjumper_live::CampaignRecord {
    sandjumper_live::CampaignRecord::Point {
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
    }
}

/// The point's jump height: measured by the camera, else replayed, else the plant's.
fn row_height(row: &super::result_row::ResultRow) -> Option<f64> {
    row.measured_jump_height_m
        .or(row.predicted_jump_height_m)
        .or(row.plant_jump_height_m)
}

/// One line of the campaign's live table on the terminal.
fn point_line(row: &super::result_row::ResultRow, total: usize) -> String {
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
fn refresh(state: &mut State, journal: &Journal, work: &Path, seed: u64) -> Result<(), CliError> {
    state
        .catch_up(&journal.records)
        .map_err(CliError::internal)?;
    write_results(work, state).map_err(CliError::internal)?;
    write_documents(work, state, seed).map_err(CliError::internal)
}

/// Run the points not done yet, then finish the campaign.
fn drive(
    file: &CampaignFile,
    target: &mut Target<'_>,
    work: &Path,
    out: &Path,
    mut journal: Journal,
    stop_after: Option<usize>,
    mut live: Option<&mut crate::live::LiveView>,
) -> Result<(), CliError> {
    let mut state = State::from_records(&journal.records).map_err(CliError::internal)?;
    if let Some(v) = live.as_deref_mut() {
        v.bus().event(sandjumper_live::Event::RunStarted {
            title: format!("campaign {}", state.name),
            t_s: 0.0,
        });
        v.bus().event(sandjumper_live::Event::Campaign(
            sandjumper_live::CampaignRecord::Start {
                plan: format!(
                    "{}: {} points on {}",
                    state.name,
                    state.points.len(),
                    state.link
                ),
                points: state.points.len(),
                swept: swept(&state.points),
                done_before: state.done(),
            },
        ));
        for row in state.rows.values() {
            v.bus()
                .event(sandjumper_live::Event::Campaign(point_record(row, true)));
        }
    }
    journal
        .append(Event::SessionStarted {
            session: state.sessions + 1,
        })
        .map_err(CliError::internal)?;
    let total = state.points.len();
    let bar = crate::command::progress_bar(total as u64, "points");
    bar.set_position(state.done() as u64);
    let mut this_session = 0usize;
    loop {
        refresh(&mut state, &journal, work, file.seed)?;
        let Some(point) = state.next_point().cloned() else {
            break;
        };
        if stop_after.is_some_and(|n| this_session >= n) {
            bar.finish_and_clear();
            println!(
                "campaign: stopped after {this_session} point(s) this session, {} of {total} done; `campaign resume {}` carries on",
                state.done(),
                out.display()
            );
            return Ok(());
        }
        let label = format!(
            "point {} ({} {} Hz{}, phi {})",
            point.index,
            point.kind,
            point.freq_hz,
            if point.kind == "delayed" {
                format!(" tau {} s", point.tau_s)
            } else {
                String::new()
            },
            point.target_phi
        );
        let mut on_phase = |phase: &str| bar.set_message(format!("{label}: {phase}"));
        let row = match target {
            Target::Simulated(link) => {
                run_point(file, &point, link, work, &mut journal, &mut on_phase)
            }
            Target::Board(connect) => run_point_on_board(
                file,
                &point,
                connect.as_mut(),
                work,
                &mut journal,
                &mut on_phase,
            ),
        }
        .map_err(CliError::input)?;
        let failed = row.status == "bed-not-prepared";
        let line = point_line(&row, total);
        // On stdout, above the progress bar when one is drawn.
        bar.suspend(|| println!("{line}"));
        if let Some(v) = live.as_deref_mut() {
            v.bus()
                .event(sandjumper_live::Event::Campaign(point_record(&row, false)));
        }
        journal
            .append(Event::Done { row })
            .map_err(CliError::internal)?;
        this_session += 1;
        bar.inc(1);
        if failed && file.on_failed_preparation == FailurePolicy::Stop {
            refresh(&mut state, &journal, work, file.seed)?;
            bar.finish_and_clear();
            return Err(CliError::internal(format!(
                "campaign: point {} failed its bed preparation and the campaign's policy is `stop`; the failure is recorded, `campaign resume {}` goes on with the next point",
                point.index,
                out.display()
            )));
        }
    }
    bar.finish_and_clear();
    state
        .catch_up(&journal.records)
        .map_err(CliError::internal)?;
    if state.finished.is_none() {
        journal
            .append(Event::Finished {
                exit_status: "success".into(),
                reason: String::new(),
            })
            .map_err(CliError::internal)?;
    }
    refresh(&mut state, &journal, work, file.seed)?;
    super::figure::write(work, &state).map_err(CliError::internal)?;
    drop(journal);
    std::fs::rename(work, out).map_err(|e| {
        CliError::internal(format!(
            "cannot rename {} to {}: {e}",
            work.display(),
            out.display()
        ))
    })?;
    let failed = state.rows.values().filter(|r| r.status != "done").count();
    println!(
        "campaign {}: {} points done ({} failed or faulted) over {} session(s), {} interruption(s); written to {}",
        state.name,
        state.done(),
        failed,
        state.sessions,
        state.interruptions,
        out.display()
    );
    Ok(())
}

#[derive(Serialize)]
struct StatusReport<'a> {
    dir: String,
    name: &'a str,
    link: &'a str,
    state: &'a str,
    points: usize,
    done: usize,
    failed: usize,
    in_progress: Option<(usize, String)>,
    sessions: u32,
    interruptions: u32,
    dropped_partial_journal_bytes: usize,
}

fn status(a: &StatusArgs) -> Result<(), CliError> {
    let work = work_dir(&a.dir);
    let (dir, finished_dir) = if work.is_dir() {
        (work, false)
    } else {
        (a.dir.clone(), true)
    };
    let jpath = dir.join("journal.jsonl");
    if !jpath.is_file() {
        return Err(CliError::input(format!(
            "{}: no campaign here (no journal.jsonl in it or in {}.incomplete)",
            a.dir.display(),
            a.dir.display()
        )));
    }
    let (records, dropped) = read(&jpath).map_err(CliError::input)?;
    let st = State::from_records(&records).map_err(CliError::input)?;
    let running = File::open(&jpath)
        .map(|f| matches!(f.try_lock_shared(), Err(std::fs::TryLockError::WouldBlock)))
        .unwrap_or(false);
    let state = if finished_dir {
        "finished"
    } else if running {
        "running"
    } else {
        "stopped (resumable)"
    };
    let rep = StatusReport {
        dir: a.dir.display().to_string(),
        name: &st.name,
        link: &st.link,
        state,
        points: st.points.len(),
        done: st.done(),
        failed: st.rows.values().filter(|r| r.status != "done").count(),
        in_progress: st.in_progress.clone(),
        sessions: st.sessions,
        interruptions: st.interruptions,
        dropped_partial_journal_bytes: dropped,
    };
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rep).map_err(|e| CliError::internal(e.to_string()))?
        );
    } else {
        println!(
            "campaign {} ({}): {}; {} of {} points done, {} failed or faulted; {} session(s), {} interruption(s){}",
            rep.name,
            rep.link,
            rep.state,
            rep.done,
            rep.points,
            rep.failed,
            rep.sessions,
            rep.interruptions,
            rep.in_progress
                .as_ref()
                .map(|(p, ph)| format!("; point {p} at `{ph}`"))
                .unwrap_or_default()
        );
    }
    Ok(())
}
