//! The USB OTG full-speed core of RM0090 chapter 34 (Synopsys DWC OTG) in device mode, and a
//! virtual USB host on its port that enumerates it and runs a CDC-ACM port, all in virtual time.
//!
//! One [`OtgFs`] answers the four register blocks (`OTG_FS_GLOBAL`, `OTG_FS_HOST`,
//! `OTG_FS_DEVICE`, `OTG_FS_PWRCLK`) and the board's FIFO window (0x5000_1000..0x5004_0000):
//! [`OtgFs::block`] says which one an access reaches, and the model answers every read itself
//! (the register files rigless keeps for the blocks are not used). It is written against what
//! `synopsys-usb-otg` 0.4.0 (through stm32f4xx-hal 0.23), `usb-device` 0.3.2 and `usbd-serial`
//! 0.2.2 do with the core.
//!
//! | Register or behaviour | What the model does | Source |
//! |---|---|---|
//! | `CID` | Reads 0x0000_1200 (ST's file: 0x1000), the value that makes the driver treat the core as "F429-like": `NOVBUSSENS`, and OUT endpoints re-enabled when their "transfer complete" status is popped. Writable, as the section types it | 34.16.2 |
//! | `GRSTCTL` | `AHBIDL` always set; `CSRST`, `HSRST`, `FCRST`, `RXFFLSH`, `TXFFLSH` clear in the write that sets them. `RXFFLSH` empties the receive FIFO, `TXFFLSH` the transmit FIFO `TXFNUM` names (0x10: all). `CSRST` flushes every FIFO, clears the interrupts and disables every endpoint; the configuration registers stay (`GUSBCFG.FDMOD`, set before it by the driver, survives as on the part) | 34.16.2 |
//! | `GUSBCFG`, `GAHBCFG`, `GCCFG`, `GOTGCTL`, `GINTMSK`, FIFO sizes | Stored. `GOTGCTL` reads `CIDSTS` (B-device) and `BSVLD` while the cable is in. `GCCFG.PWRDWN` powers the transceiver | 34.16.2 |
//! | The D+ pull-up | On when `GUSBCFG.FHMOD` is clear, `GCCFG.PWRDWN` set, `DCTL.SDIS` clear, `PCGCCTL.STPPCLK` clear, and a B-session: `NOVBUSSENS` set, or `VBUSBSEN` set with the cable in | 34.16.2, 34.16.4 |
//! | `GINTSTS` | `USBRST`, `ENUMDNE`, `SOF`, `ESUSP`, `USBSUSP` latched (write one to clear); `RXFLVL` while a status entry waits; `IEPINT`/`OEPINT` from `DAINT & DAINTMSK`; `GINAKEFF`/`GONAKEFF` from the global NAKs; `NPTXFE`/`PTXFE` read as the reset value has them | 34.16.2 |
//! | Interrupt line 67 | High while `GAHBCFG.GINT` and `GINTSTS & GINTMSK`, recomputed after every access and event whichever block it reaches, and driven with `DeviceContext::drive_line` (the device block has no interrupt of its own to raise) | RM0090 vector table, position 67 |
//! | Receive FIFO | Status entries (`GRXSTSR` peeks, `GRXSTSP` pops) with `EPNUM`, `BCNT`, `PKTSTS` 2, 3, 4, 6 and `FRMNUM`; the data words are read from any FIFO page. `GRXFSIZ` words: an entry takes one, a packet its words; an OUT packet with no room is NAKed | 34.11, 34.16.2 |
//! | SETUP | Always taken at the device's address: "SETUP data" and "SETUP done" entries at once, `STUPCNT` down, OUT endpoint 0 disabled and NAKing, endpoint 0's `STALL` cleared both ways. `STUP` is set when "SETUP done" is popped | 34.17.7 |
//! | OUT endpoints | Taken when `EPENA`, not `NAKSTS`, not the global OUT NAK, and the FIFO has room: "OUT data"; when `PKTCNT` runs out (or was 0, which the driver never programs for endpoints 1-3) or the packet is short, "OUT complete", the endpoint disabled and NAKing; `XFRC` when that entry is popped. `STALL` answers STALL; an inactive endpoint does not answer | 34.17.6 |
//! | IN endpoints | A packet of up to `MPSIZ` of `XFRSIZ` when `EPENA`, not `NAKSTS`, `PKTCNT` > 0 and the whole packet is in its transmit FIFO (otherwise NAK: no underrun); zero-length packets need no FIFO data; the last packet sets `XFRC` and clears `EPENA`. `DTXFSTS` is the FIFO's free words, `TXFE` half or completely empty by `TXFELVL`, and counts in `DAINT` under `DIEPEMPMSK` | 34.17.6 |
//! | Endpoint control bits | `EPENA` and endpoint 0's `STALL` set-only; `EPDIS` disables an enabled endpoint at once and sets `EPDISD` (and wins over the `EPENA` a read-modify-write writes back with it); `SNAK`/`CNAK` set and clear `NAKSTS`; `SD0PID`/`SD1PID` accepted and ignored; endpoint 0 always `USBAEP`; a bus reset clears `USBAEP` of endpoints 1-3 and nothing else (no `EPENA`) | 34.16.4 |
//! | An IN endpoint armed while inactive | Stays armed: an inactive endpoint answers no token, and its activation (`USBAEP` set) does not clear the set-only `EPENA`. So a transfer the firmware arms between the driver's `deconfigure` (at `USBRST`) and `configure` (at `ENUMDNE`, which flushes the FIFOs and sets `SNAK`) leaves the endpoint enabled, NAKing and empty for good, and `EndpointIn::write` refuses for good. A firmware that writes right after `deconfigure` does exactly this (this project's did, until it wrote only while the host holds DTR): counted in [`UsbStats::in_stranded_on_activation`] | 34.16.4, 34.17.5 |
//! | `DCFG.DAD` | The device answers at `DAD`, and at the address before it until the next SETUP at the new one (the driver sets the address before the status stage of SET_ADDRESS) | 34.16.4 |
//! | `DSTS` | `SUSPSTS`, `ENUMSPD` (0b11 after the first reset), `FNSOF` | 34.16.4 |
//! | Suspend | With the cable out (the pull-up holds the bus idle) or the port disabled, 3 ms after the last SOF: `ESUSP` and `USBSUSP`, `SUSPSTS`, cleared by the next reset or SOF | USB 2.0 7.1.7.6 |
//! | Reset of the core | `RCC_AHB2RSTR.OTGFSRST` (rigless's reset line of `OTG_FS_GLOBAL`) and a system reset put every register back; the host sees the pull-up go | 6.3.6 |
//!
//! The virtual host ([`OtgFs::set_attached`], [`OtgFs::host_send`], [`OtgFs::host_take_received`],
//! [`OtgFs::configured`], [`OtgFs::stats`]): while the cable is in, it waits for the pull-up,
//! debounces it for 100 ms, resets the bus for 10 ms (`USBRST` at the start, `ENUMDNE` at the
//! end), sends a SOF every 1 ms, waits 10 ms, then GET_DESCRIPTOR device (8 bytes, at address 0),
//! SET_ADDRESS (a new address each enumeration, 2 ms recovery), GET_DESCRIPTOR device (18),
//! configuration (9, then whole), string 0 and the product, manufacturer and serial strings
//! (optional: a STALL skips one), SET_CONFIGURATION, and the `cdc-acm` driver's
//! SET_LINE_CODING (115200 8N1) and SET_CONTROL_LINE_STATE (DTR | RTS). A required request that
//! stalls, is not answered or takes 5 s fails the enumeration: the port is reset again after
//! 100 ms, and disabled after three failures in a row until the device goes away. Configured,
//! the host polls the CDC data interface's bulk IN and sends queued bytes on its bulk OUT in
//! packets of its max packet size, in order, retrying NAKed ones. A transaction happens as soon
//! as one can succeed (a firmware access that makes one possible schedules it 5 us later) and
//! takes its bus time at 12 Mbit/s (about 53 us for 64 bytes, so about 18 a frame at most);
//! every frame each pipe is polled once more, which is where NAKs are counted.
//!
//! **Left out**
//!
//! | Behaviour | Why |
//! |---|---|
//! | Host mode, OTG (SRP, HNP, ID pin), the host block's registers | The board is a device; host-block writes are stored and counted as unsupported |
//! | Resume, remote wakeup, LPM, the power-saving clock gating of `PCGCCTL` | The firmware does not use them (counted if set); the host never resumes a suspended bus, it resets it |
//! | Data toggles (`DPID`, `SD0PID`), CRC and bit errors, retries after a lost handshake | A virtual bus loses nothing |
//! | Isochronous and interrupt transfers' periodic scheduling, `MCNT`, `EOPF`, `ISOODRP`, `IISOIXFR`, `IPXFR` | CDC-ACM's bulk pipes carry the data; the notification endpoint is not polled |
//! | Timeout (`TOC`), `ITTXFE`, `INEPNE`, `OTEPDIS`, `B2BSTUP`, the "global OUT NAK" status entry | Nothing here causes them; the global NAKs take effect at once |
//! | The FIFO RAM's direct access (0x5002_0000) and FIFO pages of endpoints 4-15 | Counted as unsupported |
//! | Narrow (8/16-bit) FIFO accesses | Taken as words and counted |
//! | `DIEPCTLx.TXFNUM` routing | FIFO page n feeds transmit FIFO n and IN endpoint n sends from it (what the driver sets up); an active endpoint naming another FIFO is counted. Before its first configure the firmware's IN endpoint names FIFO 0, which the part would feed; the driver flushes every FIFO at configure |
//! | Soft disconnect seen by the device | Pulling `SDIS` only removes the pull-up: the host sees the device go, the core sees no reset or suspend |
//! | The "SETUP done" entry waiting for the data stage's first token | It is queued right behind "SETUP data" |
//!
//! Whatever the firmware does that the model does not do is counted by reason
//! ([`OtgFs::unsupported`], [`UsbStats::unsupported`]) and told to the session once per reason.

