//! The core's registers one behaviour at a time, and the model on the board's bus (wiring check,
//! dispatch to the five slots, interrupt line 67 driven from a block that has no interrupt).

use rigless::device::Level;
use rigless::mcu::Operate;
use rigless::soc::stm32f427::generated::{otg_fs_device as device, otg_fs_global as global};
use rigless::soc::{Layout, Width};
use rigless::time::VirtualNanos;

use super::usb_core::{Core, Handshake};
use super::{OtgBlock, OtgFs};
use crate::board::VirtualF407;

const ALL: u32 = 0xFFFF_FFFF;
const EPENA: u32 = 1 << 31;
const EPDIS: u32 = 1 << 30;
const SNAK: u32 = 1 << 27;
const CNAK: u32 = 1 << 26;
const NAKSTS: u32 = 1 << 17;
const USBAEP: u32 = 1 << 15;
const RXFLVL: u32 = 1 << 4;
const IEPINT: u32 = 1 << 18;

fn g(core: &mut Core, register: global::Register) -> u32 {
    core.read(OtgBlock::Global, register.index())
}

fn set_g(core: &mut Core, register: global::Register, value: u32) {
    core.write(OtgBlock::Global, register.index(), value, ALL);
}

fn d(core: &mut Core, row: usize) -> u32 {
    core.read(OtgBlock::Device, row)
}

fn set_d(core: &mut Core, row: usize, value: u32) {
    core.write(OtgBlock::Device, row, value, ALL);
}

/// A read-modify-write setting `bits`, as the driver's `modify_reg!` does.
fn or_d(core: &mut Core, row: usize, bits: u32) {
    let value = d(core, row);
    set_d(core, row, value | bits);
}

/// DIEPCTLn, DIEPINTn, DIEPTSIZn, DTXFSTSn; DOEPCTLn, DOEPINTn, DOEPTSIZn.
fn diepctl(ep: usize) -> usize {
    10 + 4 * ep
}
fn diepint(ep: usize) -> usize {
    11 + 4 * ep
}
fn dieptsiz(ep: usize) -> usize {
    12 + 4 * ep
}
fn dtxfsts(ep: usize) -> usize {
    13 + 4 * ep
}
fn doepctl(ep: usize) -> usize {
    26 + 3 * ep
}
fn doepint(ep: usize) -> usize {
    27 + 3 * ep
}

/// A core set up as the driver leaves it after a bus reset: device mode, transceiver on, 48-word
/// receive FIFO, 16-word transmit FIFOs, endpoint 0 both ways, EP1 OUT and EP2 IN bulk 64.
fn configured() -> Core {
    let mut core = Core::default();
    set_g(&mut core, global::Register::FsGusbcfg, 1 << 30);
    set_g(&mut core, global::Register::FsGccfg, (1 << 16) | (1 << 21));
    set_g(&mut core, global::Register::FsGrxfsiz, 48);
    set_g(
        &mut core,
        global::Register::FsGnptxfsizDevice,
        (16 << 16) | 48,
    );
    set_g(&mut core, global::Register::FsDieptxf1, (16 << 16) | 64);
    set_g(&mut core, global::Register::FsDieptxf2, (16 << 16) | 80);
    set_d(&mut core, device::Register::FsDcfg.index(), 0b11);
    core.bus_reset();
    core.enumeration_done();
    set_d(&mut core, diepctl(0), SNAK);
    set_d(&mut core, doepctl(0), EPENA | CNAK);
    set_d(&mut core, 28, (1 << 29) | (1 << 19) | 64);
    set_d(
        &mut core,
        diepctl(2),
        SNAK | USBAEP | (0b10 << 18) | (2 << 22) | 64,
    );
    set_d(
        &mut core,
        doepctl(1),
        EPENA | CNAK | USBAEP | (0b10 << 18) | 64,
    );
    core
}

#[test]
fn the_core_resets_with_its_master_idle_and_the_f429_like_id() {
    let mut core = Core::default();
    assert_eq!(g(&mut core, global::Register::FsCid), 0x0000_1200);
    assert_eq!(g(&mut core, global::Register::FsGrstctl), 0x8000_0000);
    set_g(
        &mut core,
        global::Register::FsGrstctl,
        0b11_0111 | (0x10 << 6),
    );
    assert_eq!(
        g(&mut core, global::Register::FsGrstctl),
        0x8000_0000 | (0x10 << 6),
        "every reset and flush bit clears itself; TXFNUM stays"
    );
    assert_eq!(g(&mut core, global::Register::FsGintsts), 0x0400_0020);
}

