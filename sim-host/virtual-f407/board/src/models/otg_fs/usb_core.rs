//! The device side of the core: every register of the four blocks, the shared receive FIFO, the
//! four dedicated transmit FIFOs, and what one USB transaction does to them (RM0090 rev 19
//! sections 34.16 and 34.17). The bus side (who sends which token when) is `host.rs`'s.

use std::collections::{BTreeMap, VecDeque};

use rigless::device::Level;
use rigless::soc::Layout;
use rigless::soc::stm32f427::generated::{
    otg_fs_device as device, otg_fs_global as global, otg_fs_host as host,
};

use super::OtgBlock;

/// IN and OUT endpoints of the F407's full-speed core (endpoint 0 and three more).
pub const ENDPOINTS: usize = 4;

// GINTSTS / GINTMSK (34.16.2).
pub(super) const CMOD: u32 = 1 << 0;
const MMIS: u32 = 1 << 1;
pub(super) const SOF: u32 = 1 << 3;
pub(super) const RXFLVL: u32 = 1 << 4;
const NPTXFE: u32 = 1 << 5;
const GINAKEFF: u32 = 1 << 6;
const GONAKEFF: u32 = 1 << 7;
pub(super) const ESUSP: u32 = 1 << 10;
pub(super) const USBSUSP: u32 = 1 << 11;
pub(super) const USBRST: u32 = 1 << 12;
pub(super) const ENUMDNE: u32 = 1 << 13;
const ISOODRP: u32 = 1 << 14;
const EOPF: u32 = 1 << 15;
pub(super) const IEPINT: u32 = 1 << 18;
pub(super) const OEPINT: u32 = 1 << 19;
const IISOIXFR: u32 = 1 << 20;
const IPXFR: u32 = 1 << 21;
const PTXFE: u32 = 1 << 26;
const CIDSCHG: u32 = 1 << 28;
const DISCINT: u32 = 1 << 29;
const SRQINT: u32 = 1 << 30;
const WKUPINT: u32 = 1 << 31;
/// The `rc_w1` bits of GINTSTS: the ones the core latches and the application clears.
const GINTSTS_LATCHED: u32 = MMIS
    | SOF
    | ESUSP
    | USBSUSP
    | USBRST
    | ENUMDNE
    | ISOODRP
    | EOPF
    | IISOIXFR
    | IPXFR
    | CIDSCHG
    | DISCINT
    | SRQINT
    | WKUPINT;

// GAHBCFG.
const GINT: u32 = 1 << 0;
const TXFELVL: u32 = 1 << 7;
// GUSBCFG.
pub(super) const FHMOD: u32 = 1 << 29;
// GRSTCTL.
const CSRST: u32 = 1 << 0;
const RXFFLSH: u32 = 1 << 4;
const TXFFLSH: u32 = 1 << 5;
const AHBIDL: u32 = 1 << 31;
// GCCFG.
pub(super) const PWRDWN: u32 = 1 << 16;
const VBUSASEN: u32 = 1 << 18;
pub(super) const VBUSBSEN: u32 = 1 << 19;
const SOFOUTEN: u32 = 1 << 20;
pub(super) const NOVBUSSENS: u32 = 1 << 21;
// GOTGCTL.
const SRQ: u32 = 1 << 1;
const HNPRQ: u32 = 1 << 9;
const CIDSTS: u32 = 1 << 16;
const BSVLD: u32 = 1 << 19;
/// What the F407's core answers in CID: the synopsys-usb-otg driver's "F429-like" 0x1200, which
/// selects the `NOVBUSSENS` bit and the re-enable of OUT endpoints on a completed transfer. ST's
/// file says 0x1000.
pub const CID: u32 = 0x0000_1200;
/// GNPTXSTS, host mode only: its reset value.
const GNPTXSTS: u32 = 0x0008_0200;

// DCTL.
const RWUSIG: u32 = 1 << 0;
pub(super) const SDIS: u32 = 1 << 1;
const GINSTS: u32 = 1 << 2;
const GONSTS: u32 = 1 << 3;
const TCTL: u32 = 0b111 << 4;
const SGINAK: u32 = 1 << 7;
const CGINAK: u32 = 1 << 8;
const SGONAK: u32 = 1 << 9;
const CGONAK: u32 = 1 << 10;
const POPRGDNE: u32 = 1 << 11;
// DCFG.
const NZLSOHSK: u32 = 1 << 2;
const DSPD: u32 = 0b11;
// DSTS: bit 4 is reserved and reads 1 (the table's reset value 0x10).
const DSTS_RESERVED: u32 = 1 << 4;

// DIEPCTLx / DOEPCTLx.
pub(super) const EPENA: u32 = 1 << 31;
const EPDIS: u32 = 1 << 30;
const SNAK: u32 = 1 << 27;
const CNAK: u32 = 1 << 26;
const TXFNUM: u32 = 0xF << 22;
pub(super) const STALL: u32 = 1 << 21;
const SNPM: u32 = 1 << 20;
const EPTYP: u32 = 0b11 << 18;
pub(super) const NAKSTS: u32 = 1 << 17;
pub(super) const USBAEP: u32 = 1 << 15;
const MPSIZ: u32 = 0x7FF;
const MPSIZ0: u32 = 0b11;
// DIEPINTx / DOEPINTx.
pub(super) const XFRC: u32 = 1 << 0;
const EPDISD: u32 = 1 << 1;
pub(super) const STUP: u32 = 1 << 3;
const IN_INT_CLEARED: u32 = XFRC | EPDISD | (1 << 3) | (1 << 4) | (1 << 6);
const OUT_INT_CLEARED: u32 = XFRC | EPDISD | STUP | (1 << 4) | (1 << 6);
pub(super) const TXFE: u32 = 1 << 7;
/// DOEPINTx bit 7: reserved, reads 1 (the table's reset value 0x80).
const DOEPINT_RESERVED: u32 = 1 << 7;