mod host;
mod usb_core;

use std::collections::BTreeMap;
use std::num::NonZeroU64;
use std::sync::OnceLock;

use rigless::device::{
    DeviceContext, ErasedDevice, InterruptChange, Level, RegisterFile, RequestChange,
};
use rigless::emulator::InterruptLine;
use rigless::soc::stm32f427::generated::{
    otg_fs_device, otg_fs_global, otg_fs_host, otg_fs_pwrclk,
};
use rigless::soc::{Bus, Cpu, Endian, RegisterSpec, Width, Window};
use rigless::time::{EventId, VirtualNanos};

use self::host::Host;
pub use self::host::{
    ATTACH_DEBOUNCE_NS, BUS_RESET_NS, FRAME_NS, RECEIVE_LIMIT, RESET_RECOVERY_NS, UsbDeviceInfo,
    UsbStats, transaction_ns,
};
use self::usb_core::Core;
pub use self::usb_core::{CID, ENDPOINTS};

/// The OTG FS global interrupt (position 67 of RM0090's vector table).
pub const OTG_FS_LINE: u16 = 67;
const LINE: InterruptLine = match InterruptLine::new(OTG_FS_LINE) {
    Some(line) => line,
    None => panic!("line 67 exists"),
};
/// How soon after the device becomes ready the host's next token comes, ns.
pub const TURNAROUND_NS: u64 = 5_000;

