//! The virtual USB host: one root port with a cable, enumerating the device the way a Linux host
//! does and then running a CDC-ACM port (the `cdc-acm` driver's requests, its bulk IN reads and
//! bulk OUT writes). It speaks to the device only through [`Core`]'s transactions, in virtual
//! time: a frame every millisecond, and a transaction whenever one can succeed.

use std::collections::VecDeque;

use super::usb_core::{Core, Handshake};

/// One USB frame, ns.
pub const FRAME_NS: u64 = 1_000_000;
/// How long the port sees the device's pull-up before it resets it, ns (USB 2.0 7.1.7.3
/// `TATTDB`, Linux's `HUB_DEBOUNCE_STABLE`: 100 ms).
pub const ATTACH_DEBOUNCE_NS: u64 = 100_000_000;
/// The bus reset, ns (`TDRST`, 10 ms minimum).
pub const BUS_RESET_NS: u64 = 10_000_000;
/// After the reset, before the first request, ns (`TRSTRCY`, 10 ms).
pub const RESET_RECOVERY_NS: u64 = 10_000_000;
/// After SET_ADDRESS, before the next request, ns (`TDSETADDR`, 2 ms).
pub const SET_ADDRESS_RECOVERY_NS: u64 = 2_000_000;
/// A control transfer that has not finished after this long fails, ns (Linux's
/// `USB_CTRL_GET_TIMEOUT`, 5 s).
pub const CONTROL_TIMEOUT_NS: u64 = 5_000_000_000;
/// After a failed enumeration, before the port is reset again, ns.
pub const RETRY_DELAY_NS: u64 = 100_000_000;
/// Enumerations in a row that may fail before the port is disabled until the device goes.
pub const ENUMERATION_ATTEMPTS: u32 = 3;
/// How long an idle bus takes to suspend a device, ns (3 ms).
pub const SUSPEND_NS: u64 = 3_000_000;
/// Bytes the host buffers from bulk IN before it stops reading (a full tty throttles the read).
pub const RECEIVE_LIMIT: usize = 1 << 20;
/// The line coding the host sets: 115200 baud, 1 stop bit, no parity, 8 data bits.
pub const LINE_CODING: [u8; 7] = [0x00, 0xC2, 0x01, 0x00, 0, 0, 8];
/// A NAKed or empty transaction on the bus, ns (token and handshake).
const NAK_NS: u64 = 5_000;

/// Bus time of a transaction carrying `payload` bytes at 12 Mbit/s, ns: the payload plus about
/// 16 bytes of sync, PIDs, CRC, handshake and inter-packet gaps.
pub fn transaction_ns(payload: usize) -> u64 {
    (payload as u64 + 16) * 8 * 1_000 / 12
}

/// What the host counted.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UsbStats {
    /// Bus resets the host drove.
    pub bus_resets: u64,
    /// Enumerations that reached the configured state (and set up the CDC port).
    pub enumerations: u64,
    /// Enumerations that failed (a required request stalled, timed out or was not answered).
    pub enumeration_failures: u64,
    /// Times a device the host had on the bus went away (cable out, pull-up off, reset).
    pub disconnects: u64,
    /// Start-of-frame tokens sent.
    pub sofs: u64,
    /// SETUP packets the device took.
    pub setups: u64,
    /// Control transfers completed.
    pub control_transfers: u64,
    /// STALL handshakes seen (control or bulk).
    pub stalls: u64,
    /// Tokens nothing answered.
    pub no_response: u64,
    /// Bulk OUT packets the device took, and their bytes.
    pub out_packets: u64,
    /// Bulk OUT bytes the device took.
    pub out_bytes: u64,
    /// Bulk IN packets received (zero-length ones included), and their bytes.
    pub in_packets: u64,
    /// Bulk IN bytes received.
    pub in_bytes: u64,
    /// Zero-length bulk IN packets received.
    pub in_zero_length: u64,
    /// NAKs on bulk IN tokens (one counted per poll: a frame's, or one after the device changed).
    pub naks_in: u64,
    /// NAKs on bulk OUT packets (counted as `naks_in`).
    pub naks_out: u64,
    /// NAKs in control transfers' data and status stages.
    pub naks_control: u64,
    /// Bytes queued with `host_send` that never reached the device: sent with the cable out, or
    /// still queued when the device went away.
    pub out_bytes_discarded: u64,
    /// SETUP packets pushed into a receive FIFO already full.
    pub rx_fifo_overflows: u64,
    /// IN endpoints 1-3 the firmware enabled while inactive (data written before the host
    /// configured the device; the next bus reset's deconfigure and flush drop it).
    pub in_armed_before_configuration: u64,
    /// IN endpoints the firmware's configure activated with a transfer still armed from while
    /// they were inactive: stranded (enabled, NAKing, their data flushed). Non-zero means the
    /// CDC IN pipe hangs.
    pub in_stranded_on_activation: u64,
    /// Register or FIFO accesses the model does not support (see `OtgFs::unsupported`).
    pub unsupported: u64,
    /// Times the OTG FS interrupt line went high.
    pub interrupts: u64,
}

