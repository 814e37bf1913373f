//! The same jump as `jump_sil`, run by the F407 release binary on the virtual STM32F407 board
//! (free on its own tick, the robot behind its pins): `sandjumper hil --link f407`.
//!
//! The virtual board is a program of its own with its own toolchain (rustc 1.98.0), built by
//! `sim-host/virtual-f407/build.sh`, and it runs the F407 firmware ELF built by
//! `cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release`. Without them
//! this example says what is missing and exits cleanly.
//!
//! Run it from the workspace root with
//! `cargo run -p sandjumper-rig --example jump_virtual_board` (some seconds).

use std::path::Path;

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil::virtual_board::VirtualBoardConfig;
use sandjumper_rig::hil_command::{self, HilRequest};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let board = VirtualBoardConfig::new(Path::new("."));
    for (what, path) in [("virtual board", &board.program), ("F407 ELF", &board.elf)] {
        if !path.is_file() {
            println!(
                "the {what} is not available ({} missing): nothing to run",
                path.display()
            );
            return Ok(());
        }
    }
    let request = HilRequest {
        link: LinkArg::F407,
        kind: JumpKind::Stutter,
        freq_hz: 10.0,
        camera_fps: 0,
        ..HilRequest::default()
    };
    let jump = hil_command::run(&request, &Silent)?;
    // `hil --json`'s object: the rig tool's record, with `jump_height_m` as on every link.
    println!("{}", jump.json()?);
    Ok(())
}