// Receive status entries (GRXSTSR/GRXSTSP, device mode).
pub(super) const PKTSTS_OUT_DATA: u32 = 2;
pub(super) const PKTSTS_OUT_DONE: u32 = 3;
pub(super) const PKTSTS_SETUP_DONE: u32 = 4;
pub(super) const PKTSTS_SETUP_DATA: u32 = 6;

/// What a device answers one token with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handshake {
    /// Data taken (OUT, SETUP) or sent (IN).
    Ack,
    /// Not now: the host tries again later.
    Nak,
    /// The endpoint is halted.
    Stall,
    /// Nothing answers (wrong address, inactive endpoint, no device).
    Silent,
}

/// One endpoint's three registers.
#[derive(Clone, Debug, Default)]
struct Endpoint {
    /// The stored bits of DxEPCTL: EPENA, STALL, TXFNUM, SNPM, EPTYP, NAKSTS, USBAEP, MPSIZ.
    ctl: u32,
    /// DxEPINT's latched bits (TXFE is computed).
    int: u32,
    tsiz: u32,
}

/// The receive FIFO: status entries with their packets, and the packet whose status was popped
/// and whose words the application is reading.
#[derive(Clone, Debug, Default)]
struct RxFifo {
    entries: VecDeque<(u32, Vec<u32>)>,
    reading: VecDeque<u32>,
    /// Words in use: one per status entry plus every data word not yet read.
    used: usize,
}

impl RxFifo {
    fn push(&mut self, status: u32, data: Vec<u32>) {
        self.used += 1 + data.len();
        self.entries.push_back((status, data));
    }

    fn head(&self) -> u32 {
        self.entries.front().map_or(0, |entry| entry.0)
    }
}

/// A receive status word.
pub(super) fn rx_status(ep: usize, bcnt: usize, pktsts: u32, frame: u32) -> u32 {
    (ep as u32 & 0xF) | ((bcnt as u32 & 0x7FF) << 4) | (pktsts << 17) | ((frame & 0xF) << 21)
}

/// The words a packet occupies in a FIFO, little-endian as the core packs them.
fn pack(data: &[u8]) -> Vec<u32> {
    data.chunks(4)
        .map(|chunk| {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            u32::from_le_bytes(word)
        })
        .collect()
}

fn words(bytes: usize) -> usize {
    bytes.div_ceil(4)
}

fn merge(old: u32, value: u32, mask: u32) -> u32 {
    (old & !mask) | (value & mask)
}

/// Every register of the core and what fills them.
#[derive(Debug)]
pub struct Core {
    gotgctl: u32,
    gotgint: u32,
    gahbcfg: u32,
    gusbcfg: u32,
    txfnum: u32,
    /// GINTSTS's latched bits; the rest is computed.
    gintsts: u32,
    gintmsk: u32,
    grxfsiz: u32,
    gnptxfsiz: u32,
    gccfg: u32,
    cid: u32,
    hptxfsiz: u32,
    dieptxf: [u32; 3],
    dcfg: u32,
    /// DCTL's stored bits: RWUSIG, SDIS, TCTL, POPRGDNE.
    dctl: u32,
    global_in_nak: bool,
    global_out_nak: bool,
    diepmsk: u32,
    doepmsk: u32,
    daintmsk: u32,
    dvbusdis: u32,
    dvbuspulse: u32,
    diepempmsk: u32,
    ep_in: [Endpoint; ENDPOINTS],
    ep_out: [Endpoint; ENDPOINTS],
    pcgcctl: u32,
    host_block: Vec<u32>,
    rx: RxFifo,
    tx: [VecDeque<u32>; ENDPOINTS],
    /// DSTS.ENUMSPD: 0b11 (full speed, 48 MHz PHY clock) once a bus reset ended.
    speed: u32,
    suspended: bool,
    frame: u32,
    /// The address the core still answers at while the SET_ADDRESS transfer that changed DCFG.DAD
    /// finishes its status stage (the driver sets the address before the status stage).
    previous_address: Option<u8>,
    /// VBUS on the connector (the cable is in).
    pub vbus: bool,
    /// Something the host may be waiting on changed since the last look.
    pub changed: bool,
    /// What the firmware did that the model does not do, by reason.
    pub unsupported: BTreeMap<&'static str, u64>,
    /// Reasons seen for the first time, for the session's `told` list.
    pub to_tell: Vec<(&'static str, &'static str)>,
    /// SETUP packets pushed into a receive FIFO already full.
    pub rx_overflows: u64,
    /// IN endpoints 1-3 enabled while not active (armed before the host configured the device).
    pub armed_inactive: u64,
    /// IN endpoints activated (USBAEP set) with a transfer still armed from while inactive.
    pub stranded_on_activation: u64,
}