#[test]
fn latched_interrupts_clear_on_a_written_one_and_gate_the_line() {
    let mut core = configured();
    let usbrst_enumdne = (1 << 12) | (1 << 13);
    assert_eq!(
        g(&mut core, global::Register::FsGintsts) & usbrst_enumdne,
        usbrst_enumdne
    );
    set_g(&mut core, global::Register::FsGintmsk, 1 << 12);
    assert_eq!(core.line(), Level::Low, "GINT clear");
    set_g(&mut core, global::Register::FsGahbcfg, 1);
    assert_eq!(core.line(), Level::High);
    set_g(&mut core, global::Register::FsGintsts, 1 << 12);
    assert_eq!(core.line(), Level::Low);
    assert_eq!(
        g(&mut core, global::Register::FsGintsts) & usbrst_enumdne,
        1 << 13
    );
}

#[test]
fn a_setup_queues_its_data_and_its_end_and_naks_endpoint_0() {
    let mut core = configured();
    let packet = [0x80, 6, 0, 1, 0, 0, 18, 0];
    assert_eq!(core.setup(0, packet), Handshake::Ack);
    assert_ne!(g(&mut core, global::Register::FsGintsts) & RXFLVL, 0);
    let peek = g(&mut core, global::Register::FsGrxstsrDevice);
    assert_eq!((peek >> 17) & 0xF, 6, "SETUP data");
    assert_eq!((peek >> 4) & 0x7FF, 8);
    assert_eq!(
        g(&mut core, global::Register::FsGrxstsrDevice),
        peek,
        "GRXSTSR only peeks"
    );
    assert_eq!(g(&mut core, global::Register::FsGrxstspDevice), peek);
    assert_eq!(core.read_fifo(0), u32::from_le_bytes([0x80, 6, 0, 1]));
    assert_eq!(core.read_fifo(0x20), u32::from_le_bytes([0, 0, 18, 0]));
    let done = g(&mut core, global::Register::FsGrxstspDevice);
    assert_eq!((done >> 17) & 0xF, 4, "SETUP done");
    assert_eq!(g(&mut core, global::Register::FsGintsts) & RXFLVL, 0);
    assert_eq!(
        d(&mut core, doepint(0)) & (1 << 3),
        1 << 3,
        "STUP on the pop"
    );
    let ctl = d(&mut core, doepctl(0));
    assert_eq!(ctl & (EPENA | NAKSTS), NAKSTS, "OUT 0 disabled and NAKing");
    assert_eq!(core.setup(5, packet), Handshake::Silent, "another address");
    assert!(core.unsupported.is_empty());
}

#[test]
fn an_out_packet_waits_for_the_endpoint_and_room_and_ends_the_transfer() {
    let mut core = configured();
    or_d(&mut core, doepctl(1), SNAK);
    assert_eq!(core.out(0, 1, b"hello"), Handshake::Nak, "NAKing");
    or_d(&mut core, doepctl(1), CNAK);
    assert_eq!(core.out(0, 1, b"hello"), Handshake::Ack);
    let status = g(&mut core, global::Register::FsGrxstspDevice);
    assert_eq!(status & 0xF, 1);
    assert_eq!((status >> 4) & 0x7FF, 5);
    assert_eq!((status >> 17) & 0xF, 2, "OUT data");
    assert_eq!(core.read_fifo(0), u32::from_le_bytes(*b"hell"));
    assert_eq!(core.read_fifo(0) & 0xFF, u32::from(b'o'));
    assert_eq!(
        d(&mut core, doepctl(1)) & (EPENA | NAKSTS),
        NAKSTS,
        "PKTCNT 0: one packet ends the transfer"
    );
    assert_eq!(
        core.out(0, 1, b"again"),
        Handshake::Nak,
        "until the driver re-enables it"
    );
    let complete = g(&mut core, global::Register::FsGrxstspDevice);
    assert_eq!((complete >> 17) & 0xF, 3, "OUT complete");
    assert_eq!(d(&mut core, doepint(1)) & 1, 1, "XFRC on the pop");
    or_d(&mut core, doepctl(1), EPENA | CNAK);
    // 48 words: a 64-byte packet takes 17 and its end 1, so two fit and a third does not.
    for _ in 0..2 {
        or_d(&mut core, doepctl(1), EPENA | CNAK);
        assert_eq!(core.out(0, 1, &[7; 64]), Handshake::Ack);
    }
    or_d(&mut core, doepctl(1), EPENA | CNAK);
    assert_eq!(
        core.out(0, 1, &[7; 64]),
        Handshake::Nak,
        "no room: NAK, nothing lost"
    );
    assert_eq!(
        core.out(0, 3, &[1]),
        Handshake::Silent,
        "an inactive endpoint"
    );
}

