//! What the clock tree does to the core: its instruction rate and its NMI input, followed after
//! every access to the RCC or the flash interface and at every stop, resets included, by
//! whichever driver runs the board (`run.rs`'s, and the USB tests' own).

use std::num::NonZeroU64;

use rigless::device::Level;
use rigless::emulator::{self, Host};
use rigless::soc::stm32f427::generated::rcc::{Register as RccRegister, cir};

use crate::board::{F407, NMI_INPUT, RESET_INSTRUCTION_RATE};

/// The RCC's and the flash interface's registers (RM0090 table 1): an access there may change
/// the clock.
pub const CLOCK_REGISTERS: std::ops::Range<u64> = 0x4002_3800..0x4002_4000;

/// When the clock tree may have changed at `settled`, its virtual time, ns: at every stop (a
/// reset's among them: rigless settles the stop after the models' reset, so the core is back on
/// the HSI's rate before its first instruction) and after every access to [`CLOCK_REGISTERS`].
/// The driver then follows the clock ([`CoreClock::follow`]).
pub fn clock_may_have_changed_at(settled: &emulator::Settled) -> Option<u64> {
    match settled {
        emulator::Settled::Stop(stop) => Some(stop.at.0),
        emulator::Settled::Access { access, .. } if CLOCK_REGISTERS.contains(&access.address) => {
            Some(access.virtual_time.0)
        }
        _ => None,
    }
}

/// The core's rate and NMI input as the board last set them.
#[derive(Debug, Clone)]
pub struct CoreClock {
    /// The instructions a second the core was last given.
    rate_hz: u64,
    /// Every change of rate: (virtual time ns, instructions a second).
    pub rates: Vec<(u64, u64)>,
    /// The level the board drives on the core's NMI input.
    nmi_high: bool,
}

impl Default for CoreClock {
    /// The core out of reset: the HSI's rate, the NMI input low.
    fn default() -> Self {
        Self {
            rate_hz: RESET_INSTRUCTION_RATE.get(),
            rates: Vec::new(),
            nmi_high: false,
        }
    }
}

impl CoreClock {
    /// The level the board drives on the NMI input now.
    pub fn nmi_high(&self) -> bool {
        self.nmi_high
    }

    /// The core's side of the clock tree as `mcu` has it at `at_ns`:
    /// - the instruction rate: one instruction a cycle of HCLK (RM0090 6.2: the core runs on
    ///   HCLK; 16 MHz on the HSI from reset, 168 MHz on the PLL). A core with no clock (HCLK 0:
    ///   the crystal stopped under a PLL with no clock security) keeps its rate; the run's
    ///   driver holds it.
    /// - the NMI input: high while `RCC_CIR.CSSF` is set, low once `CSSC` clears it (RM0090
    ///   6.2.7: "the NMI is executed indefinitely unless the CSS interrupt pending bit is
    ///   cleared"); the core pends the NMI again at each return while it stays high.
    pub fn follow(&mut self, mcu: &mut F407, host: &mut dyn Host, at_ns: u64) {
        // TIM7's next period on the clock as this access left it.
        mcu.clock_the_tick_timer();
        let (rcc, regs) = mcu.part.clocks();
        let hclk = rcc.hclk(regs);
        let css_pending = cir::CSSF.is_set(regs.get(RccRegister::Cir));
        if hclk != self.rate_hz
            && let Some(rate) = NonZeroU64::new(hclk)
        {
            self.rate_hz = hclk;
            self.rates.push((at_ns, hclk));
            host.set_instruction_rate(rate);
        }
        if css_pending != self.nmi_high {
            self.nmi_high = css_pending;
            let line = emulator::InterruptLine::new(NMI_INPUT)
                .expect("the NMI input is a line the emulator numbers");
            host.set_interrupt(line, if css_pending { Level::High } else { Level::Low });
        }
    }
}
