//! Test images for the bring-up (docs/bringup.md step 4) and the virtual board's fault tests: a
//! fault built in with `SANDJUMPER_INJECT=panic|hardfault|stack-overflow|unhandled-interrupt`
//! at build time, fired
//! by the control tick [`INJECT_AT_TICK`] ticks after start-up, with the drive as the tick left
//! it. A normal build has none: [`INJECTED`] is `None` and the tick's check compiles away.
//!
//! ```sh
//! SANDJUMPER_INJECT=stack-overflow cargo build -p sandjumper-firmware \
//!     --target thumbv7em-none-eabihf --release --target-dir target/inject-stack-overflow
//! ```

/// A fault a test image fires.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Injected {
    /// `panic!` in the control tick.
    Panic,
    /// An undefined instruction in the control tick (a HardFault).
    HardFault,
    /// Unbounded recursion with a large frame: flip-link's stack at the bottom of RAM makes
    /// the overflow a HardFault with the stack pointer below RAM.
    StackOverflow,
    /// An interrupt with no handler of its own (EXTI0) enabled and pended: the default handler.
    UnhandledInterrupt,
}

/// The fault this image fires, from `SANDJUMPER_INJECT` at build time.
pub const INJECTED: Option<Injected> = match option_env!("SANDJUMPER_INJECT") {
    None => None,
    Some(text) => Some(parse(text)),
};

/// Ticks after start-up when it fires (2 s at 10 kHz).
pub const INJECT_AT_TICK: u32 = 20_000;

const fn parse(text: &str) -> Injected {
    let b = text.as_bytes();
    if eq(b, b"panic") {
        Injected::Panic
    } else if eq(b, b"hardfault") {
        Injected::HardFault
    } else if eq(b, b"stack-overflow") {
        Injected::StackOverflow
    } else if eq(b, b"unhandled-interrupt") {
        Injected::UnhandledInterrupt
    } else {
        panic!("SANDJUMPER_INJECT must be panic, hardfault, stack-overflow or unhandled-interrupt")
    }
}

const fn eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Fire the image's fault if `tick` is its tick.
#[inline(always)]
pub fn at_tick(tick: u32) {
    if let Some(kind) = INJECTED
        && tick == INJECT_AT_TICK
    {
        fire(kind);
    }
}

#[inline(never)]
fn fire(kind: Injected) {
    match kind {
        Injected::Panic => panic!("injected by SANDJUMPER_INJECT=panic"),
        Injected::HardFault => cortex_m::asm::udf(),
        Injected::StackOverflow => {
            core::hint::black_box(overflow(0));
        }
        Injected::UnhandledInterrupt => {
            use stm32f4xx_hal::pac::Interrupt;
            // SAFETY: a test image; EXTI0 is bound to no task, so its vector is the default
            // handler, at priority 0 (above the tick's): it runs at once.
            unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::EXTI0) };
            cortex_m::peripheral::NVIC::pend(Interrupt::EXTI0);
        }
    }
}

#[inline(never)]
#[allow(unconditional_recursion)]
fn overflow(depth: u32) -> u32 {
    let frame = core::hint::black_box([depth; 256]);
    overflow(depth + 1).wrapping_add(frame[depth as usize % 256])
}
