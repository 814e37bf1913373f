//! One jump through the loop with the controller in this process (software in the loop):
//! the same call `sandjumper hil --link sil --kind stutter --freq 10` makes.
//!
//! Run it with `cargo run -p sandjumper-rig --example jump_sil` (a second or two).

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil_command::{self, HilJump, HilRequest};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let request = HilRequest {
        link: LinkArg::Sil,
        kind: JumpKind::Stutter,
        freq_hz: 10.0,
        // No rendered camera frames: only the jump.
        camera_fps: 0,
        ..HilRequest::default()
    };
    let jump = hil_command::run(&request, &Silent)?;
    if let HilJump::Loop(run) = &jump {
        // The human summary `sandjumper hil` prints.
        print!("{run}");
    }
    println!(
        "jump height {:.2} mm, {} fault(s)",
        1e3 * jump.jump_height_m().unwrap_or(f64::NAN),
        jump.faults().len()
    );
    Ok(())
}
