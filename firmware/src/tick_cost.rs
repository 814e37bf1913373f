//! Measures what one control tick costs.
//!
//! - STM32F407: CPU cycles from the DWT cycle counter (168 per microsecond).
//! - Emulated board: guest instructions. Under QEMU `-icount shift=N` virtual time advances
//!   exactly 2^N ns per instruction, and SysTick counts that virtual time at the 25 MHz system
//!   clock, so SysTick counts are proportional to instructions. The ratio is calibrated at boot
//!   against a loop of known length, which makes the figure independent of the shift chosen
//!   (shift 6 gives 1.6 counts per instruction, i.e. better than one instruction resolution).

#[cfg(feature = "board-qemu")]
pub use systick::InstructionCounter;

#[cfg(feature = "board-qemu")]
mod systick {
    use cortex_m::peripheral::SYST;
    use cortex_m::peripheral::syst::SystClkSource;

    /// SysTick's 24-bit counter mask.
    const MASK: u32 = 0x00FF_FFFF;
    /// Iterations of the two-instruction calibration loop.
    const CALIBRATION_ITERATIONS: u32 = 50_000;

    /// Counts guest instructions between two points (see the module docs).
    pub struct InstructionCounter {
        /// SysTick counts per 1024 instructions, calibrated.
        counts_per_1024: u32,
        /// Counts that a back-to-back `start`/`elapsed` pair itself takes.
        overhead_counts: u32,
    }

    impl InstructionCounter {
        /// Starts SysTick free-running from the processor clock and calibrates it. Returns
        /// `None` if SysTick does not advance (no `-icount`, or not under QEMU).
        pub fn new(mut syst: SYST) -> Option<Self> {
            syst.disable_interrupt();
            syst.set_reload(MASK);
            syst.clear_current();
            syst.set_clock_source(SystClkSource::Core);
            syst.enable_counter();
            let start = SYST::get_current();
            // SAFETY: a register-only countdown loop: `subs` + `bne`, two instructions per
            // iteration, no memory access.
            unsafe {
                core::arch::asm!(
                    "1:",
                    "subs {n}, #1",
                    "bne 1b",
                    n = inout(reg) CALIBRATION_ITERATIONS => _,
                    options(nomem, nostack),
                );
            }
            let loop_counts = counts_between(start, SYST::get_current());
            let instructions = 2 * CALIBRATION_ITERATIONS;
            let counts_per_1024 =
                u32::try_from(u64::from(loop_counts) * 1024 / u64::from(instructions)).ok()?;
            if counts_per_1024 == 0 {
                return None;
            }
            let mut counter = Self {
                counts_per_1024,
                overhead_counts: 0,
            };
            let start = counter.start();
            let empty = counts_between(start, SYST::get_current());
            counter.overhead_counts = empty;
            Some(counter)
        }

        /// A reading to pass to [`Self::instructions_since`].
        #[inline(always)]
        pub fn start(&self) -> u32 {
            SYST::get_current()
        }

        /// Instructions executed since `start` (rounded to the nearest, the measurement's own
        /// two reads removed). Valid up to ~10 million instructions (SysTick wraps at 2^24).
        #[inline(always)]
        pub fn instructions_since(&self, start: u32) -> u32 {
            let counts =
                counts_between(start, SYST::get_current()).saturating_sub(self.overhead_counts);
            ((u64::from(counts) * 1024 + u64::from(self.counts_per_1024) / 2)
                / u64::from(self.counts_per_1024)) as u32
        }

        /// SysTick counts per 1024 instructions (1638 under `-icount shift=6`).
        pub fn counts_per_1024_instructions(&self) -> u32 {
            self.counts_per_1024
        }
    }

    /// SysTick counts down; the difference of two readings modulo 2^24.
    #[inline(always)]
    fn counts_between(earlier: u32, later: u32) -> u32 {
        earlier.wrapping_sub(later) & MASK
    }
}