impl Default for Core {
    fn default() -> Self {
        let reset = |table: &[rigless::soc::RegisterSpec], row: usize| table[row].reset as u32;
        let g = &global::REGISTERS;
        let d = &device::REGISTERS;
        let mut ep_out: [Endpoint; ENDPOINTS] = Default::default();
        ep_out[0].ctl = USBAEP;
        Self {
            gotgctl: reset(g, global::Register::FsGotgctl.index()),
            gotgint: 0,
            gahbcfg: 0,
            gusbcfg: reset(g, global::Register::FsGusbcfg.index()),
            txfnum: 0,
            gintsts: 0,
            gintmsk: 0,
            grxfsiz: reset(g, global::Register::FsGrxfsiz.index()),
            gnptxfsiz: reset(g, global::Register::FsGnptxfsizDevice.index()),
            gccfg: 0,
            cid: CID,
            hptxfsiz: reset(g, global::Register::FsHptxfsiz.index()),
            dieptxf: [
                reset(g, global::Register::FsDieptxf1.index()),
                reset(g, global::Register::FsDieptxf2.index()),
                reset(g, global::Register::FsDieptxf3.index()),
            ],
            dcfg: reset(d, device::Register::FsDcfg.index()),
            dctl: 0,
            global_in_nak: false,
            global_out_nak: false,
            diepmsk: 0,
            doepmsk: 0,
            daintmsk: 0,
            dvbusdis: reset(d, device::Register::Dvbusdis.index()),
            dvbuspulse: reset(d, device::Register::Dvbuspulse.index()),
            diepempmsk: 0,
            ep_in: Default::default(),
            ep_out,
            pcgcctl: 0,
            host_block: host::REGISTERS.iter().map(|r| r.reset as u32).collect(),
            rx: RxFifo::default(),
            tx: Default::default(),
            speed: 0,
            suspended: false,
            frame: 0,
            previous_address: None,
            vbus: false,
            changed: false,
            unsupported: BTreeMap::new(),
            to_tell: Vec::new(),
            rx_overflows: 0,
            armed_inactive: 0,
            stranded_on_activation: 0,
        }
    }
}

impl Core {
    /// Counts something the firmware did that the model does not do (and tells it once).
    pub fn note(&mut self, register: &'static str, reason: &'static str) {
        let count = self.unsupported.entry(reason).or_insert(0);
        if *count == 0 {
            self.to_tell.push((register, reason));
        }
        *count += 1;
    }

    /// The core and its state, back to reset, keeping what the model counted.
    pub fn restart(&mut self) {
        let unsupported = std::mem::take(&mut self.unsupported);
        let to_tell = std::mem::take(&mut self.to_tell);
        *self = Self {
            unsupported,
            to_tell,
            rx_overflows: self.rx_overflows,
            armed_inactive: self.armed_inactive,
            stranded_on_activation: self.stranded_on_activation,
            vbus: self.vbus,
            ..Self::default()
        };
    }

    // ------------------------------------------------------------------ what the bus sees

    /// The device's D+ pull-up is on: device mode, transceiver powered, not soft-disconnected,
    /// and a B-session (VBUS sensing off with `NOVBUSSENS`, or VBUS seen by `VBUSBSEN`).
    pub fn pullup(&self) -> bool {
        let session = self.gccfg & NOVBUSSENS != 0 || (self.gccfg & VBUSBSEN != 0 && self.vbus);
        self.gusbcfg & FHMOD == 0
            && self.gccfg & PWRDWN != 0
            && self.dctl & SDIS == 0
            && self.pcgcctl & 1 == 0
            && session
    }

    /// The level of the OTG FS global interrupt: an unmasked GINTSTS bit with `GINT` set.
    pub fn line(&self) -> Level {
        Level::from(self.gahbcfg & GINT != 0 && self.gintsts_value() & self.gintmsk != 0)
    }

    /// DCFG.DAD.
    pub fn address(&self) -> u8 {
        ((self.dcfg >> 4) & 0x7F) as u8
    }

    fn answers(&self, address: u8) -> bool {
        address == self.address() || self.previous_address == Some(address)
    }

    /// A bus reset begins: `USBRST`, and every endpoint but 0 inactive (34.16.4, `USBAEP`).
    pub fn bus_reset(&mut self) {
        self.gintsts |= USBRST;
        self.suspended = false;
        self.previous_address = None;
        for ep in 1..ENDPOINTS {
            self.ep_in[ep].ctl &= !USBAEP;
            self.ep_out[ep].ctl &= !USBAEP;
        }
    }

    /// The bus reset ended and the speed is known: `ENUMDNE`, DSTS.ENUMSPD full speed.
    pub fn enumeration_done(&mut self) {
        self.gintsts |= ENUMDNE;
        self.speed = 0b11;
    }

    /// A start-of-frame token with frame number `frame`.
    pub fn start_of_frame(&mut self, frame: u32) {
        self.frame = frame;
        self.gintsts |= SOF;
        self.suspended = false;
    }

    /// 3 ms of an idle bus: early suspend and suspend, DSTS.SUSPSTS.
    pub fn suspend(&mut self) {
        if !self.suspended && self.speed != 0 {
            self.suspended = true;
            self.gintsts |= ESUSP | USBSUSP;
        }
    }

    fn out_mps(&self, ep: usize) -> usize {
        if ep == 0 {
            mps0(self.ep_in[0].ctl)
        } else {
            (self.ep_out[ep].ctl & MPSIZ) as usize
        }
    }

    fn in_mps(&self, ep: usize) -> usize {
        if ep == 0 {
            mps0(self.ep_in[0].ctl)
        } else {
            (self.ep_in[ep].ctl & MPSIZ) as usize
        }
    }

    fn rx_free(&self) -> usize {
        ((self.grxfsiz & 0xFFFF) as usize).saturating_sub(self.rx.used)
    }