/// Which part of the OTG FS core an access reaches.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OtgBlock {
    /// `OTG_FS_GLOBAL`, 0x5000_0000.
    #[default]
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

/// The core and the virtual host on its port.
#[derive(Debug, Default)]
pub struct OtgFs {
    active: OtgBlock,
    core: Core,
    host: Host,
    frame_event: Option<EventId>,
    service_event: Option<(EventId, u64)>,
    bus_free_at: u64,
    line: Level,
    interrupts: u64,
}

impl OtgFs {
    /// The model answering `block` (the board's `Mcu::split` calls this for the five slots).
    pub fn block(&mut self, block: OtgBlock) -> Option<&mut dyn ErasedDevice> {
        self.active = block;
        Some(self)
    }

    /// A system reset of the MCU: the core back to reset; the virtual host sees the device vanish
    /// and enumerates it again once the firmware connects.
    pub fn reset(&mut self) {
        self.core.restart();
        self.host.device_gone();
        self.frame_event = None;
        self.service_event = None;
        self.bus_free_at = 0;
        self.line = Level::Low;
    }

    /// Plugs the cable in (true) or pulls it out; a new `OtgFs` starts plugged in. Takes effect
    /// at the next frame (within 1 ms of virtual time).
    pub fn set_attached(&mut self, attached: bool) {
        self.host.attached = attached;
    }

