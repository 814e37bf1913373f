//! The DAC of RM0090 chapter 14, both channels, as the volts on PA4 and PA5 (rigless binds no
//! model to it). A channel converts its output register (`DORx`); a write of its 12-bit
//! right-aligned holding register (`DHRx`) reaches `DORx` at once when its trigger is off
//! (`TENx` clear, the only mode the firmware uses), and with the trigger on (`TENx` set) only on
//! the trigger `TSELx` selects (RM0090 14.3.6, 14.3.7): the software trigger (`TSEL` 111, a
//! `SWTRIGR` bit) or TIM7's TRGO (`TSEL` 010, when TIM7's master mode selects its update event,
//! `MMS` 010). The other trigger sources (TIM6, TIM8, TIM5, TIM2, TIM4, EXTI 9) are not modelled
//! on this board and never fire: a channel waiting for them keeps its output, which from reset
//! is code 0 (0 V: -300 N through the drive's stage). The output buffer is modelled as the
//! datasheet states it (DS8626 table 70): with the buffer on (`BOFFx` clear) the output is
//! linear only between 0.2 V and VDDA - 0.2 V and clips there; with it off the output spans
//! 0 V to VDDA. A disabled channel (`ENx` clear) drives nothing: 0 V here.
//!
//! Left out: DMA, the noise and triangle generators, dual-channel registers, 8-bit and
//! left-aligned holding registers (the firmware writes `DHR12R1`/`DHR12R2` only; the others are
//! counted in `other_writes`), the three APB1 cycles between a trigger and `DORx`, settling
//! time. A transfer on TIM7's trigger shows in the volts at once and in the `DORx` register at
//! the channel's next holding-register write.

use rigless::device::{Device, DeviceContext, RegisterFile};
use rigless::soc::stm32f427::generated::dac;

/// The analog supply and reference, V.
pub const VDDA_V: f64 = 3.3;
/// How close to either rail the buffered output stays linear, V (DS8626 table 70).
pub const BUFFER_HEADROOM_V: f64 = 0.2;

/// `TSELx`: the software trigger.
pub const TSEL_SOFTWARE: u8 = 0b111;
/// `TSELx`: TIM7's TRGO.
pub const TSEL_TIM7: u8 = 0b010;

/// Both DAC channels.
#[derive(Debug, Default)]
pub struct Dac {
    /// The output registers (`DORx`) as last transferred.
    codes: [u16; 2],
    /// The holding registers (`DHRx`) and when each was written (or `CR` last written after
    /// that), ns: a TIM7 trigger at or after it moves the holding register out.
    held: [u16; 2],
    held_ns: [u64; 2],
    /// TIM7's last TRGO, ns (its update event while its master mode selects it): the board sets
    /// it before every access and before the outputs are read.
    pub tim7_trgo_ns: Option<u64>,
    /// Holding-register writes since reset.
    pub writes: u64,
    /// Writes of registers this model does not convert (8-bit, left-aligned, dual).
    pub other_writes: u64,
    cr: u64,
    /// Virtual time of the last channel-1 write and the spread of the intervals between them
    /// (min, max), ns: the control tick's output jitter as a scope on PA4 would show it.
    last_ch1_write_ns: Option<u64>,
    /// (shortest, longest) interval between two channel-1 writes, ns.
    pub ch1_interval_ns: Option<(u64, u64)>,
    /// The control tick's last update event, ns (the board sets it before every access).
    pub tick_ns: u64,
    /// (earliest, latest) channel-1 write after the tick's update event, ns: where in the tick
    /// the force command lands.
    pub ch1_offset_ns: Option<(u64, u64)>,
}

impl Dac {
    /// The 12-bit code channel `ch` (0 or 1) converts: its output register, or its holding
    /// register once TIM7's trigger came after the write when the channel waits for it.
    pub fn code(&self, ch: usize) -> u16 {
        if self.waits_for(ch, TSEL_TIM7) && self.tim7_trgo_ns.is_some_and(|t| t >= self.held_ns[ch])
        {
            self.held[ch]
        } else {
            self.codes[ch]
        }
    }

    /// Whether channel `ch`'s trigger is on (`TENx`).
    pub fn triggered(&self, ch: usize) -> bool {
        self.cr & (1 << (2 + 16 * ch)) != 0
    }

    /// Channel `ch`'s trigger selection (`TSELx`).
    pub fn trigger_source(&self, ch: usize) -> u8 {
        ((self.cr >> (3 + 16 * ch)) & 0b111) as u8
    }

    fn waits_for(&self, ch: usize, source: u8) -> bool {
        self.triggered(ch) && self.trigger_source(ch) == source
    }

    /// Channel `ch`'s holding register to its output register (a trigger, or no trigger).
    fn transfer(&mut self, ch: usize, r: &mut RegisterFile) {
        self.codes[ch] = self.held[ch];
        r.set(
            if ch == 0 {
                dac::Register::Dor1
            } else {
                dac::Register::Dor2
            },
            u64::from(self.codes[ch]),
        );
    }