    /// A SETUP packet to endpoint 0 at `address`: always taken (34.17.7), status entries "SETUP
    /// data" and "SETUP done", STUPCNT down, endpoint 0's OUT side disabled and NAKing and both
    /// sides' STALL cleared.
    pub fn setup(&mut self, address: u8, packet: [u8; 8]) -> Handshake {
        if !self.answers(address) {
            return Handshake::Silent;
        }
        if address == self.address() {
            self.previous_address = None;
        }
        self.changed = true;
        self.ep_in[0].ctl &= !STALL;
        self.ep_out[0].ctl &= !STALL;
        if self.rx_free() < 1 + 2 + 1 {
            self.rx_overflows += 1;
        }
        self.rx.push(
            rx_status(0, 8, PKTSTS_SETUP_DATA, self.frame),
            pack(&packet),
        );
        self.rx
            .push(rx_status(0, 0, PKTSTS_SETUP_DONE, self.frame), Vec::new());
        let out = &mut self.ep_out[0];
        let count = (out.tsiz >> 29) & 0b11;
        out.tsiz = merge(out.tsiz, count.saturating_sub(1) << 29, 0b11 << 29);
        out.ctl = (out.ctl & !EPENA) | NAKSTS;
        Handshake::Ack
    }

    fn out_check(&self, address: u8, ep: usize, len: usize) -> Handshake {
        if !self.answers(address) || ep >= ENDPOINTS {
            return Handshake::Silent;
        }
        let ctl = self.ep_out[ep].ctl;
        if ep != 0 && ctl & USBAEP == 0 {
            return Handshake::Silent;
        }
        if ctl & STALL != 0 {
            return Handshake::Stall;
        }
        if self.global_out_nak
            || ctl & EPENA == 0
            || ctl & NAKSTS != 0
            || self.rx_free() < 2 + words(len)
        {
            return Handshake::Nak;
        }
        Handshake::Ack
    }

    /// Whether an OUT packet of `len` bytes would be taken now.
    pub fn out_ready(&self, address: u8, ep: usize, len: usize) -> bool {
        self.out_check(address, ep, len) == Handshake::Ack
    }

    /// An OUT data packet. Taken when the endpoint is enabled, not NAKing and the receive FIFO has
    /// room: status entry "OUT data", and when the transfer completes (PKTCNT runs out or a short
    /// packet) "OUT complete", the endpoint disabled and NAKing.
    pub fn out(&mut self, address: u8, ep: usize, data: &[u8]) -> Handshake {
        let answer = self.out_check(address, ep, data.len());
        if answer != Handshake::Ack {
            return answer;
        }
        self.changed = true;
        let mps = self.out_mps(ep);
        self.rx.push(
            rx_status(ep, data.len(), PKTSTS_OUT_DATA, self.frame),
            pack(data),
        );
        let out = &mut self.ep_out[ep];
        let (size_mask, count_mask) = if ep == 0 {
            (0x7F, 0x1)
        } else {
            (0x7_FFFF, 0x3FF)
        };
        let size = out.tsiz & size_mask;
        let count = (out.tsiz >> 19) & count_mask;
        let complete = count <= 1 || data.len() < mps;
        let size = size.saturating_sub(data.len() as u32);
        let count = count.saturating_sub(1);
        out.tsiz = merge(
            out.tsiz,
            size | (count << 19),
            size_mask | (count_mask << 19),
        );
        if complete {
            out.ctl = (out.ctl & !EPENA) | NAKSTS;
            self.rx
                .push(rx_status(ep, 0, PKTSTS_OUT_DONE, self.frame), Vec::new());
        }
        Handshake::Ack
    }

    fn in_check(&self, address: u8, ep: usize) -> Handshake {
        if !self.answers(address) || ep >= ENDPOINTS {
            return Handshake::Silent;
        }
        let endpoint = &self.ep_in[ep];
        if ep != 0 && endpoint.ctl & USBAEP == 0 {
            return Handshake::Silent;
        }
        if endpoint.ctl & STALL != 0 {
            return Handshake::Stall;
        }
        if self.global_in_nak || endpoint.ctl & EPENA == 0 || endpoint.ctl & NAKSTS != 0 {
            return Handshake::Nak;
        }
        let (size, count) = in_size(ep, endpoint.tsiz);
        if count == 0 || self.tx[ep].len() < words(size.min(self.in_mps(ep))) {
            return Handshake::Nak;
        }
        Handshake::Ack
    }

    /// Whether an IN token would be answered with data now.
    pub fn in_ready(&self, address: u8, ep: usize) -> bool {
        self.in_check(address, ep) == Handshake::Ack
    }

    /// An IN token. Answered with a packet when the endpoint is enabled, not NAKing, PKTCNT is
    /// not zero and the packet (up to MPSIZ of XFRSIZ) is whole in its transmit FIFO; the last
    /// packet of the transfer sets XFRC and disables the endpoint. Appends the packet to `data`.
    pub fn in_token(&mut self, address: u8, ep: usize, data: &mut Vec<u8>) -> Handshake {
        let answer = self.in_check(address, ep);
        if answer != Handshake::Ack {
            return answer;
        }
        self.changed = true;
        let mps = self.in_mps(ep);
        let (size, count) = in_size(ep, self.ep_in[ep].tsiz);
        let packet = size.min(mps);
        let mut left = packet;
        for _ in 0..words(packet) {
            let word = self.tx[ep].pop_front().unwrap_or_default().to_le_bytes();
            let take = left.min(4);
            data.extend_from_slice(&word[..take]);
            left -= take;
        }
        let endpoint = &mut self.ep_in[ep];
        let (size_mask, count_mask) = if ep == 0 {
            (0x7F, 0x3)
        } else {
            (0x7_FFFF, 0x3FF)
        };
        let size = (size - packet) as u32;
        let count = count - 1;
        endpoint.tsiz = merge(
            endpoint.tsiz,
            size | (count << 19),
            size_mask | (count_mask << 19),
        );
        if count == 0 {
            endpoint.ctl &= !EPENA;
            endpoint.int |= XFRC;
        }
        Handshake::Ack
    }

    // ------------------------------------------------------------------ what the firmware sees