/// What enumeration learned about the device.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UsbDeviceInfo {
    /// The address the host gave it.
    pub address: u8,
    /// bMaxPacketSize0.
    pub max_packet_size_0: u16,
    /// idVendor.
    pub vendor_id: u16,
    /// idProduct.
    pub product_id: u16,
    /// bDeviceClass.
    pub device_class: u8,
    /// The manufacturer string.
    pub manufacturer: Option<String>,
    /// The product string.
    pub product: Option<String>,
    /// The serial number string.
    pub serial: Option<String>,
    /// The configuration descriptor, whole.
    pub configuration: Vec<u8>,
    /// bConfigurationValue.
    pub configuration_value: u8,
    /// The CDC communication interface's number.
    pub comm_interface: u8,
    /// Its notification endpoint (interrupt IN), address and max packet size.
    pub notification_in: Option<(u8, u16)>,
    /// The CDC data interface's bulk IN endpoint, address and max packet size.
    pub bulk_in: Option<(u8, u16)>,
    /// The CDC data interface's bulk OUT endpoint, address and max packet size.
    pub bulk_out: Option<(u8, u16)>,
}

/// One control request of the enumeration, in the order the host makes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    /// GET_DESCRIPTOR(device) for 8 bytes at address 0: bMaxPacketSize0.
    DeviceHead,
    SetAddress(u8),
    Device,
    ConfigurationHead,
    Configuration(u16),
    Languages,
    /// GET_DESCRIPTOR(string) for the product (0), manufacturer (1) and serial (2).
    String(u8, u8),
    SetConfiguration(u8),
    SetLineCoding,
    SetControlLineState,
}

impl Step {
    /// A request whose failure the host shrugs off (Linux reads strings as best it can).
    fn optional(self) -> bool {
        matches!(self, Self::Languages | Self::String(..))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Setup,
    DataIn,
    DataOut,
    StatusIn,
    StatusOut,
}

#[derive(Clone, Debug)]
struct Control {
    step: Step,
    setup: [u8; 8],
    stage: Stage,
    length: usize,
    received: Vec<u8>,
    sending: Vec<u8>,
    sent: usize,
    started: u64,
}

/// The port's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Port {
    /// The cable is out.
    Detached,
    /// The cable is in and the device has no pull-up on.
    Waiting,
    /// The pull-up has been seen since the instant given; the reset starts after the debounce.
    Debouncing(u64),
    /// The bus reset ends at the instant given.
    Resetting(u64),
    /// SOFs run and control transfers enumerate the device.
    Enumerating,
    /// Enumerated, configured, the CDC port open.
    Configured,
    /// Enumeration failed too often: the port is disabled until the device goes away.
    Disabled,
}