    /// Whether channel `ch`'s output buffer is on.
    pub fn buffered(&self, ch: usize) -> bool {
        self.cr & (1 << (1 + 16 * ch)) == 0
    }

    /// Whether channel `ch` is enabled.
    pub fn enabled(&self, ch: usize) -> bool {
        self.cr & (1 << (16 * ch)) != 0
    }

    /// The volts channel `ch` drives now.
    pub fn volts(&self, ch: usize) -> f64 {
        if !self.enabled(ch) {
            return 0.0;
        }
        let v = f64::from(self.code(ch)) * VDDA_V / 4095.0;
        if self.buffered(ch) {
            v.clamp(BUFFER_HEADROOM_V, VDDA_V - BUFFER_HEADROOM_V)
        } else {
            v
        }
    }
}

impl Device for Dac {
    type Register = dac::Register;
    fn write(
        &mut self,
        reg: dac::Register,
        v: u64,
        r: &mut RegisterFile,
        cx: &mut DeviceContext<'_>,
    ) {
        let ch = match reg {
            dac::Register::Cr => {
                // A transfer TIM7's trigger made under the old settings stays made, and only a
                // trigger after this write counts under the new ones (RM0090 14.3.7).
                let now = cx.now().0;
                for ch in 0..2 {
                    if self.code(ch) != self.codes[ch] {
                        self.transfer(ch, r);
                    }
                    self.held_ns[ch] = self.held_ns[ch].max(now);
                }
                self.cr = r.get(dac::Register::Cr);
                return;
            }
            dac::Register::Dhr12r1 => 0,
            dac::Register::Dhr12r2 => 1,
            dac::Register::Swtrigr => {
                // SWTRIGx: a transfer on a channel waiting for it; cleared by hardware.
                for ch in 0..2 {
                    if v & (1 << ch) != 0 && self.waits_for(ch, TSEL_SOFTWARE) {
                        self.transfer(ch, r);
                    }
                }
                r.set(dac::Register::Swtrigr, 0);
                return;
            }
            _ => {
                self.other_writes += 1;
                return;
            }
        };
        self.writes += 1;
        if ch == 0 {
            let now = cx.now().0;
            // From 5 ms on: init's writes and the first tick are not the tick's rhythm.
            if let Some(last) = self.last_ch1_write_ns.filter(|_| now > 5_000_000) {
                let d = now - last;
                self.ch1_interval_ns = Some(match self.ch1_interval_ns {
                    None => (d, d),
                    Some((lo, hi)) => (lo.min(d), hi.max(d)),
                });
            }
            self.last_ch1_write_ns = Some(now);
            if now > 5_000_000 && now >= self.tick_ns {
                let d = now - self.tick_ns;
                self.ch1_offset_ns = Some(match self.ch1_offset_ns {
                    None => (d, d),
                    Some((lo, hi)) => (lo.min(d), hi.max(d)),
                });
            }
        }
        // A value TIM7's trigger moved out since the last write is the output now.
        if self.code(ch) != self.codes[ch] {
            self.transfer(ch, r);
        }
        self.held[ch] = (v & 0xFFF) as u16;
        self.held_ns[ch] = cx.now().0;
        if !self.triggered(ch) {
            self.transfer(ch, r);
        }
    }
    fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use rigless::mcu::Operate;
    use rigless::soc::Width;
    use rigless::time::VirtualNanos;

    use super::{TSEL_SOFTWARE, TSEL_TIM7};
    use crate::board::{F407, VirtualF407};

    const CR: u64 = 0x4000_7400;
    const SWTRIGR: u64 = 0x4000_7404;
    const DHR12R1: u64 = 0x4000_7408;
    const DOR1: u64 = 0x4000_742C;

    fn write(mcu: &mut F407, ns: u64, address: u64, value: u64) {
        mcu.write(VirtualNanos(ns), address, Width::W32, value)
            .expect("the write lands");
    }

    fn read(mcu: &mut F407, address: u64) -> u64 {
        mcu.read(VirtualNanos(0), address, Width::W32)
            .expect("the read lands")
    }

    /// Channel 1 enabled, unbuffered, its trigger `ten` with the source `tsel`.
    fn cr(ten: bool, tsel: u8) -> u64 {
        1 | (1 << 1) | (u64::from(ten) << 2) | (u64::from(tsel) << 3)
    }

    /// TIM7's last TRGO, as its model records it and the board hands it to the DAC.
    fn trgo(mcu: &mut F407, ns: Option<u64>) {
        mcu.tim7.last_trgo_ns = ns;
        mcu.dac.tim7_trgo_ns = ns;
    }

    fn board() -> VirtualF407 {
        let mut board = VirtualF407::new().expect("the board");
        write(&mut board.mcu, 0, 0x4002_3840, 1 << 29); // RCC_APB1ENR.DACEN
        board
    }

