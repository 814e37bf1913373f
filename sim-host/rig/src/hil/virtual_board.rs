//! `--link f407`: the F407 release ELF (the binary a user flashes) on the virtual board, a
//! separate program (`sim-host/virtual-f407`, its own workspace on rustc 1.98.0) that runs the
//! firmware and the plant in one process in virtual time, coupled through the board's
//! peripherals: the robot's motion drives TIM2's quadrature edges, the DAC's volts are the
//! drive's force, the bed's inputs come through GPIO and ADC. The host reaches it exactly as it
//! reaches a board on a serial port: the USB CDC byte stream (here the program's stdin and
//! stdout) carries commands, replies and telemetry, nothing else. The firmware runs free on its
//! own tick, so programs run through the free-running path of the rig tool's session.
//!
//! The board runs in virtual time, as fast as the machine lets it: its program writes its
//! virtual clock to a file (`--clock`; stdout stays the USB byte stream), which the link reads
//! to count its waits in the board's time ([`super::framed::BoardClock`]).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command as Process, Stdio};
use std::time::Duration;

use super::framed::{BoardClock, ChildGuard, FramedLink};
use super::link::{LinkError, LinkReport, RigLink};
use crate::firmware_image::{Board, F407_BUILD, F407_ELF, check_elf};
use sandjumper_core::protocol::FaultReport;
use sandjumper_core::{ActuatorFrame, Command, Reply, SampleRecord, SensorFrame};
use sandjumper_model::params::{ModelName, Params};

/// The virtual board's program, relative to the workspace root.
pub const VIRTUAL_BOARD_BIN: &str = "sim-host/virtual-f407/target/release/virtual-f407";
/// How to build it.
pub const VIRTUAL_BOARD_BUILD: &str = "sim-host/virtual-f407/build.sh (needs rustc 1.98.0: \
     `rustup toolchain install 1.98.0 --profile minimal -c clippy,rustfmt`; about 3 min cold)";

/// How to start the virtual board.
#[derive(Clone, Debug)]
pub struct VirtualBoardConfig {
    /// The virtual board's program.
    pub program: PathBuf,
    /// The F407 ELF.
    pub elf: PathBuf,
    /// What the drive moves (None: nothing).
    pub load: Option<VirtualLoad>,
    /// Run no faster than this multiple of real time (None: as fast as it can; the program
    /// allows 0.001 to 1000). Slowing the board down does not fail a run: the link counts its
    /// waits in the board's virtual time.
    pub pace: Option<f64>,
    /// How long to wait for an answer, in the board's virtual time (the board's clock standing
    /// still this long in wall time is a hang).
    pub answer_timeout: Duration,
}

/// `relative` under `start` or the nearest of its ancestors that has it (the workspace root,
/// from anywhere inside it), else under `start`.
fn find_up(start: &Path, relative: &str) -> PathBuf {
    start
        .ancestors()
        .map(|dir| dir.join(relative))
        .find(|p| p.exists())
        .unwrap_or_else(|| start.join(relative))
}

impl VirtualBoardConfig {
    /// The program and ELF at their default places under `root` (the workspace root, or any
    /// folder inside it).
    pub fn new(root: &Path) -> Self {
        let root = std::path::absolute(root).unwrap_or_else(|_| root.to_path_buf());
        Self {
            program: find_up(&root, VIRTUAL_BOARD_BIN),
            elf: find_up(&root, F407_ELF),
            load: None,
            pace: None,
            answer_timeout: Duration::from_secs(10),
        }
    }
}

/// What the virtual board's drive moves.
#[derive(Clone, Debug)]
pub enum VirtualLoad {
    /// The robot on its ground model, the carriage resting at `p0_m` at power-up (the encoder's
    /// zero is the rig's, p = 0; the sil and pil rigs start the robot at the trajectory's start,
    /// which is what `rig` passes).
    Robot {
        /// Parameters.
        params: Params,
        /// Ground model.
        model: ModelName,
        /// m.
        p0_m: f64,
    },
    /// The slow-intrusion fixture (motor clamped, foot on the surface at `surface_p_m`).
    Intrusion {
        /// Parameters.
        params: Params,
        /// Ground model (a sand model).
        model: ModelName,
        /// m.
        surface_p_m: f64,
    },
}