/// The host.
#[derive(Debug)]
pub struct Host {
    /// The cable is in.
    pub attached: bool,
    /// The application reads the CDC port (bulk IN is polled).
    pub reading: bool,
    port: Port,
    address: u8,
    last_address: u8,
    control: Option<Control>,
    /// The next request and the instant it may start.
    next: Option<(Step, u64)>,
    failures: u32,
    frame: u32,
    suspend_at: Option<u64>,
    /// iProduct, iManufacturer, iSerialNumber.
    string_indexes: [u8; 3],
    pub info: UsbDeviceInfo,
    out_queue: VecDeque<u8>,
    received: Vec<u8>,
    pub stats: UsbStats,
}

impl Default for Host {
    fn default() -> Self {
        Self {
            attached: true,
            reading: true,
            port: Port::Waiting,
            address: 0,
            last_address: 0,
            control: None,
            next: None,
            failures: 0,
            frame: 0,
            suspend_at: None,
            string_indexes: [0; 3],
            info: UsbDeviceInfo::default(),
            out_queue: VecDeque::new(),
            received: Vec::new(),
            stats: UsbStats::default(),
        }
    }
}

impl Host {
    /// Enumeration and the CDC set-up are done (and the cable is still in).
    pub fn configured(&self) -> bool {
        self.attached && self.port == Port::Configured
    }