    /// Whether the cable is in.
    pub fn attached(&self) -> bool {
        self.host.attached
    }

    /// Queues bytes for the device's bulk OUT: delivered in packets of up to 64 bytes as the
    /// device takes them, in order. With the cable out they are dropped (and counted).
    pub fn host_send(&mut self, bytes: &[u8]) {
        self.host.send(bytes);
    }

    /// The bytes the device sent on bulk IN since the last call, in order.
    pub fn host_take_received(&mut self) -> Vec<u8> {
        self.host.take_received()
    }

    /// Whether the host application reads the port (polls bulk IN). A host that stops reading
    /// leaves the device's IN endpoint full.
    pub fn set_host_reading(&mut self, reading: bool) {
        self.host.reading = reading;
    }

    /// Enumeration and SET_CONFIGURATION done, and the CDC line set up.
    pub fn configured(&self) -> bool {
        self.host.configured()
    }

    /// The host's port state, by name (for logs).
    pub fn host_state(&self) -> &'static str {
        self.host.state()
    }

    /// What the host learned about the device in its last enumeration.
    pub fn device_info(&self) -> &UsbDeviceInfo {
        &self.host.info
    }

    /// Bulk OUT bytes the device took so far (the firmware's link drained its FIFO for them).
    pub fn out_bytes(&self) -> u64 {
        self.host.stats.out_bytes
    }

    /// What the host and the core counted.
    pub fn stats(&self) -> UsbStats {
        UsbStats {
            rx_fifo_overflows: self.core.rx_overflows,
            in_armed_before_configuration: self.core.armed_inactive,
            in_stranded_on_activation: self.core.stranded_on_activation,
            unsupported: self.core.unsupported.values().sum(),
            interrupts: self.interrupts,
            ..self.host.stats.clone()
        }
    }

    /// What the firmware did that the model does not do, by reason, with how often.
    pub fn unsupported(&self) -> &BTreeMap<&'static str, u64> {
        &self.core.unsupported
    }

    /// IN endpoint `ep` (0-3): its DIEPCTL, its DIEPTSIZ, and the words in its transmit FIFO.
    pub fn in_endpoint(&self, ep: usize) -> (u32, u32, usize) {
        self.core.in_endpoint(ep)
    }

    /// The core's endpoints and FIFOs, and the host's state, for a log.
    pub fn describe(&self) -> String {
        format!(
            "host: {} address {} line {:?}\n{}",
            self.host.state(),
            self.host.info.address,
            self.line,
            self.core.describe()
        )
    }

    /// The level the model drives on interrupt line 67.
    pub fn interrupt_line(&self) -> bool {
        self.line == Level::High
    }

    /// After an access or an event: the frame clock running, a transaction scheduled if one can
    /// now succeed, the interrupt line at its level, and anything new told.
    fn settle(&mut self, cx: &mut DeviceContext<'_>) {
        if self.frame_event.is_none() {
            self.frame_event = Some(cx.schedule(VirtualNanos(cx.now().0 + FRAME_NS)));
        }
        if std::mem::take(&mut self.core.changed) {
            self.kick(cx);
        }
        self.drive(cx);
        for (register, reason) in self.core.to_tell.drain(..) {
            cx.tell(register, reason);
        }
    }

    /// Schedules the bus if a transaction can succeed, as soon as the bus is free.
    fn kick(&mut self, cx: &mut DeviceContext<'_>) {
        if !self.host.ready(&self.core) {
            return;
        }
        let at = (cx.now().0 + TURNAROUND_NS).max(self.bus_free_at);
        if self.service_event.is_some_and(|(_, pending)| pending <= at) {
            return;
        }
        self.service_event = Some((cx.schedule(VirtualNanos(at)), at));
    }

    fn drive(&mut self, cx: &mut DeviceContext<'_>) {
        let level = self.core.line();
        if level != self.line {
            if level == Level::High {
                self.interrupts += 1;
            }
            self.line = level;
            cx.drive_line(LINE, level);
        }
    }

    fn event(&mut self, event: EventId, cx: &mut DeviceContext<'_>) {
        let now = cx.now().0;
        let mut run = false;
        if self.frame_event == Some(event) {
            self.frame_event = Some(cx.schedule(VirtualNanos(now + FRAME_NS)));
            self.host.frame(&mut self.core, now);
            run = true;
        }
        if self.service_event.is_some_and(|(id, _)| id == event) {
            self.service_event = None;
            run = true;
        }
        if run && now >= self.bus_free_at {
            let (used, _) = self.host.work(&mut self.core, now);
            self.bus_free_at = now + used;
        }
        self.core.changed = true;
        self.settle(cx);
    }
}