    fn tx_depth(&self, ep: usize) -> usize {
        let size = if ep == 0 {
            self.gnptxfsiz
        } else {
            self.dieptxf[ep - 1]
        };
        (size >> 16) as usize
    }

    fn txfe(&self, ep: usize) -> bool {
        let used = self.tx[ep].len();
        if self.gahbcfg & TXFELVL != 0 {
            used == 0
        } else {
            used * 2 <= self.tx_depth(ep)
        }
    }

    fn daint(&self) -> u32 {
        let mut daint = 0;
        for ep in 0..ENDPOINTS {
            let mut mask = self.diepmsk & !TXFE;
            let mut pending = self.ep_in[ep].int;
            if self.diepempmsk & (1 << ep) != 0 {
                mask |= TXFE;
            }
            if self.txfe(ep) {
                pending |= TXFE;
            }
            if pending & mask != 0 {
                daint |= 1 << ep;
            }
            if self.ep_out[ep].int & self.doepmsk & !DOEPINT_RESERVED != 0 {
                daint |= 1 << (16 + ep);
            }
        }
        daint
    }

    fn gintsts_value(&self) -> u32 {
        let mut value = self.gintsts | NPTXFE | PTXFE;
        if !self.rx.entries.is_empty() {
            value |= RXFLVL;
        }
        if self.global_in_nak {
            value |= GINAKEFF;
        }
        if self.global_out_nak {
            value |= GONAKEFF;
        }
        let daint = self.daint() & self.daintmsk;
        if daint & 0xFFFF != 0 {
            value |= IEPINT;
        }
        if daint >> 16 != 0 {
            value |= OEPINT;
        }
        if self.gusbcfg & FHMOD != 0 {
            value |= CMOD;
        }
        value
    }

    /// What a read of `row` of `block` answers, with nothing changed (GRXSTSP peeks).
    pub fn value(&self, block: OtgBlock, row: usize) -> u32 {
        match block {
            OtgBlock::Global => self.global_value(row),
            OtgBlock::Device => self.device_value(row),
            OtgBlock::Host => self.host_block.get(row).copied().unwrap_or(0),
            OtgBlock::PowerClock => self.pcgcctl,
            OtgBlock::Fifo => 0,
        }
    }

    fn global_value(&self, row: usize) -> u32 {
        use global::Register as G;
        let Some(register) = G::from_index(row) else {
            return 0;
        };
        match register {
            G::FsGotgctl => self.gotgctl | CIDSTS | if self.vbus { BSVLD } else { 0 },
            G::FsGotgint => self.gotgint,
            G::FsGahbcfg => self.gahbcfg,
            G::FsGusbcfg => self.gusbcfg,
            G::FsGrstctl => AHBIDL | (self.txfnum << 6),
            G::FsGintsts => self.gintsts_value(),
            G::FsGintmsk => self.gintmsk,
            G::FsGrxstsrDevice | G::FsGrxstsrHost | G::FsGrxstspDevice => self.rx.head(),
            G::FsGrxfsiz => self.grxfsiz,
            G::FsGnptxfsizDevice | G::FsGnptxfsizHost => self.gnptxfsiz,
            G::FsGnptxsts => GNPTXSTS,
            G::FsGccfg => self.gccfg,
            G::FsCid => self.cid,
            G::FsHptxfsiz => self.hptxfsiz,
            G::FsDieptxf1 => self.dieptxf[0],
            G::FsDieptxf2 => self.dieptxf[1],
            G::FsDieptxf3 => self.dieptxf[2],
        }
    }

    fn device_value(&self, row: usize) -> u32 {
        use device::Register as D;
        match row {
            10..=25 => {
                let ep = (row - 10) / 4;
                let e = &self.ep_in[ep];
                return match (row - 10) % 4 {
                    0 => e.ctl | if ep == 0 { USBAEP } else { 0 },
                    1 => e.int | if self.txfe(ep) { TXFE } else { 0 },
                    2 => e.tsiz,
                    _ => self.tx_depth(ep).saturating_sub(self.tx[ep].len()) as u32,
                };
            }
            26..=37 => {
                let ep = (row - 26) / 3;
                let e = &self.ep_out[ep];
                return match (row - 26) % 3 {
                    0 => e.ctl,
                    1 => e.int | DOEPINT_RESERVED,
                    _ => e.tsiz,
                };
            }
            _ => {}
        }
        let Some(register) = D::from_index(row) else {
            return 0;
        };
        match register {
            D::FsDcfg => self.dcfg,
            D::FsDctl => {
                self.dctl
                    | if self.global_in_nak { GINSTS } else { 0 }
                    | if self.global_out_nak { GONSTS } else { 0 }
            }
            D::FsDsts => {
                u32::from(self.suspended)
                    | (self.speed << 1)
                    | DSTS_RESERVED
                    | ((self.frame & 0x3FFF) << 8)
            }
            D::FsDiepmsk => self.diepmsk,
            D::FsDoepmsk => self.doepmsk,
            D::FsDaint => self.daint(),
            D::FsDaintmsk => self.daintmsk,
            D::Dvbusdis => self.dvbusdis,
            D::Dvbuspulse => self.dvbuspulse,
            D::Diepempmsk => self.diepempmsk,
            _ => 0,
        }
    }

    /// A read over the bus: GRXSTSP pops the receive FIFO's status entry.
    pub fn read(&mut self, block: OtgBlock, row: usize) -> u32 {
        if block == OtgBlock::Global && row == global::Register::FsGrxstspDevice.index() {
            return self.pop_status();
        }
        self.value(block, row)
    }