/// A running virtual board: the link, and where its plant's summary will be once it ends.
pub struct VirtualBoard {
    /// The link (a [`FramedLink`] over the program's stdin/stdout).
    pub link: FramedLink,
    /// The plant's summary (`jump_height_m`, ...), written when the program ends (after
    /// `finish`).
    pub summary_path: PathBuf,
    /// The program's stderr (the firmware's log, its own report).
    pub log_path: PathBuf,
}

/// `e` with the last lines the virtual board wrote (why it stopped, the firmware's last log).
fn with_log_tail(e: LinkError, log: &Path) -> LinkError {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    let tail: Vec<&str> = text.lines().rev().take(8).collect();
    if tail.is_empty() {
        return e;
    }
    let tail: Vec<&str> = tail.into_iter().rev().collect();
    LinkError::Io {
        what: e.to_string(),
        message: format!("the virtual board's last words:\n{}", tail.join("\n")),
    }
}

/// The virtual time in the board's `--clock` file: a u64 of ns, little-endian, at offset 0 and
/// its bitwise complement at offset 8. `None` before the first write, or when a read caught a
/// write half done.
fn read_clock(path: &Path) -> Option<Duration> {
    let bytes = std::fs::read(path).ok()?;
    let word = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
    };
    let (ns, check) = (word(0)?, word(8)?);
    (check == !ns).then(|| Duration::from_nanos(ns))
}

fn io(what: &str) -> impl Fn(std::io::Error) -> LinkError + '_ {
    move |e| LinkError::Io {
        what: what.to_string(),
        message: e.to_string(),
    }
}

/// Start the virtual board with `cfg` and wait for its first status.
pub fn start(cfg: &VirtualBoardConfig) -> Result<VirtualBoard, LinkError> {
    if !cfg.program.is_file() {
        return Err(LinkError::Io {
            what: format!("the virtual board {}", cfg.program.display()),
            message: format!("not built: build it with {VIRTUAL_BOARD_BUILD}"),
        });
    }
    if !cfg.elf.is_file() {
        return Err(LinkError::Io {
            what: format!("the F407 firmware {}", cfg.elf.display()),
            message: format!("not built: build it with `{F407_BUILD}`"),
        });
    }
    check_elf(&cfg.elf, Board::F407).map_err(|e| LinkError::Io {
        what: "firmware image".into(),
        message: e.to_string(),
    })?;
    let dir = tempfile::Builder::new()
        .prefix("sandjumper-f407-")
        .tempdir()
        .map_err(io("creating the virtual board's directory"))?;
    let summary_path = dir.path().join("summary.json");
    let clock_path = dir.path().join("clock");
    let mut cmd = Process::new(&cfg.program);
    cmd.arg("--elf")
        .arg(&cfg.elf)
        .arg("--stdio")
        .arg("--summary")
        .arg(&summary_path)
        .arg("--clock")
        .arg(&clock_path);
    if let Some(load) = &cfg.load {
        let (params, model, flag, at_flag, at_m) = match load {
            VirtualLoad::Robot {
                params,
                model,
                p0_m,
            } => (params, model, "--robot", "--p0", p0_m),
            VirtualLoad::Intrusion {
                params,
                model,
                surface_p_m,
            } => (params, model, "--intrusion", "--surface-p", surface_p_m),
        };
        let params_path = dir.path().join("params.toml");
        let text = toml::to_string(params).map_err(|e| LinkError::Io {
            what: "the rig's parameters".into(),
            message: e.to_string(),
        })?;
        std::fs::File::create(&params_path)
            .and_then(|mut f| f.write_all(text.as_bytes()))
            .map_err(io("writing the rig's parameters"))?;
        cmd.arg(flag)
            .arg(&params_path)
            .arg("--model")
            .arg(model.to_string())
            .arg(at_flag)
            .arg(at_m.to_string());
    }
    if let Some(p) = cfg.pace {
        cmd.arg("--pace").arg(p.to_string());
    }
    let log_path = dir.path().join("board.log");
    let log = std::fs::File::create(&log_path).map_err(io("creating the board's log"))?;
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::from(log))
        .spawn()
        .map_err(io("starting the virtual board"))?;
    let stdin = child.stdin.take().ok_or_else(|| LinkError::Io {
        what: "the virtual board".into(),
        message: "no stdin".into(),
    })?;
    let stdout = child.stdout.take().ok_or_else(|| LinkError::Io {
        what: "the virtual board".into(),
        message: "no stdout".into(),
    })?;
    let clock: BoardClock = std::sync::Arc::new(move || read_clock(&clock_path));
    let link = FramedLink::start_clocked(
        "f407",
        Box::new(stdout),
        Box::new(stdin),
        Some(ChildGuard::new(child, "the virtual board")),
        cfg.answer_timeout,
        Some(clock),
    )
    .map_err(|e| with_log_tail(e, &log_path))?;
    Ok(VirtualBoard {
        log_path,
        link: link.keep_alive(dir),
        summary_path,
    })
}