/// The layout a board window carries (rigless's own empty table, which the wiring check compares
/// by address): read off a window of a bus built for the purpose.
fn window_layout() -> &'static [RegisterSpec] {
    static LAYOUT: OnceLock<&'static [RegisterSpec]> = OnceLock::new();
    LAYOUT.get_or_init(|| {
        let built = Bus::builder(Cpu::new("window", false, 1, Endian::Little), &[], []).build();
        let mut bus = built.expect("an empty bus builds");
        let window = Window::new("window", 0x1000, NonZeroU64::MIN);
        let slot = bus.add_window(window).expect("a window fits an empty bus");
        bus.slots()[slot].peripheral().registers
    })
}

impl ErasedDevice for OtgFs {
    fn layout(&self) -> &'static [RegisterSpec] {
        match self.active {
            OtgBlock::Global => &otg_fs_global::REGISTERS,
            OtgBlock::Host => &otg_fs_host::REGISTERS,
            OtgBlock::Device => &otg_fs_device::REGISTERS,
            OtgBlock::PowerClock => &otg_fs_pwrclk::REGISTERS,
            OtgBlock::Fifo => window_layout(),
        }
    }

    fn read(
        &mut self,
        row: usize,
        _: &mut RegisterFile,
        cx: &mut DeviceContext<'_>,
    ) -> Option<u64> {
        let value = self.core.read(self.active, row);
        self.settle(cx);
        Some(value.into())
    }

    fn peek(&self, row: usize, _: &RegisterFile, _: VirtualNanos) -> Option<u64> {
        Some(self.core.value(self.active, row).into())
    }

    fn write(&mut self, row: usize, value: u64, _: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        let mask = cx.access_mask().unwrap_or(0xFFFF_FFFF) as u32;
        self.core.write(self.active, row, value as u32, mask);
        self.settle(cx);
    }

    fn on_event(&mut self, event: EventId, _: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        self.event(event, cx);
    }

    fn on_request(&mut self, _: RequestChange, _: &mut RegisterFile, _: &mut DeviceContext<'_>) {}

    fn on_interrupt(
        &mut self,
        _: InterruptChange,
        _: &mut RegisterFile,
        _: &mut DeviceContext<'_>,
    ) {
    }

    fn on_clock(&mut self, _: u64, _: &mut RegisterFile, _: &mut DeviceContext<'_>) {}

    fn poll(&mut self, _: &mut RegisterFile, _: &mut DeviceContext<'_>) {}

    fn reset(&mut self) {
        OtgFs::reset(self);
    }

    /// `RCC_AHB2RSTR.OTGFSRST`: the whole core back to reset while the part runs on.
    fn reset_line(&mut self, _: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        OtgFs::reset(self);
        self.line = Level::High;
        self.drive(cx);
        self.settle(cx);
    }

    fn on_access(&mut self, _: u64, _: u64, _: &mut RegisterFile, _: &mut DeviceContext<'_>) {}

    fn on_refused(&mut self, _: u64, _: &mut RegisterFile, _: &mut DeviceContext<'_>) {}

    fn read_window(&mut self, offset: u64, width: Width, cx: &mut DeviceContext<'_>) -> u64 {
        if width != Width::W32 {
            self.core.note(
                "OTG_FS_FIFO",
                "receive FIFO read narrower than a word (a word is popped)",
            );
        }
        let value = self.core.read_fifo(offset);
        self.settle(cx);
        value.into()
    }

    fn write_window(&mut self, offset: u64, width: Width, value: u64, cx: &mut DeviceContext<'_>) {
        self.core
            .write_fifo(offset, value as u32, width == Width::W32);
        self.settle(cx);
    }

    fn peek_window(&self, offset: u64, _: Width, _: VirtualNanos) -> Option<u64> {
        Some(self.core.peek_fifo(offset).into())
    }
}

#[cfg(test)]
mod tests;
