//! What the STM32F407 does when the firmware itself fails: drive disabled and zero force first
//! (raw register writes, no HAL state needed), then a defmt report over RTT, then a stop.
//!
//! Our own panic handler rather than `panic-probe`: panic-probe prints before anything else,
//! and the drive must be made safe before anything else. The behaviour otherwise matches it
//! (report over defmt, then HardFault so `probe-rs run` shows a backtrace).
//!
//! After a HardFault the core halts in the handler (a breakpoint if a debugger is attached); the
//! independent watchdog then resets the chip, and the drive enable pin, an input with a
//! pull-down after reset, keeps the drive off.

use crate::board::f407::force_safe_state;
use cortex_m::peripheral::DCB;
use cortex_m_rt::{ExceptionFrame, exception};
use defmt_rtt as _;

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    force_safe_state();
    cortex_m::interrupt::disable();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

#[defmt::panic_handler]
fn defmt_panic() -> ! {
    force_safe_state();
    cortex_m::asm::udf()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    force_safe_state();
    defmt::error!(
        "HardFault: pc={=u32:#x} lr={=u32:#x}",
        frame.pc(),
        frame.lr()
    );
    loop {
        if DCB::is_debugger_attached() {
            cortex_m::asm::bkpt();
        }
    }
}
