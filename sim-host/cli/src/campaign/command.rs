//! `sandjumper campaign run|resume|status`: the arguments as a request to
//! [`sandjumper_campaign::session`], its outcome printed.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

use super::point::Connect;
use super::session::{self, Hooks, ResumeRequest, RunRequest, SessionOutcome, StatusRequest};
use crate::command::CliError;
use crate::command::progress::Bars;
use sandjumper_campaign::CampaignError;

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

fn run_new(a: &RunArgs) -> Result<(), CliError> {
    let request = RunRequest {
        file: a.file.clone(),
        link: a.link.clone(),
        port: a.port.clone(),
        firmware: a.firmware.clone(),
        out: a.out.clone(),
        stop_after: a.stop_after,
    };
    request.validate()?;
    with_live(&a.live, |hooks, bars| session::run(&request, hooks, bars))
}

fn resume(a: &ResumeArgs) -> Result<(), CliError> {
    let request = ResumeRequest {
        dir: a.dir.clone(),
        firmware: a.firmware.clone(),
        stop_after: a.stop_after,
    };
    with_live(&a.live, |hooks, bars| {
        session::resume(&request, hooks, bars)
    })
}

/// Run `call` (a session) with the live view `args` asks for and progress bars; print its last line
/// and tell the live view how it ended.
fn with_live(
    args: &crate::live::LiveArgs,
    call: impl FnOnce(Hooks<'_>, &Bars) -> Result<SessionOutcome, CampaignError>,
) -> Result<(), CliError> {
    session::check_pace(args.pace)?;
    let mut live = crate::live::LiveView::start(args, &[])?;
    let bars = Bars::default();
    let result = call(hooks(&mut live, &bars), &bars)
        .map(|o| println!("{o}"))
        .map_err(CliError::from);
    finish_live(live, &result);
    result
}

/// What a session reports to besides `bars`: the live view's bus, and each point's line
/// printed on stdout (above the progress bar when one is drawn).
fn hooks<'a>(live: &'a mut Option<crate::live::LiveView>, bars: &'a Bars) -> Hooks<'a> {
    Hooks {
        live: live.as_mut().map(|v| v.bus()),
        on_point: Some(Box::new(move |_row, line| {
            bars.suspend(|| println!("{line}"));
        })),
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
    v.bus()
        .event(session::stop_event(exit_status, message.clone()));
    v.finish(0.0, message, exit_status == 0);
}

/// Run the campaign file `file` on a board reached by `connect` (a fresh link per point),
/// into `out` (the library entry for boards that are not serial ports, e.g. a stand-in:
/// [`session::run_on_board`]).
pub fn run_on_board(
    file: &Path,
    out: &Path,
    connect: Box<Connect<'_>>,
    stop_after: Option<usize>,
) -> Result<(), CliError> {
    let request = RunRequest {
        file: file.to_path_buf(),
        out: out.to_path_buf(),
        stop_after,
        ..RunRequest::default()
    };
    let bars = Bars::default();
    let outcome = session::run_on_board(&request, connect, hooks(&mut None, &bars), &bars)?;
    println!("{outcome}");
    Ok(())
}

fn status(a: &StatusArgs) -> Result<(), CliError> {
    let report = session::status(&StatusRequest { dir: a.dir.clone() })?;
    if a.json {
        println!("{}", report.json()?);
    } else {
        println!("{report}");
    }
    Ok(())
}