    fn pop_status(&mut self) -> u32 {
        self.changed = true;
        let Some((status, data)) = self.rx.entries.pop_front() else {
            self.note(
                "FS_GRXSTSP_Device",
                "GRXSTSP popped with the receive FIFO empty (reads 0)",
            );
            return 0;
        };
        if !self.rx.reading.is_empty() {
            self.note(
                "FS_GRXSTSP_Device",
                "GRXSTSP popped before the previous packet's data was read (the rest is dropped)",
            );
            self.rx.used -= self.rx.reading.len();
            self.rx.reading.clear();
        }
        self.rx.used -= 1;
        self.rx.reading = data.into();
        let ep = (status & 0xF) as usize;
        match (status >> 17) & 0xF {
            PKTSTS_OUT_DONE => self.ep_out[ep].int |= XFRC,
            PKTSTS_SETUP_DONE => self.ep_out[ep].int |= STUP,
            _ => {}
        }
        status
    }

    /// A read of the FIFO window at `offset`: the next word of the receive FIFO's popped packet.
    pub fn read_fifo(&mut self, offset: u64) -> u32 {
        if offset >= 0x1_0000 {
            self.note(
                "OTG_FS_FIFO",
                "direct FIFO RAM access or reserved FIFO space (reads 0)",
            );
            return 0;
        }
        match self.rx.reading.pop_front() {
            Some(word) => {
                self.changed = true;
                self.rx.used -= 1;
                word
            }
            None => {
                self.note(
                    "OTG_FS_FIFO",
                    "receive FIFO read with no packet data popped (reads 0)",
                );
                0
            }
        }
    }

    /// What a read of the FIFO window at `offset` would answer, with nothing popped.
    pub fn peek_fifo(&self, offset: u64) -> u32 {
        if offset >= 0x1_0000 {
            0
        } else {
            self.rx.reading.front().copied().unwrap_or(0)
        }
    }

    /// A write of the FIFO window at `offset`: a word pushed into endpoint n's transmit FIFO.
    pub fn write_fifo(&mut self, offset: u64, value: u32, full_word: bool) {
        self.changed = true;
        let page = (offset >> 12) as usize;
        if offset >= 0x1_0000 || page >= ENDPOINTS {
            self.note(
                "OTG_FS_FIFO",
                "write to a FIFO page of an endpoint the core lacks, or to FIFO RAM",
            );
            return;
        }
        if !full_word {
            self.note(
                "OTG_FS_FIFO",
                "transmit FIFO written narrower than a word (pushed as a word)",
            );
        }
        if self.tx[page].len() >= self.tx_depth(page) {
            self.note(
                "OTG_FS_FIFO",
                "write to a full transmit FIFO (the word is dropped)",
            );
            return;
        }
        self.tx[page].push_back(value);
    }

    /// A write over the bus of `value` under `mask` (the bytes the access covers).
    pub fn write(&mut self, block: OtgBlock, row: usize, value: u32, mask: u32) {
        self.changed = true;
        match block {
            OtgBlock::Global => self.write_global(row, value, mask),
            OtgBlock::Device => self.write_device(row, value, mask),
            OtgBlock::Host => {
                if let Some(slot) = self.host_block.get_mut(row) {
                    *slot = merge(*slot, value, mask);
                }
                self.note(
                    "OTG_FS_HOST",
                    "host-mode register written (host mode is not modelled)",
                );
            }
            OtgBlock::PowerClock => {
                self.pcgcctl = merge(self.pcgcctl, value, mask & 0b11);
                if self.pcgcctl & 0b11 != 0 {
                    self.note(
                        "FS_PCGCCTL",
                        "PHY clock stopped or HCLK gated (not modelled: the core runs on)",
                    );
                }
            }
            OtgBlock::Fifo => {}
        }
    }

    fn write_global(&mut self, row: usize, value: u32, mask: u32) {
        use global::Register as G;
        let set = value & mask;
        let Some(register) = G::from_index(row) else {
            return;
        };
        match register {
            G::FsGotgctl => {
                self.gotgctl = merge(self.gotgctl, value, mask & (SRQ | HNPRQ | (0b11 << 10)));
                if set & (SRQ | HNPRQ) != 0 {
                    self.note(
                        "FS_GOTGCTL",
                        "session or HNP request (the OTG protocols are not modelled)",
                    );
                }
            }
            G::FsGotgint => self.gotgint &= !set,
            G::FsGahbcfg => {
                self.gahbcfg = merge(self.gahbcfg, value, mask & (GINT | TXFELVL | (1 << 8)))
            }
            G::FsGusbcfg => {
                self.gusbcfg = merge(self.gusbcfg, value, mask);
                if self.gusbcfg & FHMOD != 0 {
                    self.note(
                        "FS_GUSBCFG",
                        "host mode forced (only device mode is modelled)",
                    );
                }
            }
            G::FsGrstctl => {
                self.txfnum = merge(self.txfnum << 6, value, mask & (0x1F << 6)) >> 6;
                if set & CSRST != 0 {
                    self.soft_reset();
                }
                if set & RXFFLSH != 0 {
                    self.rx = RxFifo::default();
                }
                if set & TXFFLSH != 0 {
                    if self.txfnum == 0x10 {
                        self.tx.iter_mut().for_each(VecDeque::clear);
                    } else if let Some(fifo) = self.tx.get_mut(self.txfnum as usize) {
                        fifo.clear();
                    }
                }
            }
            G::FsGintsts => self.gintsts &= !(set & GINTSTS_LATCHED),
            G::FsGintmsk => self.gintmsk = merge(self.gintmsk, value, mask),
            G::FsGrxfsiz => self.grxfsiz = merge(self.grxfsiz, value, mask & 0xFFFF),
            G::FsGnptxfsizDevice | G::FsGnptxfsizHost => {
                self.gnptxfsiz = merge(self.gnptxfsiz, value, mask)
            }
            G::FsGccfg => {
                let bits = PWRDWN | VBUSASEN | VBUSBSEN | SOFOUTEN | NOVBUSSENS;
                self.gccfg = merge(self.gccfg, value, mask & bits);
                if self.gccfg & SOFOUTEN != 0 {
                    self.note("FS_GCCFG", "SOF pulse output enabled (not modelled)");
                }
            }
            G::FsCid => self.cid = merge(self.cid, value, mask),
            G::FsHptxfsiz => self.hptxfsiz = merge(self.hptxfsiz, value, mask),
            G::FsDieptxf1 => self.dieptxf[0] = merge(self.dieptxf[0], value, mask),
            G::FsDieptxf2 => self.dieptxf[1] = merge(self.dieptxf[1], value, mask),
            G::FsDieptxf3 => self.dieptxf[2] = merge(self.dieptxf[2], value, mask),
            G::FsGrxstsrDevice | G::FsGrxstsrHost | G::FsGrxstspDevice | G::FsGnptxsts => {}
        }
    }