    /// The port's state, by name.
    pub fn state(&self) -> &'static str {
        match self.port {
            Port::Detached => "detached",
            Port::Waiting => "waiting for the device",
            Port::Debouncing(_) => "debouncing",
            Port::Resetting(_) => "resetting",
            Port::Enumerating => "enumerating",
            Port::Configured => "configured",
            Port::Disabled => "disabled",
        }
    }

    /// SOFs and transactions run.
    fn bus_active(&self) -> bool {
        matches!(self.port, Port::Enumerating | Port::Configured)
    }

    /// Queues bytes for bulk OUT (dropped, and counted, with the cable out).
    pub fn send(&mut self, bytes: &[u8]) {
        if self.attached {
            self.out_queue.extend(bytes);
        } else {
            self.stats.out_bytes_discarded += bytes.len() as u64;
        }
    }

    /// What arrived on bulk IN since the last call.
    pub fn take_received(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.received)
    }

    /// The device went away (its pull-up went off, or the MCU reset): the port is back to waiting.
    pub fn device_gone(&mut self) {
        if self.port != Port::Detached {
            self.lose_device(0, false);
            self.port = if self.attached {
                Port::Waiting
            } else {
                Port::Detached
            };
        }
    }

    /// Everything the host had for the device dropped. With `idle`, the bus is left idle (the
    /// cable out with the device's pull-up on, or the port disabled), which suspends the device.
    fn lose_device(&mut self, now: u64, idle: bool) {
        let on_bus = matches!(
            self.port,
            Port::Resetting(_) | Port::Enumerating | Port::Configured
        );
        if on_bus {
            self.stats.disconnects += 1;
        }
        if idle && self.bus_active() {
            self.suspend_at = Some(now + SUSPEND_NS);
        }
        self.stats.out_bytes_discarded += self.out_queue.len() as u64;
        self.out_queue.clear();
        self.control = None;
        self.next = None;
        self.failures = 0;
        self.string_indexes = [0; 3];
        self.info = UsbDeviceInfo::default();
    }

    /// One frame: the port's state machine, the SOF, control transfers starting and timing out.
    pub fn frame(&mut self, core: &mut Core, now: u64) {
        core.vbus = self.attached;
        if !self.attached && self.port != Port::Detached {
            // The cable is out: the device's pull-up holds the bus idle, so it suspends.
            self.lose_device(now, true);
            self.port = Port::Detached;
        } else if self.attached && self.port == Port::Detached {
            self.port = Port::Waiting;
        }
        if let Some(at) = self.suspend_at
            && now >= at
        {
            core.suspend();
            self.suspend_at = None;
        }
        let pullup = core.pullup();
        if !matches!(self.port, Port::Detached | Port::Waiting | Port::Disabled) && !pullup {
            // The bus goes to SE0 (the host's pull-downs): no suspend, nothing the core sees.
            self.lose_device(now, false);
            self.port = Port::Waiting;
        }
        match self.port {
            Port::Detached => {}
            Port::Waiting => {
                if pullup {
                    self.port = Port::Debouncing(now + ATTACH_DEBOUNCE_NS);
                }
            }
            Port::Disabled => {
                if !pullup {
                    self.port = Port::Waiting;
                }
            }
            Port::Debouncing(until) => {
                if now >= until {
                    self.reset_port(core, now);
                }
            }
            Port::Resetting(until) => {
                if now >= until {
                    core.enumeration_done();
                    self.address = 0;
                    self.info = UsbDeviceInfo {
                        max_packet_size_0: 8,
                        ..UsbDeviceInfo::default()
                    };
                    self.control = None;
                    self.port = Port::Enumerating;
                    self.next = Some((Step::DeviceHead, now + RESET_RECOVERY_NS));
                }
            }
            Port::Enumerating | Port::Configured => {
                self.suspend_at = None;
                self.frame = (self.frame + 1) & 0x7FF;
                core.start_of_frame(self.frame);
                self.stats.sofs += 1;
                if let Some(control) = &self.control
                    && now.saturating_sub(control.started) > CONTROL_TIMEOUT_NS
                {
                    self.control_failed(now);
                }
                if self.control.is_none()
                    && let Some((step, at)) = self.next
                    && now >= at
                {
                    self.next = None;
                    self.start(step, now);
                }
            }
        }
    }

    fn reset_port(&mut self, core: &mut Core, now: u64) {
        core.bus_reset();
        self.stats.bus_resets += 1;
        self.suspend_at = None;
        self.control = None;
        self.next = None;
        self.port = Port::Resetting(now + BUS_RESET_NS);
    }

    fn start(&mut self, step: Step, now: u64) {
        let get = |kind: u16, index: u16, language: u16, length: u16| {
            request(0x80, 6, (kind << 8) | index, language, length)
        };
        let comm = u16::from(self.info.comm_interface);
        let (setup, sending) = match step {
            Step::DeviceHead => (get(1, 0, 0, 8), Vec::new()),
            Step::SetAddress(address) => (request(0x00, 5, address.into(), 0, 0), Vec::new()),
            Step::Device => (get(1, 0, 0, 18), Vec::new()),
            Step::ConfigurationHead => (get(2, 0, 0, 9), Vec::new()),
            Step::Configuration(length) => (get(2, 0, 0, length), Vec::new()),
            Step::Languages => (get(3, 0, 0, 255), Vec::new()),
            Step::String(index, _) => (get(3, index.into(), 0x0409, 255), Vec::new()),
            Step::SetConfiguration(value) => (request(0x00, 9, value.into(), 0, 0), Vec::new()),
            Step::SetLineCoding => (request(0x21, 0x20, 0, comm, 7), LINE_CODING.to_vec()),
            Step::SetControlLineState => (request(0x21, 0x22, 0b11, comm, 0), Vec::new()),
        };
        self.control = Some(Control {
            step,
            setup,
            stage: Stage::Setup,
            length: usize::from(u16::from_le_bytes([setup[6], setup[7]])),
            received: Vec::new(),
            sending,
            sent: 0,
            started: now,
        });
    }

    /// Whether a transaction would succeed now (so the bus should run soon).
    pub fn ready(&self, core: &Core) -> bool {
        if !self.bus_active() || !core.pullup() {
            return false;
        }
        if let Some(control) = &self.control {
            let ready = match control.stage {
                Stage::Setup => true,
                Stage::DataIn | Stage::StatusIn => core.in_ready(self.address, 0),
                Stage::DataOut => {
                    let chunk = (control.sending.len() - control.sent).min(self.mps0());
                    core.out_ready(self.address, 0, chunk)
                }
                Stage::StatusOut => core.out_ready(self.address, 0, 0),
            };
            if ready {
                return true;
            }
        }
        if self.port != Port::Configured {
            return false;
        }
        if let Some((ep, mps)) = self.info.bulk_out
            && !self.out_queue.is_empty()
            && core.out_ready(
                self.address,
                usize::from(ep & 0xF),
                self.out_queue.len().min(usize::from(mps)),
            )
        {
            return true;
        }
        if let Some((ep, _)) = self.info.bulk_in
            && self.wants_in()
            && core.in_ready(self.address, usize::from(ep & 0xF))
        {
            return true;
        }
        false
    }

    fn wants_in(&self) -> bool {
        self.reading && self.received.len() < RECEIVE_LIMIT
    }

    fn mps0(&self) -> usize {
        usize::from(self.info.max_packet_size_0.max(8))
    }

    /// Runs at most one transaction per pipe (control, bulk OUT, bulk IN). Answers the bus time
    /// taken, ns, and whether any transaction moved data.
    pub fn work(&mut self, core: &mut Core, now: u64) -> (u64, bool) {
        if !self.bus_active() || !core.pullup() {
            return (0, false);
        }
        let mut used = 0;
        let mut moved = false;
        if self.control.is_some() {
            let (time, done) = self.control_transaction(core, now);
            used += time;
            moved |= done;
        }
        if self.port != Port::Configured {
            return (used, moved);
        }
        if let Some((ep, mps)) = self.info.bulk_out
            && !self.out_queue.is_empty()
        {
            let n = self.out_queue.len().min(usize::from(mps));
            let chunk: Vec<u8> = self.out_queue.iter().take(n).copied().collect();
            match core.out(self.address, usize::from(ep & 0xF), &chunk) {
                Handshake::Ack => {
                    self.out_queue.drain(..n);
                    self.stats.out_packets += 1;
                    self.stats.out_bytes += n as u64;
                    used += transaction_ns(n);
                    moved = true;
                }
                Handshake::Nak => {
                    self.stats.naks_out += 1;
                    used += NAK_NS;
                }
                Handshake::Stall => self.stats.stalls += 1,
                Handshake::Silent => self.stats.no_response += 1,
            }
        }
        if let Some((ep, _)) = self.info.bulk_in
            && self.wants_in()
        {
            let before = self.received.len();
            match core.in_token(self.address, usize::from(ep & 0xF), &mut self.received) {
                Handshake::Ack => {
                    let n = self.received.len() - before;
                    self.stats.in_packets += 1;
                    self.stats.in_bytes += n as u64;
                    if n == 0 {
                        self.stats.in_zero_length += 1;
                    }
                    used += transaction_ns(n);
                    moved = true;
                }
                Handshake::Nak => {
                    self.stats.naks_in += 1;
                    used += NAK_NS;
                }
                Handshake::Stall => self.stats.stalls += 1,
                Handshake::Silent => self.stats.no_response += 1,
            }
        }
        (used, moved)
    }

    /// One transaction of the control transfer in flight.
    fn control_transaction(&mut self, core: &mut Core, now: u64) -> (u64, bool) {
        let address = self.address;
        let mps = self.mps0();
        let Some(control) = self.control.as_mut() else {
            return (0, false);
        };
        let answer;
        let mut time = NAK_NS;
        let mut finished = false;
        match control.stage {
            Stage::Setup => {
                answer = core.setup(address, control.setup);
                if answer == Handshake::Ack {
                    self.stats.setups += 1;
                    time = transaction_ns(8);
                    control.stage = match (control.length, control.setup[0] & 0x80 != 0) {
                        (0, _) => Stage::StatusIn,
                        (_, true) => Stage::DataIn,
                        (_, false) => Stage::DataOut,
                    };
                }
            }
            Stage::DataIn => {
                let before = control.received.len();
                answer = core.in_token(address, 0, &mut control.received);
                if answer == Handshake::Ack {
                    let n = control.received.len() - before;
                    time = transaction_ns(n);
                    if n < mps || control.received.len() >= control.length {
                        control.received.truncate(control.length);
                        control.stage = Stage::StatusOut;
                    }
                }
            }
            Stage::DataOut => {
                let end = (control.sent + mps).min(control.sending.len());
                answer = core.out(address, 0, &control.sending[control.sent..end]);
                if answer == Handshake::Ack {
                    time = transaction_ns(end - control.sent);
                    control.sent = end;
                    if control.sent >= control.sending.len() {
                        control.stage = Stage::StatusIn;
                    }
                }
            }
            Stage::StatusIn => {
                let mut data = Vec::new();
                answer = core.in_token(address, 0, &mut data);
                if answer == Handshake::Ack {
                    time = transaction_ns(data.len());
                    finished = true;
                }
            }
            Stage::StatusOut => {
                answer = core.out(address, 0, &[]);
                if answer == Handshake::Ack {
                    time = transaction_ns(0);
                    finished = true;
                }
            }
        }
        match answer {
            Handshake::Ack => {}
            Handshake::Nak => self.stats.naks_control += 1,
            Handshake::Stall => {
                self.stats.stalls += 1;
                self.control_failed(now);
            }
            Handshake::Silent => {
                self.stats.no_response += 1;
                self.control_failed(now);
            }
        }
        if finished {
            self.stats.control_transfers += 1;
            if let Some(control) = self.control.take() {
                self.control_done(control.step, &control.received, now);
            }
        }
        (time, answer == Handshake::Ack)
    }

    /// The control transfer in flight failed: an optional request is skipped, a required one
    /// fails the enumeration.
    fn control_failed(&mut self, now: u64) {
        let Some(control) = self.control.take() else {
            return;
        };
        if control.step.optional() {
            self.advance(control.step, now);
        } else {
            self.enumeration_failed(now);
        }
    }

    fn enumeration_failed(&mut self, now: u64) {
        self.stats.enumeration_failures += 1;
        self.failures += 1;
        self.control = None;
        self.next = None;
        if self.failures >= ENUMERATION_ATTEMPTS {
            if self.bus_active() {
                self.suspend_at = Some(now + SUSPEND_NS);
            }
            self.port = Port::Disabled;
        } else {
            self.port = Port::Debouncing(now + RETRY_DELAY_NS);
        }
    }

    /// A control transfer finished with `data` from its data stage.
    fn control_done(&mut self, step: Step, data: &[u8], now: u64) {
        match step {
            Step::DeviceHead => {
                if data.len() < 8 || data[1] != 1 || ![8, 16, 32, 64].contains(&data[7]) {
                    return self.enumeration_failed(now);
                }
                self.info.max_packet_size_0 = data[7].into();
            }
            Step::SetAddress(address) => {
                self.address = address;
                self.info.address = address;
            }
            Step::Device => {
                if data.len() < 18 || data[1] != 1 {
                    return self.enumeration_failed(now);
                }
                let info = &mut self.info;
                info.device_class = data[4];
                info.max_packet_size_0 = data[7].into();
                info.vendor_id = u16::from_le_bytes([data[8], data[9]]);
                info.product_id = u16::from_le_bytes([data[10], data[11]]);
                // The string indexes ride in the strings' slots until they are read.
                self.string_indexes = [data[15], data[14], data[16]];
            }
            Step::ConfigurationHead => {
                if data.len() < 9 || data[1] != 2 || u16::from_le_bytes([data[2], data[3]]) < 9 {
                    return self.enumeration_failed(now);
                }
            }
            Step::Configuration(length) => {
                if data.len() < usize::from(length) || !self.parse_configuration(data) {
                    return self.enumeration_failed(now);
                }
            }
            Step::Languages => {}
            Step::String(_, which) => {
                let text = parse_string(data);
                match which {
                    0 => self.info.product = text,
                    1 => self.info.manufacturer = text,
                    _ => self.info.serial = text,
                }
            }
            Step::SetConfiguration(_) | Step::SetLineCoding => {}
            Step::SetControlLineState => {
                self.port = Port::Configured;
                self.failures = 0;
                self.stats.enumerations += 1;
                return;
            }
        }
        let wait = if matches!(step, Step::SetAddress(_)) {
            SET_ADDRESS_RECOVERY_NS
        } else {
            0
        };
        self.next_after(step, data, now + wait);
    }

    /// A skipped optional request: the one after it.
    fn advance(&mut self, step: Step, now: u64) {
        self.next_after(step, &[], now);
    }

    fn next_after(&mut self, step: Step, data: &[u8], at: u64) {
        let next = match step {
            Step::DeviceHead => {
                self.last_address = self.last_address % 127 + 1;
                Step::SetAddress(self.last_address)
            }
            Step::SetAddress(_) => Step::Device,
            Step::Device => Step::ConfigurationHead,
            Step::ConfigurationHead => Step::Configuration(u16::from_le_bytes([data[2], data[3]])),
            Step::Configuration(_) => Step::Languages,
            Step::Languages => match self.next_string(0) {
                Some(next) => next,
                None => Step::SetConfiguration(self.info.configuration_value),
            },
            Step::String(_, which) => match self.next_string(which + 1) {
                Some(next) => next,
                None => Step::SetConfiguration(self.info.configuration_value),
            },
            Step::SetConfiguration(_) => Step::SetLineCoding,
            Step::SetLineCoding => Step::SetControlLineState,
            Step::SetControlLineState => return,
        };
        self.next = Some((next, at));
    }

    /// The next string the device has, from `which` on (product, manufacturer, serial).
    fn next_string(&self, which: u8) -> Option<Step> {
        (which..3).find_map(|w| {
            let index = self.string_indexes[usize::from(w)];
            (index != 0).then_some(Step::String(index, w))
        })
    }

    /// Finds the CDC interfaces and their endpoints in a configuration descriptor.
    fn parse_configuration(&mut self, data: &[u8]) -> bool {
        if data.len() < 9 || data[1] != 2 {
            return false;
        }
        let info = &mut self.info;
        info.configuration = data.to_vec();
        info.configuration_value = data[5];
        let mut class = None;
        let mut at = 0;
        while at + 2 <= data.len() {
            let length = usize::from(data[at]);
            if length < 2 || at + length > data.len() {
                return false;
            }
            let descriptor = &data[at..at + length];
            match descriptor[1] {
                4 if length >= 9 => {
                    class = Some(descriptor[5]);
                    if descriptor[5] == 0x02 && descriptor[6] == 0x02 {
                        info.comm_interface = descriptor[2];
                    }
                }
                5 if length >= 7 => {
                    let address = descriptor[2];
                    let kind = descriptor[3] & 0b11;
                    let mps = u16::from_le_bytes([descriptor[4], descriptor[5]]) & 0x7FF;
                    match (class, kind, address & 0x80 != 0) {
                        (Some(0x0A), 2, true) => info.bulk_in = Some((address, mps)),
                        (Some(0x0A), 2, false) => info.bulk_out = Some((address, mps)),
                        (Some(0x02), 3, true) => info.notification_in = Some((address, mps)),
                        _ => {}
                    }
                }
                _ => {}
            }
            at += length;
        }
        info.bulk_in.is_some() && info.bulk_out.is_some()
    }
}

/// A SETUP packet.
fn request(request_type: u8, request: u8, value: u16, index: u16, length: u16) -> [u8; 8] {
    let [v0, v1] = value.to_le_bytes();
    let [i0, i1] = index.to_le_bytes();
    let [l0, l1] = length.to_le_bytes();
    [request_type, request, v0, v1, i0, i1, l0, l1]
}

/// A string descriptor's UTF-16LE text.
fn parse_string(data: &[u8]) -> Option<String> {
    if data.len() < 2 || data[1] != 3 {
        return None;
    }
    let end = usize::from(data[0]).min(data.len());
    let units: Vec<u16> = data[2..end]
        .as_chunks::<2>()
        .0
        .iter()
        .map(|c| u16::from_le_bytes(*c))
        .collect();
    String::from_utf16(&units).ok()
}
