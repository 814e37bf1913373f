//! Which controller a rig tool program talks to ([`Target`]): a board on its serial port, or a
//! simulated one (`sil`, `pil`, the virtual F407 board), with its firmware and the drive
//! calibration sent when the session opens.

use std::path::{Path, PathBuf};
use std::time::Duration;

use sandjumper_output::parse::number_within;

use super::drive_calibration::{read_calibration, send_calibration};
use crate::error::RigError;
use crate::firmware_image::EMULATED_ELF;
use crate::hil::open::{LinkArg, open_link};
use crate::hil::rig_model::RigModelConfig;
use crate::hil::serial;
use crate::hil::virtual_board::{self, VirtualBoardConfig, VirtualLoad};
use crate::protocol::link::RigLink;

/// The controller of a rig tool program and how to reach it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Target {
    /// `Serial(PATH)`: the board on its USB serial port (the real rig); `Sil`, `Pil`, `F407`:
    /// a simulated controller against a simulated rig.
    pub link: LinkArg,
    /// Firmware ELF: for `Pil` the QEMU build (default [`EMULATED_ELF`]); for `F407` and
    /// flashing the F407 build (default: the virtual board's own default).
    pub firmware: Option<PathBuf>,
    /// The virtual board's program for `F407` (default:
    /// sim-host/virtual-f407/target/release/virtual-f407).
    pub virtual_board: Option<PathBuf>,
    /// Run the virtual board no faster than this many times real time (0.001..=1; `None`: as
    /// fast as the machine allows). Only with `F407`.
    pub board_pace: Option<f64>,
    /// A drive calibration file (`rig calibrate-drive --save`), sent when the session opens.
    pub drive_calibration: Option<PathBuf>,
}

impl Target {
    /// A simulated or real controller on `link`, everything else the defaults.
    pub fn on(link: LinkArg) -> Self {
        Self {
            link,
            ..Self::default()
        }
    }

    /// True when the rig is simulated (sil, pil, f407).
    pub fn is_simulated(&self) -> bool {
        !matches!(self.link, LinkArg::Serial(_))
    }

    /// True when the host plays the rig in lockstep (sil/pil); the virtual F407 board moves its
    /// own robot.
    pub fn host_plays_the_rig(&self) -> bool {
        matches!(self.link, LinkArg::Sil | LinkArg::Pil)
    }

    /// Open the link and send the saved drive calibration, if [`Target::drive_calibration`]
    /// names one. `load`: what a virtual F407 board's drive moves.
    pub fn open_with_load(
        &self,
        model: &RigModelConfig,
        load: Option<VirtualLoad>,
    ) -> Result<Box<dyn RigLink>, RigError> {
        let calibration = self
            .drive_calibration
            .as_deref()
            .map(read_calibration)
            .transpose()?;
        if self.board_pace.is_some() && self.link != LinkArg::F407 {
            return Err(RigError::input(
                "--board-pace paces the virtual board: it needs --link f407",
            ));
        }
        let mut link = if self.link == LinkArg::F407 {
            let mut cfg = VirtualBoardConfig::new(Path::new("."));
            if let Some(p) = &self.virtual_board {
                cfg.program = p.clone();
            }
            if let Some(elf) = &self.firmware {
                cfg.elf = elf.clone();
            }
            cfg.load = load;
            cfg.pace = self.board_pace;
            let board = virtual_board::start(&cfg).map_err(|e| {
                RigError::input(format!("cannot start the virtual F407 board: {e}"))
            })?;
            Box::new(board)
        } else {
            self.open_link(model)?
        };
        if let Some(cal) = calibration {
            send_calibration(link.as_mut(), cal)?;
        }
        Ok(link)
    }

    /// [`Target::open_with_load`] with nothing for a virtual board's drive to move.
    pub fn open(&self, model: &RigModelConfig) -> Result<Box<dyn RigLink>, RigError> {
        self.open_with_load(model, None)
    }

    fn open_link(&self, model: &RigModelConfig) -> Result<Box<dyn RigLink>, RigError> {
        let elf = self
            .firmware
            .clone()
            .unwrap_or_else(|| PathBuf::from(EMULATED_ELF));
        match &self.link {
            // A board that streams samples needs longer than a lockstep answer.
            LinkArg::Serial(path) => Ok(Box::new(
                serial::start(path, Duration::from_secs(2)).map_err(|e| {
                    RigError::input(format!("cannot open the board on {path}: {e}"))
                })?,
            )),
            other => open_link(other, model, &elf),
        }
    }
}

/// `--board-pace X`: the virtual board's pace, times real time (its program's range,
/// 0.001..=1).
pub fn parse_board_pace(s: &str) -> Result<f64, String> {
    number_within(s, |v| (0.001..=1.0).contains(&v)).ok_or_else(|| {
        format!(
            "`{s}` is not a board pace (allowed: 0.001..=1 times real time: a board run faster \
             than real time would see the host's 50 ms polls spread past its watchdogs)"
        )
    })
}