    /// CSRST: the FIFOs flushed, the interrupts cleared, every endpoint disabled. The
    /// configuration registers stay (the driver sets `FDMOD` before the reset and relies on it).
    fn soft_reset(&mut self) {
        self.rx = RxFifo::default();
        self.tx.iter_mut().for_each(VecDeque::clear);
        self.gintsts = 0;
        self.global_in_nak = false;
        self.global_out_nak = false;
        for endpoint in self.ep_in.iter_mut().chain(self.ep_out.iter_mut()) {
            endpoint.int = 0;
            endpoint.ctl &= !EPENA;
        }
    }

    fn write_device(&mut self, row: usize, value: u32, mask: u32) {
        use device::Register as D;
        let set = value & mask;
        match row {
            10..=25 => {
                let ep = (row - 10) / 4;
                match (row - 10) % 4 {
                    0 => self.write_in_ctl(ep, value, mask),
                    1 => self.ep_in[ep].int &= !(set & IN_INT_CLEARED),
                    2 => {
                        let bits = if ep == 0 {
                            0x7F | (0b11 << 19)
                        } else {
                            0x7_FFFF | (0x3FF << 19) | (0b11 << 29)
                        };
                        self.ep_in[ep].tsiz = merge(self.ep_in[ep].tsiz, value, mask & bits);
                    }
                    _ => {}
                }
                return;
            }
            26..=37 => {
                let ep = (row - 26) / 3;
                match (row - 26) % 3 {
                    0 => self.write_out_ctl(ep, value, mask),
                    1 => self.ep_out[ep].int &= !(set & OUT_INT_CLEARED),
                    _ => {
                        let bits = if ep == 0 {
                            0x7F | (1 << 19) | (0b11 << 29)
                        } else {
                            0x7_FFFF | (0x3FF << 19) | (0b11 << 29)
                        };
                        self.ep_out[ep].tsiz = merge(self.ep_out[ep].tsiz, value, mask & bits);
                    }
                }
                return;
            }
            _ => {}
        }
        let Some(register) = D::from_index(row) else {
            return;
        };
        match register {
            D::FsDcfg => {
                let before = self.address();
                self.dcfg = merge(self.dcfg, value, mask);
                if self.address() != before {
                    self.previous_address = Some(before);
                }
                if self.dcfg & NZLSOHSK != 0 {
                    self.note(
                        "FS_DCFG",
                        "NZLSOHSK: STALL on a non-zero status OUT (not modelled)",
                    );
                }
                if self.dcfg & DSPD != 0b11 {
                    self.note(
                        "FS_DCFG",
                        "device speed other than full speed (only full speed is modelled)",
                    );
                }
            }
            D::FsDctl => {
                self.dctl = merge(self.dctl, value, mask & (RWUSIG | SDIS | TCTL | POPRGDNE));
                if set & SGINAK != 0 {
                    self.global_in_nak = true;
                }
                if set & CGINAK != 0 {
                    self.global_in_nak = false;
                }
                if set & SGONAK != 0 {
                    self.global_out_nak = true;
                }
                if set & CGONAK != 0 {
                    self.global_out_nak = false;
                }
                if self.dctl & RWUSIG != 0 {
                    self.note(
                        "FS_DCTL",
                        "remote wakeup signalling (suspend and resume are not modelled)",
                    );
                }
                if self.dctl & TCTL != 0 {
                    self.note("FS_DCTL", "test control mode (not modelled)");
                }
            }
            D::FsDiepmsk => self.diepmsk = merge(self.diepmsk, value, mask),
            D::FsDoepmsk => self.doepmsk = merge(self.doepmsk, value, mask),
            D::FsDaintmsk => self.daintmsk = merge(self.daintmsk, value, mask),
            D::Dvbusdis => self.dvbusdis = merge(self.dvbusdis, value, mask),
            D::Dvbuspulse => self.dvbuspulse = merge(self.dvbuspulse, value, mask),
            D::Diepempmsk => self.diepempmsk = merge(self.diepempmsk, value, mask & 0xFFFF),
            _ => {}
        }
    }

