//! What the STM32F407 does when the firmware itself fails: drive disabled and zero force first,
//! then a defmt report over RTT, then a stop that the independent watchdog ends with a reset.
//!
//! Our own panic handler rather than `panic-probe`: panic-probe prints before anything else,
//! and the drive must be made safe before anything else. The behaviour otherwise matches it
//! (report over defmt, then HardFault so `probe-rs run` shows a backtrace).
//!
//! The HardFault handler's first instructions use registers only: a stack overflow (flip-link
//! puts the stack at the bottom of RAM, so an overflow faults instead of corrupting data)
//! leaves the stack pointer below RAM, and anything that pushes there faults again and locks
//! the core up with the enable line still high. So the entry, in assembly, drops the enable
//! line and writes the zero-force DAC code, then moves the stack pointer back to the top of the
//! stack and only then calls Rust ([`hard_fault_after_safe`]).
//!
//! After a fault the core stops in a loop (one breakpoint first if a debugger has been
//! attached since power-up); the independent watchdog, which keeps counting while the core is
//! halted, then resets the chip. From reset until `init` configures it, PE7 is a floating input:
//! the board must hold the drive's enable line low with an external pull-down (see
//! `docs/firmware.md`, wiring).

use crate::board::f407::{
    DAC_DHR12R1, DAC_DHR12R2, ENABLES_OFF, GPIOE_BSRR, TIM3_CCR1, force_safe_state,
};
use crate::drive::ZERO_FORCE_CODE;
use cortex_m::peripheral::DCB;
use defmt_rtt as _;

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // Mask first: the control tick must not preempt and re-enable the drive.
    cortex_m::interrupt::disable();
    force_safe_state();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

#[defmt::panic_handler]
fn defmt_panic() -> ! {
    cortex_m::interrupt::disable();
    force_safe_state();
    cortex_m::asm::udf()
}

// The HardFault vector (cortex-m-rt's vector table takes the `HardFault` symbol). Registers
// only until the stack pointer is valid again:
//   1. drive and lift enables low (GPIOE BSRR reset bits), 2. DAC channel 1 to the zero-force
//   code, channel 2 (blower) to 0 V, TIM3 CCR1 (shaker duty) to 0,
//   3. r0 = the faulting stack pointer, MSP = the top of the stack, 4. branch to Rust.
core::arch::global_asm!(
    ".section .HardFault.user, \"ax\"",
    ".global HardFault",
    ".type HardFault, %function",
    ".thumb_func",
    "HardFault:",
    "cpsid i",
    "ldr r0, ={bsrr}",
    "ldr r1, ={enable_off}",
    "str r1, [r0]",
    "ldr r0, ={dac}",
    "ldr r1, ={zero}",
    "str r1, [r0]",
    "ldr r0, ={blower}",
    "movs r1, #0",
    "str r1, [r0]",
    "ldr r0, ={shaker}",
    "str r1, [r0]",
    "mrs r0, msp",
    "ldr r1, =_stack_start",
    "msr msp, r1",
    "b {after}",
    ".ltorg",
    bsrr = const GPIOE_BSRR,
    enable_off = const ENABLES_OFF,
    dac = const DAC_DHR12R1,
    blower = const DAC_DHR12R2,
    shaker = const TIM3_CCR1,
    zero = const ZERO_FORCE_CODE as u32,
    after = sym hard_fault_after_safe,
);

/// RAM (the stack lives in it): where a stacked exception frame can be read.
const RAM: core::ops::Range<u32> = 0x2000_0000..0x2002_0000;

/// The rest of the HardFault handler, on a valid stack with the drive already safe: report the
/// faulting pc and lr if the stacked frame is readable, then stop.
///
/// # Safety
/// Called only from the `HardFault` entry above, with `faulting_sp` the stack pointer at the
/// fault.
#[unsafe(no_mangle)]
unsafe extern "C" fn hard_fault_after_safe(faulting_sp: u32) -> ! {
    force_safe_state();
    if RAM.contains(&faulting_sp) && RAM.contains(&(faulting_sp + 32)) {
        // SAFETY: the eight words of the exception frame lie in RAM (checked above).
        let (lr, pc) = unsafe {
            let frame = faulting_sp as *const u32;
            (frame.add(5).read_volatile(), frame.add(6).read_volatile())
        };
        defmt::error!("HardFault: pc={=u32:#x} lr={=u32:#x}", pc, lr);
    } else {
        defmt::error!(
            "HardFault with the stack pointer at {=u32:#x}, outside RAM (stack overflow?)",
            faulting_sp
        );
    }
    if DCB::is_debugger_attached() {
        cortex_m::asm::bkpt();
    }
    loop {
        cortex_m::asm::nop();
    }
}

/// Any interrupt or exception without a handler of its own (a vector the firmware never meant
/// to enable): the whole safe state, a report, then the same stop as a HardFault (the watchdog
/// resets the chip).
#[cortex_m_rt::exception]
unsafe fn DefaultHandler(irqn: i16) {
    cortex_m::interrupt::disable();
    force_safe_state();
    defmt::error!("unexpected exception or interrupt {=i16}", irqn);
    if DCB::is_debugger_attached() {
        cortex_m::asm::bkpt();
    }
    loop {
        cortex_m::asm::nop();
    }
}

/// The clock security system's NMI (enabled in `board::init`): the crystal stopped and the part
/// fell back to its 16 MHz HSI, so every rate (the tick, USB, the PWM) is wrong. The whole safe
/// state, a report, then the same stop as a HardFault (the watchdog resets the chip; the
/// start-up's bounded wait for the crystal then reports it).
#[cortex_m_rt::exception]
unsafe fn NonMaskableInt() {
    cortex_m::interrupt::disable();
    force_safe_state();
    defmt::error!("clock security: the 8 MHz crystal (HSE) stopped; the rig is stopped");
    loop {
        cortex_m::asm::nop();
    }
}
