//! Placeholder: the USB OTG FS device core and its virtual CDC-ACM host (being written).

use rigless::device::ErasedDevice;

/// Which part of the OTG FS core an access reaches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OtgBlock {
    /// `OTG_FS_GLOBAL`, 0x5000_0000.
    Global,
    /// `OTG_FS_HOST`, 0x5000_0400.
    Host,
    /// `OTG_FS_DEVICE`, 0x5000_0800.
    Device,
    /// `OTG_FS_PWRCLK`, 0x5000_0E00.
    PowerClock,
    /// The FIFO window, 0x5000_1000..0x5004_0000 (a board window).
    Fifo,
}

/// The core (placeholder: answers nothing).
#[derive(Debug, Default)]
pub struct OtgFs {}

impl OtgFs {
    /// A system reset of the MCU.
    pub fn reset(&mut self) {}
}

impl OtgFs {
    /// The model answering `block`, if any.
    pub fn block(&mut self, _block: OtgBlock) -> Option<&mut dyn ErasedDevice> {
        None
    }
}

/// Statistics (placeholder).
#[derive(Debug, Default)]
pub struct UsbStats {}

impl OtgFs {
    /// Cable in or out.
    pub fn set_attached(&mut self, _attached: bool) {}
    /// Bytes to the device.
    pub fn host_send(&mut self, _bytes: &[u8]) {}
    /// Bytes from the device.
    pub fn host_take_received(&mut self) -> Vec<u8> {
        Vec::new()
    }
    /// Configured.
    pub fn configured(&self) -> bool {
        false
    }
    /// Statistics.
    pub fn stats(&self) -> UsbStats {
        UsbStats::default()
    }
}
