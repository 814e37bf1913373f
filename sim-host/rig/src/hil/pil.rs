//! Processor in the loop: the real firmware, built for QEMU's `mps2-an386` (Cortex-M4F), started
//! by the simulator; lockstep frames over two host FIFOs through semihosting.
//!
//! QEMU runs with `-icount shift=6,align=off,sleep=off` (the flags of `firmware/qemu-run.sh`):
//! virtual time advances with the instruction count, so a run is deterministic and the
//! firmware's per-tick instruction count is exact. The firmware's semihosting command line is
//! `fifo IN OUT`; it opens IN for reading, then OUT for writing.
//!
//! QEMU and the host's lockstep threads share one core (see [`super::affinity`]): cross-core
//! wake-ups cost more than the tick itself.
//!
//! Build the firmware first: [`crate::firmware_image::EMULATED_BUILD`] (the ELF is
//! [`crate::firmware_image::EMULATED_ELF`]).

use std::fs::{File, OpenOptions};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use super::affinity::PinnedThread;
use super::framed::{ChildGuard, FramedLink};
use super::link::LinkError;
use crate::firmware_image::{Board, check_elf};

/// How to start the emulated firmware.
#[derive(Clone, Debug, PartialEq)]
pub struct PilConfig {
    /// The firmware ELF built with `--features board-qemu`.
    pub elf: PathBuf,
    /// The QEMU binary (default `qemu-system-arm`).
    pub qemu: PathBuf,
    /// Run QEMU and the host's lockstep threads on one core (default true; 2.5x faster on
    /// a 2-core VM).
    pub pin_to_one_core: bool,
    /// Longest wait for any answer from the firmware before it counts as hung.
    pub answer_timeout: Duration,
}

impl PilConfig {
    /// `elf` with `qemu-system-arm` from `PATH` and a 5 s answer timeout.
    pub fn new(elf: impl Into<PathBuf>) -> Self {
        Self {
            elf: elf.into(),
            qemu: "qemu-system-arm".into(),
            pin_to_one_core: true,
            answer_timeout: Duration::from_secs(5),
        }
    }

    /// The ELF a release build for the emulated board leaves under `target_dir`.
    pub fn elf_in(target_dir: &Path) -> PathBuf {
        target_dir.join("thumbv7em-none-eabihf/release/sandjumper-firmware")
    }
}

/// Reads a FIFO, opening it on first use (opening blocks until the writer opens its end, which
/// must not hold up the host: the reader thread does it).
struct LazyFifo {
    path: PathBuf,
    file: Option<File>,
}

impl Read for LazyFifo {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.file.is_none() {
            self.file = Some(File::open(&self.path)?);
        }
        match self.file.as_mut() {
            Some(f) => f.read(buf),
            None => Ok(0),
        }
    }
}

fn io(what: &str) -> impl Fn(std::io::Error) -> LinkError + '_ {
    move |e| LinkError::Io {
        what: what.to_string(),
        message: e.to_string(),
    }
}

/// Start QEMU with the firmware in a FIFO session and connect to it. The FIFOs live in a fresh
/// temporary directory removed when the link is dropped.
pub fn start(config: &PilConfig) -> Result<FramedLink, LinkError> {
    start_session(config, &["fifo"])
}

/// Start QEMU with `firmware_args` (the first word is the session; `fifo` gets the two FIFO
/// paths appended).
pub fn start_session(config: &PilConfig, firmware_args: &[&str]) -> Result<FramedLink, LinkError> {
    check_elf(&config.elf, Board::Emulated).map_err(|e| LinkError::Io {
        what: "firmware image".into(),
        message: e.to_string(),
    })?;
    let dir = tempfile::Builder::new()
        .prefix("sandjumper-pil-")
        .tempdir()
        .map_err(io("creating the FIFO directory"))?;
    let input = dir.path().join("sensor.fifo");
    let output = dir.path().join("actuator.fifo");
    for fifo in [&input, &output] {
        let status = Command::new("mkfifo")
            .arg(fifo)
            .status()
            .map_err(io("running mkfifo"))?;
        if !status.success() {
            return Err(LinkError::Io {
                what: format!("mkfifo {}", fifo.display()),
                message: status.to_string(),
            });
        }
    }
    let mut semihosting = String::from("enable=on,target=native");
    let mut args: Vec<String> = firmware_args.iter().map(|s| s.to_string()).collect();
    if args.first().map(String::as_str) == Some("fifo") {
        args.push(input.display().to_string());
        args.push(output.display().to_string());
    }
    for a in &args {
        if a.contains(',') {
            return Err(LinkError::Io {
                what: format!("firmware argument {a}"),
                message: "QEMU cannot pass a comma".into(),
            });
        }
        semihosting.push_str(",arg=");
        semihosting.push_str(a);
    }
    // Before QEMU and the reader thread exist: both inherit the calling thread's one core.
    let pin = config.pin_to_one_core.then(PinnedThread::pin);
    let child = Command::new(&config.qemu)
        .args([
            "-machine",
            "mps2-an386",
            "-cpu",
            "cortex-m4",
            "-nographic",
            "-monitor",
            "none",
            "-serial",
            "none",
        ])
        .args(["-semihosting-config", &semihosting])
        .args(["-icount", "shift=6,align=off,sleep=off"])
        .arg("-kernel")
        .arg(&config.elf)
        .stdin(Stdio::null())
        .stdout(Stdio::inherit())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(io(
            "starting qemu-system-arm (apt-get install qemu-system-arm)",
        ))?;
    let child = ChildGuard::new(child, "QEMU");
    // Read + write: opening does not block, and closing it is the firmware's end of file.
    let writer = OpenOptions::new()
        .read(true)
        .write(true)
        .open(&input)
        .map_err(io("opening the sensor FIFO"))?;
    let reader = LazyFifo {
        path: output,
        file: None,
    };
    let link = FramedLink::start(
        "pil",
        Box::new(reader),
        Box::new(writer),
        Some(child),
        config.answer_timeout,
    )?;
    Ok(link.keep_alive(dir).keep_alive(pin))
}