#[test]
fn an_in_packet_goes_once_it_is_whole_in_its_fifo() {
    let mut core = configured();
    assert_eq!(d(&mut core, dtxfsts(2)), 16);
    set_d(&mut core, dieptsiz(2), (1 << 19) | 6);
    or_d(&mut core, diepctl(2), EPENA | CNAK);
    let mut got = Vec::new();
    assert_eq!(core.in_token(0, 2, &mut got), Handshake::Nak, "no data yet");
    core.write_fifo(0x2000, u32::from_le_bytes(*b"abcd"), true);
    assert_eq!(d(&mut core, dtxfsts(2)), 15);
    assert_eq!(
        core.in_token(0, 2, &mut got),
        Handshake::Nak,
        "half a packet"
    );
    core.write_fifo(0x2ABC, u32::from_le_bytes(*b"ef\0\0"), true);
    assert_eq!(core.in_token(0, 2, &mut got), Handshake::Ack);
    assert_eq!(got, b"abcdef");
    assert_eq!(d(&mut core, diepctl(2)) & EPENA, 0);
    assert_eq!(d(&mut core, diepint(2)) & 1, 1, "XFRC");
    assert_eq!(d(&mut core, dtxfsts(2)), 16);
    set_d(&mut core, device::Register::FsDiepmsk.index(), 1);
    set_d(&mut core, device::Register::FsDaintmsk.index(), 1 << 2);
    assert_ne!(g(&mut core, global::Register::FsGintsts) & IEPINT, 0);
    set_d(&mut core, diepint(2), 1);
    assert_eq!(g(&mut core, global::Register::FsGintsts) & IEPINT, 0);
    // A zero-length packet needs nothing in the FIFO.
    set_d(&mut core, dieptsiz(2), 1 << 19);
    or_d(&mut core, diepctl(2), EPENA | CNAK);
    got.clear();
    assert_eq!(core.in_token(0, 2, &mut got), Handshake::Ack);
    assert!(got.is_empty());
}

#[test]
fn a_disable_written_back_with_enable_disables() {
    let mut core = configured();
    set_d(&mut core, dieptsiz(2), (1 << 19) | 64);
    set_d(&mut core, diepctl(2), EPENA | CNAK);
    let ctl = d(&mut core, diepctl(2));
    set_d(&mut core, diepctl(2), ctl | EPDIS);
    assert_eq!(d(&mut core, diepctl(2)) & EPENA, 0);
    assert_eq!(d(&mut core, diepint(2)) & 0b10, 0b10, "EPDISD");
    let ctl = d(&mut core, diepctl(2));
    set_d(&mut core, diepctl(2), ctl | EPENA);
    let ctl = d(&mut core, diepctl(2));
    set_d(&mut core, diepctl(2), ctl & !USBAEP);
    assert_eq!(d(&mut core, diepctl(2)) & EPENA, EPENA, "EPENA is set-only");
}

#[test]
fn an_endpoint_armed_while_inactive_is_stranded_by_its_activation() {
    {
        let mut core = configured();
        core.bus_reset();
        set_d(&mut core, dieptsiz(2), (1 << 19) | 64);
        set_d(&mut core, diepctl(2), EPENA | CNAK);
        for _ in 0..16 {
            core.write_fifo(0x2000, 0x5555_5555, true);
        }
        assert_eq!(core.armed_inactive, 1);
        let mut got = Vec::new();
        assert_eq!(core.in_token(0, 2, &mut got), Handshake::Silent, "inactive");
        // The driver's configure: flush every FIFO, then SNAK and USBAEP with write_reg.
        set_g(
            &mut core,
            global::Register::FsGrstctl,
            (1 << 5) | (0x10 << 6),
        );
        set_d(
            &mut core,
            diepctl(2),
            SNAK | USBAEP | (0b10 << 18) | (2 << 22) | 64,
        );
        let ctl = d(&mut core, diepctl(2));
        assert_eq!(ctl & (EPENA | NAKSTS), EPENA | NAKSTS, "{ctl:#x}");
        assert_eq!(core.stranded_on_activation, 1);
        assert_eq!(core.in_token(0, 2, &mut got), Handshake::Nak);
    }
}

