//! Which link closes the loop ([`LinkArg`]: the core in this process, the firmware in QEMU, a
//! board on a serial port), opening it ([`open_link`]), and a fault as a link reports it.

use std::time::Duration;

use serde::Serialize;

use super::link::{LinkError, RigLink};
use super::pil::{self, PilConfig};
use super::rig_model::RigModelConfig;
use super::run::rig_config;
use super::serial;
use super::sil::SilLink;
use crate::error::RigError;
use crate::firmware_image::{Board, check_elf};

/// Where the controller is.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum LinkArg {
    /// The core in this process.
    #[default]
    Sil,
    /// The firmware in QEMU over semihosting FIFOs.
    Pil,
    /// The F407 release ELF on the virtual board (free-running, coupled through its
    /// peripherals).
    F407,
    /// A board on a serial port.
    Serial(String),
}

impl std::fmt::Display for LinkArg {
    /// The link as the command line names it (`sil`, `pil`, `f407`, `serial:PATH`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Sil => write!(f, "sil"),
            Self::Pil => write!(f, "pil"),
            Self::F407 => write!(f, "f407"),
            Self::Serial(p) => write!(f, "serial:{p}"),
        }
    }
}

/// Parse a link as named on the command line: `sil`, `pil` or `serial:PATH`.
pub fn parse_link(s: &str) -> Result<LinkArg, String> {
    match s {
        "sil" => Ok(LinkArg::Sil),
        "pil" => Ok(LinkArg::Pil),
        "f407" => Ok(LinkArg::F407),
        _ => match s.strip_prefix("serial:") {
            Some(path) if !path.is_empty() => Ok(LinkArg::Serial(path.to_string())),
            _ => Err(format!(
                "unknown link `{s}` (allowed: sil, pil, f407, serial:PATH e.g. serial:/dev/ttyACM0)"
            )),
        },
    }
}

/// A fault as reported.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FaultEntry {
    /// Stable code (README table).
    pub code: u8,
    /// Name.
    pub name: &'static str,
    /// Controller tick it was latched on.
    pub tick: u32,
}

/// Open the link `arg` for a rig with `model_config`.
pub fn open_link(
    arg: &LinkArg,
    model_config: &RigModelConfig,
    firmware: &std::path::Path,
) -> Result<Box<dyn RigLink>, RigError> {
    let fail = |e: LinkError| RigError::input(format!("cannot open the link: {e}"));
    Ok(match arg {
        LinkArg::Sil => Box::new(SilLink::new(rig_config(model_config)).map_err(fail)?),
        LinkArg::Pil => {
            check_elf(firmware, Board::Emulated).map_err(|e| RigError::input(e.to_string()))?;
            Box::new(pil::start(&PilConfig::new(firmware)).map_err(fail)?)
        }
        LinkArg::F407 => {
            let mut cfg = super::virtual_board::VirtualBoardConfig::new(std::path::Path::new("."));
            cfg.elf = firmware.to_path_buf();
            Box::new(super::virtual_board::start(&cfg).map_err(fail)?)
        }
        LinkArg::Serial(path) => {
            Box::new(serial::start(path, Duration::from_secs(2)).map_err(fail)?)
        }
    })
}

impl FaultEntry {
    /// The entry of a fault report.
    pub fn of(f: &sandjumper_core::protocol::FaultReport) -> Self {
        Self {
            code: f.code.code(),
            name: f.code.name(),
            tick: f.tick,
        }
    }
}