    fn write_in_ctl(&mut self, ep: usize, value: u32, mask: u32) {
        let set = value & mask;
        let bits = if ep == 0 {
            MPSIZ0 | TXFNUM
        } else {
            MPSIZ | USBAEP | EPTYP | TXFNUM | STALL
        };
        let before = self.ep_in[ep].ctl;
        let endpoint = &mut self.ep_in[ep];
        endpoint.ctl = merge(endpoint.ctl, value, mask & bits);
        // Endpoint 0's STALL is `rs`: the application sets it, a SETUP clears it.
        endpoint.ctl |= set & STALL;
        if set & SNAK != 0 {
            endpoint.ctl |= NAKSTS;
        }
        if set & CNAK != 0 {
            endpoint.ctl &= !NAKSTS;
        }
        // A read-modify-write of an enabled endpoint writes EPENA back with EPDIS: the disable
        // wins. EPENA written while already set changes nothing.
        if set & EPDIS != 0 && endpoint.ctl & EPENA != 0 {
            endpoint.ctl &= !EPENA;
            endpoint.int |= EPDISD;
        } else if set & EPENA != 0 && before & EPENA == 0 {
            endpoint.ctl |= EPENA;
            let (ctl, tsiz) = (endpoint.ctl, endpoint.tsiz);
            if ep != 0 && ctl & USBAEP == 0 {
                // Armed while inactive (before the host configured the device, or between a
                // bus reset and the driver's configure): no token reaches it.
                self.armed_inactive += 1;
            }
            if (ctl & EPTYP) >> 18 == 0b01 {
                self.note(
                    "DIEPCTL",
                    "isochronous IN endpoint enabled (isochronous transfers are not modelled)",
                );
            }
            if ep != 0 && ctl & USBAEP != 0 && ((ctl & TXFNUM) >> 22) as usize != ep {
                self.note(
                    "DIEPCTL",
                    "IN endpoint on another endpoint's transmit FIFO (FIFO n is endpoint n's here)",
                );
            }
            if ep != 0 && (tsiz >> 29) & 0b11 > 1 {
                self.note(
                    "DIEPTSIZ",
                    "MCNT above 1 (periodic multi-packet frames are not modelled)",
                );
            }
        }
        // Activated with a transfer armed while it was inactive: the part keeps it armed (EPENA
        // is set-only), so unless its data is still whole in the FIFO and the NAK is cleared the
        // endpoint is stranded: enabled, and the driver's write() refuses until it completes.
        let ctl = self.ep_in[ep].ctl;
        if ep != 0 && before & USBAEP == 0 && ctl & USBAEP != 0 && ctl & EPENA != 0 {
            self.stranded_on_activation += 1;
        }
    }

    fn write_out_ctl(&mut self, ep: usize, value: u32, mask: u32) {
        let set = value & mask;
        let bits = if ep == 0 {
            MPSIZ0 | SNPM
        } else {
            MPSIZ | USBAEP | EPTYP | STALL | SNPM
        };
        let endpoint = &mut self.ep_out[ep];
        endpoint.ctl = merge(endpoint.ctl, value, mask & bits);
        endpoint.ctl |= set & STALL;
        if set & SNAK != 0 {
            endpoint.ctl |= NAKSTS;
        }
        if set & CNAK != 0 {
            endpoint.ctl &= !NAKSTS;
        }
        if ep != 0 && set & EPDIS != 0 && endpoint.ctl & EPENA != 0 {
            endpoint.ctl &= !EPENA;
            endpoint.int |= EPDISD;
        } else if set & EPENA != 0 {
            endpoint.ctl |= EPENA;
        }
        let ctl = endpoint.ctl;
        if ctl & SNPM != 0 {
            self.note(
                "DOEPCTL",
                "snoop mode (not modelled: data is taken as in normal mode)",
            );
        }
        if set & EPENA != 0 && (ctl & EPTYP) >> 18 == 0b01 {
            self.note(
                "DOEPCTL",
                "isochronous OUT endpoint enabled (isochronous transfers are not modelled)",
            );
        }
    }
}

/// Endpoint 0's MPSIZ encoding: 64, 32, 16, 8 bytes.
fn mps0(ctl: u32) -> usize {
    [64, 32, 16, 8][(ctl & MPSIZ0) as usize]
}

/// DIEPTSIZx's XFRSIZ and PKTCNT.
fn in_size(ep: usize, tsiz: u32) -> (usize, u32) {
    if ep == 0 {
        ((tsiz & 0x7F) as usize, (tsiz >> 19) & 0b11)
    } else {
        ((tsiz & 0x7_FFFF) as usize, (tsiz >> 19) & 0x3FF)
    }
}

impl Core {
    /// IN endpoint `ep`'s DIEPCTL, DIEPTSIZ and the words in its transmit FIFO.
    pub fn in_endpoint(&self, ep: usize) -> (u32, u32, usize) {
        let e = &self.ep_in[ep];
        (e.ctl, e.tsiz, self.tx[ep].len())
    }

    /// The endpoints and FIFOs, for a log.
    pub fn describe(&self) -> String {
        let mut out = format!(
            "gintsts={:#010x} gintmsk={:#010x} gahbcfg={:#x} dcfg={:#x} dctl={:#x} daint={:#x} daintmsk={:#x} diepmsk={:#x} rx={} entries/{} words (reading {}) grxfsiz={}\n",
            self.gintsts_value(),
            self.gintmsk,
            self.gahbcfg,
            self.dcfg,
            self.dctl,
            self.daint(),
            self.daintmsk,
            self.diepmsk,
            self.rx.entries.len(),
            self.rx.used,
            self.rx.reading.len(),
            self.grxfsiz
        );
        for ep in 0..ENDPOINTS {
            out += &format!(
                "ep{ep}: IN ctl={:#010x} int={:#x} tsiz={:#x} fifo={}/{} | OUT ctl={:#010x} int={:#x} tsiz={:#x}\n",
                self.ep_in[ep].ctl,
                self.ep_in[ep].int,
                self.ep_in[ep].tsiz,
                self.tx[ep].len(),
                self.tx_depth(ep),
                self.ep_out[ep].ctl,
                self.ep_out[ep].int,
                self.ep_out[ep].tsiz
            );
        }
        out
    }
}
