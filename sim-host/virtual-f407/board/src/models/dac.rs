//! The DAC of RM0090 chapter 14, both channels, as the volts on PA4 and PA5 (rigless binds no
//! model to it). A write of a 12-bit right-aligned holding register moves the output at once
//! (no trigger: `TENx` clear, the only mode the firmware uses; with a trigger the code waits in
//! `DHRx`). The output buffer is modelled as the datasheet states it (DS8626 table 70): with the
//! buffer on (`BOFFx` clear) the output is linear only between 0.2 V and VDDA - 0.2 V and
//! clips there; with it off the output spans 0 V to VDDA. A disabled channel (`ENx` clear)
//! drives nothing: 0 V here (the drive's input then reads -300 N through the board's stage).
//!
//! Left out: DMA, the noise and triangle generators, dual-channel registers, 8-bit and
//! left-aligned holding registers (the firmware writes `DHR12R1`/`DHR12R2` only; the others are
//! counted in `other_writes`), settling time.

use rigless::device::{Device, DeviceContext, RegisterFile};
use rigless::soc::stm32f427::generated::dac;

/// The analog supply and reference, V.
pub const VDDA_V: f64 = 3.3;
/// How close to either rail the buffered output stays linear, V (DS8626 table 70).
pub const BUFFER_HEADROOM_V: f64 = 0.2;

/// Both DAC channels.
#[derive(Debug, Default)]
pub struct Dac {
    codes: [u16; 2],
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
    /// The 12-bit code channel `ch` (0 or 1) converts.
    pub fn code(&self, ch: usize) -> u16 {
        self.codes[ch]
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
        let v = f64::from(self.codes[ch]) * VDDA_V / 4095.0;
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
                self.cr = r.get(dac::Register::Cr);
                return;
            }
            dac::Register::Dhr12r1 => 0,
            dac::Register::Dhr12r2 => 1,
            dac::Register::Swtrigr => return,
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
        let code = (v & 0xFFF) as u16;
        self.codes[ch] = code;
        r.set(
            if ch == 0 {
                dac::Register::Dor1
            } else {
                dac::Register::Dor2
            },
            u64::from(code),
        );
    }
    fn reset(&mut self) {
        *self = Self::default();
    }
}
