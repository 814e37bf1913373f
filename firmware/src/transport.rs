//! Byte links of the emulated board to the host: two semihosting FIFOs (the default) or the
//! CMSDK UART0 (the smaller variant). Both carry the core protocol's COBS frames (0x00
//! delimited), one sensor frame in and one actuator frame out per control tick.

use crate::board::mps2_an386::UART0_BASE;
use crate::semihosting::{self, HostFile, OpenMode};

/// Why a link stopped working.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkError {
    /// The host end could not be opened (path given).
    Open,
    /// The host refused bytes (the reader went away).
    Write,
    /// The host reported a read error.
    Read,
}

/// A bidirectional byte stream to the host.
pub trait ByteLink {
    /// Blocks until at least one byte is available and returns how many were stored in `buf`;
    /// `Ok(0)` means the host closed the link (end of session).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError>;
    /// Sends all of `bytes`.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
}

/// Two host FIFOs opened through semihosting: sensor frames in, actuator frames out.
///
/// Opening order matters: the firmware opens `input` (reading) first, then `output` (writing),
/// and each open blocks until the host has opened the other end, so the host must open the
/// input FIFO for writing before the output FIFO for reading.
pub struct SemihostingFifos {
    input: HostFile,
    output: HostFile,
}

impl SemihostingFifos {
    /// Opens both FIFOs (blocking until the host has opened them too).
    pub fn open(input_path: &str, output_path: &str) -> Result<Self, LinkError> {
        let input = semihosting::open(input_path, OpenMode::Read).ok_or(LinkError::Open)?;
        let output = semihosting::open(output_path, OpenMode::Write).ok_or(LinkError::Open)?;
        Ok(Self { input, output })
    }
}

impl ByteLink for SemihostingFifos {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        semihosting::read(self.input, buf).ok_or(LinkError::Read)
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        semihosting::write_all(self.output, bytes)
            .then_some(())
            .ok_or(LinkError::Write)
    }
}

/// CMSDK APB UART (ARM DDI0479C): one-byte buffers each way, polled. QEMU connects UART0 to
/// its first `-serial` backend and does not pace it at the baud rate.
pub struct CmsdkUart {
    base: usize,
}

impl CmsdkUart {
    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const BAUDDIV: usize = 0x10;
    const STATE_TX_FULL: u32 = 1 << 0;
    const STATE_RX_FULL: u32 = 1 << 1;
    const CTRL_TX_RX_ENABLE: u32 = 0b11;
    /// The smallest divider the UART accepts (25 MHz / 16 = 1.5625 MBd nominal).
    const MIN_BAUDDIV: u32 = 16;

    /// UART0, enabled for transmit and receive, polled (no interrupts).
    pub fn uart0() -> Self {
        let uart = Self { base: UART0_BASE };
        uart.write_reg(Self::BAUDDIV, Self::MIN_BAUDDIV);
        uart.write_reg(Self::CTRL, Self::CTRL_TX_RX_ENABLE);
        uart
    }

    fn read_reg(&self, offset: usize) -> u32 {
        // SAFETY: an aligned word read of a CMSDK UART register on the mps2-an386 map.
        unsafe { core::ptr::read_volatile((self.base + offset) as *const u32) }
    }

    fn write_reg(&self, offset: usize, value: u32) {
        // SAFETY: an aligned word write of a CMSDK UART register on the mps2-an386 map.
        unsafe { core::ptr::write_volatile((self.base + offset) as *mut u32, value) }
    }
}

impl ByteLink for CmsdkUart {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        let mut n = 0;
        while n < buf.len() {
            if self.read_reg(Self::STATE) & Self::STATE_RX_FULL != 0 {
                buf[n] = self.read_reg(Self::DATA) as u8;
                n += 1;
            } else if n > 0 {
                break;
            }
        }
        Ok(n)
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        for &b in bytes {
            while self.read_reg(Self::STATE) & Self::STATE_TX_FULL != 0 {}
            self.write_reg(Self::DATA, u32::from(b));
        }
        Ok(())
    }
}
