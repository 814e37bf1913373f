//! TIM6 and TIM7, the basic timers of RM0090 chapter 20 (rigless binds no model to them): the
//! prescaler and auto-reload count the APB1 timer clock, and every update sets `UIF` and, with
//! `UIE`, raises the instance's one interrupt line (TIM7: IRQ 55). Update events are scheduled in
//! virtual time, so a 10 kHz tick is exactly 100,000 ns apart. Each period is counted on the
//! clock the timer has when it starts (RM0090 6.2, the timer clock is APB1's, doubled when
//! APB1's prescaler divides): a clock-security fall-back to the 16 MHz HSI (6.2.7) slows the
//! tick from the next update on, as on silicon (10 kHz on the 84 MHz timer clock becomes about
//! 952 Hz on 8 MHz).
//!
//! Its master-mode output (TRGO, RM0090 20.4.2): with `MMS` 010 every update event is a TRGO,
//! which the DAC can take as its trigger ([`BasicTimer::last_trgo_ns`]).
//!
//! Left out: one-pulse mode, `URS`, `ARPE` buffering (a new `ARR` applies at once), the counter's
//! own value (`CNT` reads the register file), the other master modes (reset, enable).

use rigless::device::{Device, DeviceContext, RegisterFile};
use rigless::soc::stm32f427::generated::tim6;
use rigless::time::{EventId, VirtualNanos};

/// One basic timer.
#[derive(Debug, Default)]
pub struct BasicTimer {
    /// Its input clock (APB1 timer clock), Hz: set by the board from the clock tree before
    /// every access.
    pub clock_hz: u64,
    next: Option<EventId>,
    period_ns: u64,
    /// Update events since reset.
    pub updates: u64,
    /// Virtual time of the last update event, ns.
    pub last_update_ns: u64,
    /// Stopped by a fault ([`BasicTimer::halt`]) until the next reset.
    halted: bool,
    /// `CR2.MMS` is 010: each update event is a TRGO.
    trgo_on_update: bool,
    /// Virtual time of the last TRGO, ns.
    pub last_trgo_ns: Option<u64>,
}

impl BasicTimer {
    /// Nanoseconds between two update events, 0 while stopped.
    pub fn period_ns(&self) -> u64 {
        if self.next.is_some() {
            self.period_ns
        } else {
            0
        }
    }

    /// The timer stops for good (its clock gated, its update events lost), until a reset.
    pub fn halt(&mut self) {
        self.halted = true;
        self.next = None;
    }

    fn reschedule(&mut self, r: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        let cr1 = r.get(tim6::Register::Cr1);
        if cr1 & 1 == 0 || self.clock_hz == 0 || self.halted {
            self.next = None;
            return;
        }
        let psc = r.get(tim6::Register::Psc) + 1;
        let arr = r.get(tim6::Register::Arr) + 1;
        self.period_ns = (psc * arr * 1_000_000_000) / self.clock_hz;
        self.next = Some(cx.schedule(VirtualNanos(cx.now().0 + self.period_ns.max(1))));
    }
}

impl Device for BasicTimer {
    type Register = tim6::Register;
    fn write(
        &mut self,
        reg: tim6::Register,
        _v: u64,
        r: &mut RegisterFile,
        cx: &mut DeviceContext<'_>,
    ) {
        match reg {
            tim6::Register::Cr1 | tim6::Register::Psc | tim6::Register::Arr => {
                self.reschedule(r, cx)
            }
            tim6::Register::Sr => {
                if r.get(tim6::Register::Sr) & 1 == 0 {
                    cx.lower(0);
                }
            }
            tim6::Register::Egr => r.set(tim6::Register::Egr, 0),
            tim6::Register::Cr2 => {
                self.trgo_on_update = (r.get(tim6::Register::Cr2) >> 4) & 0b111 == 0b010;
            }
            _ => {}
        }
    }
    fn on_event(&mut self, event: EventId, r: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        if self.next != Some(event) {
            return;
        }
        self.updates += 1;
        self.last_update_ns = cx.now().0;
        if self.trgo_on_update {
            self.last_trgo_ns = Some(self.last_update_ns);
        }
        r.set(tim6::Register::Sr, 1);
        if r.get(tim6::Register::Dier) & 1 != 0 {
            cx.raise(0);
        }
        // The next period on the clock the timer has now (the board keeps `clock_hz` current).
        self.reschedule(r, cx);
    }
    fn reset(&mut self) {
        *self = Self {
            clock_hz: self.clock_hz,
            ..Self::default()
        };
    }
}