    /// RM0090 14.3.6: with TEN1 clear a holding-register write is the output at once.
    #[test]
    fn without_a_trigger_a_write_is_the_output_at_once() {
        let mut board = board();
        let mcu = &mut board.mcu;
        write(mcu, 1_000, CR, cr(false, 0));
        write(mcu, 2_000, DHR12R1, 3000);
        assert_eq!(mcu.dac.code(0), 3000);
        assert_eq!(read(mcu, DOR1), 3000);
        assert!((mcu.dac.volts(0) - 3000.0 * 3.3 / 4095.0).abs() < 1e-12);
    }

    /// RM0090 14.3.7: with TEN1 set a write waits in DHR1 for the trigger TSEL1 selects; a
    /// trigger this board does not model (TIM6's TRGO, TSEL 000) never comes, and the channel
    /// stays at its reset code 0 (0 V: -300 N through the drive's stage); the software trigger
    /// moves it, and SWTRIG1 reads back cleared.
    #[test]
    fn with_a_trigger_a_write_waits_for_it() {
        let mut board = board();
        let mcu = &mut board.mcu;
        write(mcu, 1_000, CR, cr(true, 0b000));
        write(mcu, 2_000, DHR12R1, 2048);
        assert_eq!(mcu.dac.code(0), 0, "TIM6 never triggers here");
        assert_eq!(mcu.dac.volts(0), 0.0);
        assert_eq!(read(mcu, DOR1), 0);
        // The software trigger selected: a SWTRIG1 write moves the held code out.
        write(mcu, 3_000, CR, cr(true, TSEL_SOFTWARE));
        assert_eq!(mcu.dac.code(0), 0, "selecting the trigger is not a trigger");
        write(mcu, 4_000, SWTRIGR, 1);
        assert_eq!(mcu.dac.code(0), 2048);
        assert_eq!(read(mcu, DOR1), 2048);
        assert_eq!(read(mcu, SWTRIGR), 0, "cleared by hardware");
        // The next write waits again.
        write(mcu, 5_000, DHR12R1, 100);
        assert_eq!(mcu.dac.code(0), 2048);
        // A software trigger for channel 2 only leaves channel 1 waiting.
        write(mcu, 6_000, SWTRIGR, 2);
        assert_eq!(mcu.dac.code(0), 2048);
    }

    /// RM0090 14.3.7 with TSEL 010: TIM7's TRGO (its update event, MMS 010) moves the held
    /// code out; a write after the last TRGO waits for the next one.
    #[test]
    fn tim7s_trigger_moves_a_held_write_at_its_next_update() {
        let mut board = board();
        let mcu = &mut board.mcu;
        write(mcu, 1_000, CR, cr(true, TSEL_TIM7));
        trgo(mcu, Some(500));
        write(mcu, 2_000, DHR12R1, 1234);
        assert_eq!(mcu.dac.code(0), 0, "the last TRGO came before the write");
        trgo(mcu, Some(100_000));
        assert_eq!(mcu.dac.code(0), 1234, "the next update moved it");
        // Written again before the next update: the output keeps 1234, and DOR1 shows it.
        write(mcu, 150_000, DHR12R1, 4000);
        assert_eq!(mcu.dac.code(0), 1234);
        assert_eq!(read(mcu, DOR1), 1234);
        trgo(mcu, Some(200_000));
        assert_eq!(mcu.dac.code(0), 4000);
        // No TRGO after this write (TIM7 stopped, or its master mode off update): it waits.
        write(mcu, 250_000, DHR12R1, 7);
        assert_eq!(mcu.dac.code(0), 4000);
        assert_eq!(read(mcu, DOR1), 4000);
    }

    /// A transfer TIM7's TRGO made stays made when `CR` changes after it (the trigger turned
    /// off, or another source selected), and a TRGO from before TIM7 was selected is no
    /// trigger for a write waiting now.
    #[test]
    fn a_control_write_keeps_what_the_trigger_moved_and_waits_for_a_new_one() {
        let mut board = board();
        let mcu = &mut board.mcu;
        write(mcu, 1_000, CR, cr(true, TSEL_TIM7));
        write(mcu, 2_000, DHR12R1, 1234);
        trgo(mcu, Some(100_000));
        assert_eq!(mcu.dac.code(0), 1234);
        // The trigger off: the output keeps what the TRGO moved.
        write(mcu, 150_000, CR, cr(true, TSEL_SOFTWARE));
        assert_eq!(mcu.dac.code(0), 1234);
        assert_eq!(read(mcu, DOR1), 1234);
        // A write waiting for the software trigger, then TIM7 selected again after a TRGO
        // that came before the selection: the write waits for the next TRGO.
        write(mcu, 160_000, DHR12R1, 99);
        trgo(mcu, Some(170_000));
        write(mcu, 180_000, CR, cr(true, TSEL_TIM7));
        assert_eq!(
            mcu.dac.code(0),
            1234,
            "a TRGO before the selection is no trigger"
        );
        trgo(mcu, Some(200_000));
        assert_eq!(mcu.dac.code(0), 99);
    }
}
