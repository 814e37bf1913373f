//! `sandjumper rig flash`: write the F407 firmware with the probe-rs CLI
//! (`probe-rs download --chip STM32F407VGTx ELF`, then `probe-rs reset`). probe-rs is not
//! linked in: it needs libusb/libudev to build; the CLI (`cargo install probe-rs-tools`) does
//! the same job. For `--link sil|pil|f407` there is nothing to flash.

use std::path::{Path, PathBuf};
use std::process::Command;

use clap::Args;

use super::{SimLink, TargetArgs};
use sandjumper_output::CliError;
use sandjumper_rig::firmware_image::{Board, check_elf};

/// The board's chip as probe-rs names it.
pub const CHIP: &str = "STM32F407VGTx";
/// Where `cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release` puts
/// the F407 firmware.
pub const DEFAULT_F407_ELF: &str = sandjumper_rig::firmware_image::F407_ELF;

/// `rig flash`.
#[derive(Debug, Clone, Args)]
pub struct FlashArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// The probe-rs executable.
    #[arg(long, value_name = "PATH", default_value = "probe-rs")]
    pub probe_rs: PathBuf,
}

fn on_path(exe: &Path) -> bool {
    if exe.components().count() > 1 {
        return exe.is_file();
    }
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(exe).is_file()))
}

/// Run `rig flash`.
pub fn run(a: &FlashArgs) -> Result<(), CliError> {
    if let Some(link) = a.target.controller.link {
        let what = match link {
            SimLink::Sil => "--link sil runs the core's controller in this process",
            SimLink::Pil => "--link pil: QEMU loads the firmware ELF (--firmware) at every start",
            SimLink::F407 => {
                "--link f407: the virtual board loads the F407 ELF (--firmware) at every start"
            }
        };
        println!("nothing to flash: {what}");
        return Ok(());
    }
    let elf = a
        .target
        .firmware
        .clone()
        .unwrap_or_else(|| PathBuf::from(DEFAULT_F407_ELF));
    if !elf.is_file() {
        return Err(CliError::input(format!(
            "firmware ELF {} not found (build it with `cargo build -p sandjumper-firmware \
             --target thumbv7em-none-eabihf --release`, or give --firmware ELF)",
            elf.display()
        )));
    }
    if !on_path(&a.probe_rs) {
        return Err(CliError::input(format!(
            "probe-rs not found ({}): install it with `cargo install probe-rs-tools`, or give \
             --probe-rs PATH",
            a.probe_rs.display()
        )));
    }
    // probe-rs must not be handed the emulated board's image (or anything else).
    check_elf(&elf, Board::F407).map_err(|e| CliError::input(e.to_string()))?;
    let step = |args: &[&std::ffi::OsStr], what: &str| -> Result<(), CliError> {
        let out = Command::new(&a.probe_rs)
            .args(args)
            .output()
            .map_err(|e| CliError::input(format!("cannot run {}: {e}", a.probe_rs.display())))?;
        if out.status.success() {
            return Ok(());
        }
        let stderr = String::from_utf8_lossy(&out.stderr);
        let hint = if stderr.to_lowercase().contains("no probe") {
            " (is the debug probe plugged in?)"
        } else {
            ""
        };
        Err(CliError::input(format!(
            "probe-rs {what} failed ({}){hint}: {}",
            out.status,
            stderr.trim()
        )))
    };
    step(
        &[
            "download".as_ref(),
            "--chip".as_ref(),
            CHIP.as_ref(),
            elf.as_os_str(),
        ],
        "download",
    )?;
    step(
        &["reset".as_ref(), "--chip".as_ref(), CHIP.as_ref()],
        "reset",
    )?;
    println!("flashed {} to the {CHIP}", elf.display());
    if let Some(port) = &a.target.controller.port {
        println!("the board talks on {port}: try `sandjumper rig status --port {port}`");
    }
    Ok(())
}
