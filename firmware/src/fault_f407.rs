//! What the STM32F407 does when the firmware itself fails: drive disabled and zero force first
//! (raw register writes, no HAL state needed), then report over defmt and stop.
//!
//! - panic: `panic-probe` prints the message over RTT after our hook has made the drive safe.
//! - HardFault: make safe, log the exception frame, halt (the watchdog then resets the chip,
//!   which keeps the drive disabled: the enable pin resets to an input with a pull-down).

use crate::board::f407::force_safe_state;
use cortex_m_rt::{ExceptionFrame, exception};
use defmt_rtt as _;
use panic_probe as _;

/// Runs before panic-probe prints anything (panic-probe calls `defmt::panic` hook first? no:
/// we register through `#[defmt::panic_handler]`, which panic-probe's `print-defmt` uses).
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    force_safe_state();
    cortex_m::asm::udf()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    force_safe_state();
    defmt::error!(
        "HardFault at pc={=u32:#x} lr={=u32:#x}",
        frame.pc(),
        frame.lr()
    );
    loop {
        cortex_m::asm::bkpt();
    }
}