#[test]
fn the_address_changes_after_the_status_stage() {
    let mut core = configured();
    set_d(&mut core, device::Register::FsDcfg.index(), (5 << 4) | 0b11);
    set_d(&mut core, diepctl(0), EPENA | CNAK);
    set_d(&mut core, dieptsiz(0), 1 << 19);
    let mut got = Vec::new();
    assert_eq!(
        core.in_token(0, 0, &mut got),
        Handshake::Ack,
        "the status stage at the old address"
    );
    assert_eq!(
        core.setup(0, [0; 8]),
        Handshake::Ack,
        "until a SETUP at the new one"
    );
    assert_eq!(core.setup(5, [0; 8]), Handshake::Ack);
    assert_eq!(core.setup(0, [0; 8]), Handshake::Silent);
}

#[test]
fn unsupported_use_is_counted_by_reason() {
    let mut core = configured();
    set_g(&mut core, global::Register::FsGusbcfg, 1 << 29);
    core.write_fifo(0x5000, 0, true);
    core.write_fifo(0x5000, 0, true);
    assert_eq!(core.unsupported.values().sum::<u64>(), 3);
    assert_eq!(core.to_tell.len(), 2, "told once per reason");
}

#[test]
fn a_new_host_waits_for_a_pull_up() {
    let otg = OtgFs::default();
    assert!(otg.attached());
    assert!(!otg.configured());
    assert_eq!(otg.host_state(), "waiting for the device");
}

/// The model on the board's bus: the wiring check passes for all five slots, registers and the
/// FIFO window answer at their addresses, and line 67 follows GINTSTS & GINTMSK & GINT whichever
/// block the access that changes it reaches.
#[test]
fn on_the_bus_every_block_answers_and_line_67_follows() {
    let mut board = VirtualF407::new().expect("the board");
    let mcu = &mut board.mcu;
    mcu.check().expect("every slot carries its model's layout");
    let at = VirtualNanos(1_000);
    let write = |mcu: &mut crate::board::F407, address: u64, value: u64| {
        mcu.write(at, address, Width::W32, value)
            .expect("the write lands");
    };
    write(mcu, 0x4002_3834, 1 << 7); // RCC_AHB2ENR.OTGFSEN
    let read = |mcu: &mut crate::board::F407, address: u64| {
        mcu.read(at, address, Width::W32).expect("the read lands")
    };
    assert_eq!(read(mcu, 0x5000_003C), 0x1200, "CID");
    assert_eq!(read(mcu, 0x5000_0808) & 0x10, 0x10, "DSTS");
    assert_eq!(read(mcu, 0x5000_0E00), 0, "PCGCCTL");
    assert_eq!(read(mcu, 0x5000_0400), 0, "HCFG");
    write(mcu, 0x5000_0028, (16 << 16) | 48); // DIEPTXF0
    write(mcu, 0x5000_1000, 0x1234_5678); // EP0's FIFO
    assert_eq!(read(mcu, 0x5000_0918), 15, "DTXFSTS0");
    mcu.drain_lines();
    write(mcu, 0x5000_0008, 1); // GAHBCFG.GINT
    write(mcu, 0x5000_0018, 1 << 18); // GINTMSK.IEPINT
    write(mcu, 0x5000_081C, 1); // DAINTMSK: IN 0
    assert!(mcu.drain_lines().is_empty(), "nothing pending yet");
    write(mcu, 0x5000_0810, 1); // DIEPMSK.XFRCM
    write(mcu, 0x5000_0834, 1); // DIEPEMPMSK: TXFE of IN 0 (its FIFO is under half full)
    let raised = mcu.drain_lines();
    assert_eq!(raised.len(), 1, "{raised:?}");
    assert_eq!(raised[0].line.index(), 67);
    assert_eq!(raised[0].level, Level::High, "raised from the device block");
    assert!(mcu.otg.interrupt_line());
    write(mcu, 0x5000_0008, 0);
    let lowered = mcu.drain_lines();
    assert_eq!(lowered.len(), 1);
    assert_eq!(lowered[0].level, Level::Low);
    assert!(mcu.otg.unsupported().is_empty());
}
