//! `rig flash`: write the F407 firmware with the probe-rs CLI (`probe-rs download --chip
//! STM32F407VGTx ELF`, then `probe-rs reset`), an external program. probe-rs is not linked in:
//! it needs libusb/libudev to build; the CLI (`cargo install probe-rs-tools`) does the same job.
//! For a simulated controller there is nothing to flash.

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

use sandjumper_output::Progress;

use super::target::Target;
use crate::error::RigError;
use crate::firmware_image::{Board, check_elf};
use crate::hil::open::LinkArg;

/// The board's chip as probe-rs names it.
pub const CHIP: &str = "STM32F407VGTx";
/// Where `cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release` puts
/// the F407 firmware.
pub const DEFAULT_F407_ELF: &str = crate::firmware_image::F407_ELF;

/// `rig flash`: which board and which probe-rs.
#[derive(Clone, Debug, PartialEq)]
pub struct FlashRequest {
    /// The board (its firmware: [`Target::firmware`], default [`DEFAULT_F407_ELF`]).
    pub target: Target,
    /// The probe-rs executable (default `probe-rs`, found on `PATH`).
    pub probe_rs: PathBuf,
}

impl Default for FlashRequest {
    fn default() -> Self {
        Self {
            target: Target::default(),
            probe_rs: PathBuf::from("probe-rs"),
        }
    }
}

/// What `rig flash` did; its [`fmt::Display`] is what the command prints.
#[derive(Clone, Debug, PartialEq)]
pub enum Flashed {
    /// A simulated controller: nothing to flash (why, in words).
    Nothing(&'static str),
    /// The ELF written to the board, and the board's port if it has one.
    Board {
        /// The ELF written.
        elf: PathBuf,
        /// The board's serial port.
        port: Option<String>,
    },
}

impl fmt::Display for Flashed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Nothing(what) => writeln!(f, "nothing to flash: {what}"),
            Self::Board { elf, port } => {
                writeln!(f, "flashed {} to the {CHIP}", elf.display())?;
                if let Some(port) = port {
                    writeln!(
                        f,
                        "the board talks on {port}: try `sandjumper rig status --port {port}`"
                    )?;
                }
                Ok(())
            }
        }
    }
}

fn on_path(exe: &Path) -> bool {
    if exe.components().count() > 1 {
        return exe.is_file();
    }
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(exe).is_file()))
}

/// One probe-rs step (`what`: "download", "reset").
fn probe_rs(exe: &Path, args: &[&std::ffi::OsStr], what: &str) -> Result<(), RigError> {
    let out = Command::new(exe)
        .args(args)
        .output()
        .map_err(|e| RigError::input(format!("cannot run {}: {e}", exe.display())))?;
    if out.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let hint = if stderr.to_lowercase().contains("no probe") {
        " (is the debug probe plugged in?)"
    } else {
        ""
    };
    Err(RigError::input(format!(
        "probe-rs {what} failed ({}){hint}: {}",
        out.status,
        stderr.trim()
    )))
}

/// Run `rig flash`.
pub fn flash(request: &FlashRequest, _progress: &dyn Progress) -> Result<Flashed, RigError> {
    let port = match &request.target.link {
        LinkArg::Serial(port) => port.clone(),
        LinkArg::Sil => {
            return Ok(Flashed::Nothing(
                "--link sil runs the core's controller in this process",
            ));
        }
        LinkArg::Pil => {
            return Ok(Flashed::Nothing(
                "--link pil: QEMU loads the firmware ELF (--firmware) at every start",
            ));
        }
        LinkArg::F407 => {
            return Ok(Flashed::Nothing(
                "--link f407: the virtual board loads the F407 ELF (--firmware) at every start",
            ));
        }
    };
    let elf = request
        .target
        .firmware
        .clone()
        .unwrap_or_else(|| PathBuf::from(DEFAULT_F407_ELF));
    if !elf.is_file() {
        return Err(RigError::input(format!(
            "firmware ELF {} not found (build it with `cargo build -p sandjumper-firmware \
             --target thumbv7em-none-eabihf --release`, or give --firmware ELF)",
            elf.display()
        )));
    }
    let exe = &request.probe_rs;
    if !on_path(exe) {
        return Err(RigError::input(format!(
            "probe-rs not found ({}): install it with `cargo install probe-rs-tools`, or give \
             --probe-rs PATH",
            exe.display()
        )));
    }
    // probe-rs must not be handed the emulated board's image (or anything else).
    check_elf(&elf, Board::F407).map_err(|e| RigError::input(e.to_string()))?;
    let chip: &std::ffi::OsStr = CHIP.as_ref();
    probe_rs(
        exe,
        &[
            "download".as_ref(),
            "--chip".as_ref(),
            chip,
            elf.as_os_str(),
        ],
        "download",
    )?;
    probe_rs(exe, &["reset".as_ref(), "--chip".as_ref(), chip], "reset")?;
    Ok(Flashed::Board {
        elf,
        port: Some(port),
    })
}