/// A finished virtual board's summary (`jump_height_m`, `plant_error`, `virtual_s`, `wall_s`),
/// if it wrote one.
fn read_summary(path: &Path) -> Option<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

impl RigLink for VirtualBoard {
    fn name(&self) -> String {
        "f407".into()
    }
    fn command(&mut self, command: &Command) -> Result<Reply, LinkError> {
        let log = self.log_path.clone();
        self.link.command(command).map_err(|e| match e {
            LinkError::Rejected { .. } => e,
            other => with_log_tail(other, &log),
        })
    }
    fn exchange(&mut self, _frame: &SensorFrame) -> Result<ActuatorFrame, LinkError> {
        Err(LinkError::Protocol(
            "--link f407 couples the plant through the board's peripherals, not lockstep frames"
                .into(),
        ))
    }
    fn send_corrupted(&mut self, frame: &SensorFrame) -> Result<(), LinkError> {
        self.link.send_corrupted(frame)
    }
    fn silent_period(&mut self) -> Result<Option<ActuatorFrame>, LinkError> {
        Ok(None)
    }
    fn take_samples(&mut self) -> Vec<SampleRecord> {
        self.link.take_samples()
    }
    fn take_faults(&mut self) -> Vec<FaultReport> {
        self.link.take_faults()
    }
    fn finish(&mut self) -> Result<LinkReport, LinkError> {
        let log = self.log_path.clone();
        let mut report = self.link.finish().map_err(|e| with_log_tail(e, &log))?;
        let summary = read_summary(&self.summary_path);
        let field = |key: &str| summary.as_ref().and_then(|v| v.get(key));
        if let Some(error) = field("plant_error").and_then(|e| e.as_str()) {
            return Err(LinkError::Protocol(format!(
                "the virtual board's simulated rig failed: {error}"
            )));
        }
        let number = |key: &str| field(key).and_then(|n| n.as_f64());
        report.simulated_jump_height_m = number("jump_height_m");
        report.board_realtime_factor = number("virtual_s")
            .zip(number("wall_s"))
            .filter(|(_, wall)| *wall > 0.0)
            .map(|(virt, wall)| virt / wall);
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_file_is_read_only_when_whole() {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join("clock");
        assert_eq!(read_clock(&path), None, "not written yet");
        let ns: u64 = 1_234_567_890;
        let mut bytes = ns.to_le_bytes().to_vec();
        std::fs::write(&path, &bytes).expect("written");
        assert_eq!(read_clock(&path), None, "half written");
        bytes.extend((!ns).to_le_bytes());
        std::fs::write(&path, &bytes).expect("written");
        assert_eq!(read_clock(&path), Some(Duration::from_nanos(ns)));
        bytes[0] ^= 1;
        std::fs::write(&path, &bytes).expect("written");
        assert_eq!(read_clock(&path), None, "a torn write");
    }
}
