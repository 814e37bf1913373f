//! The virtual STM32F407 board: rigless's STM32F427 part (the F407's register-compatible
//! superset at the addresses the F407 uses) with a 8 MHz crystal and a 3.3 V supply, and our
//! models bound to the slots rigless leaves unmodelled: TIM7, the DAC, the four OTG FS blocks and
//! the OTG FS FIFO window (0x5000_1000..0x5004_0000, a window the patched part leaves free).
//! The crystal is ours too: rigless's RCC brings `HSERDY` up with nothing fitted, so a crystal
//! that does not start, or stops, is modelled here (see [`F407::crystal_runs`]).

use std::num::{NonZeroU32, NonZeroU64};

use rigless::device::{ErasedDevice, ResetCause};
use rigless::machine::{Board, Target, armv7m};
use rigless::mcu::{Mcu, Operate};
use rigless::soc::stm32f427::Stm32f427;
use rigless::soc::stm32f427::generated::flash::{Register as FlashRegister, sr as flash_sr};
use rigless::soc::stm32f427::generated::rcc::{Register as RccRegister, cir, cr};
use rigless::soc::stm32f427::peripherals::rcc::Apb;
use rigless::soc::{Bus, Window};
use rigless::time::VirtualNanos;

use crate::models::basic_timer::BasicTimer;
use crate::models::dac::Dac;
use crate::models::otg_fs::{OtgBlock, OtgFs};

/// The external crystal, Hz (the Discovery board's).
pub const HSE_HZ: u64 = 8_000_000;
/// The supply rail, mV.
pub const SUPPLY_MV: u32 = 3300;
/// Where the OTG FS FIFOs start (RM0090 34.16: the FIFO of endpoint n at 0x1000 (n + 1)).
pub const OTG_FS_FIFO_BASE: u64 = 0x5000_1000;
/// Bytes of the FIFO window, up to the end of the OTG FS block.
pub const OTG_FS_FIFO_SIZE: u64 = 0x5004_0000 - OTG_FS_FIFO_BASE;
/// The core's interrupt line of OTG FS (RM0090 table 63).
pub const OTG_FS_IRQ: u16 = 67;
/// The line that drives the core's NMI input (rigless-0.4.0.patch: the highest line the
/// emulator numbers); the clock security system raises it (RM0090 6.2.7).
pub const NMI_INPUT: u16 = rigless::emulator::INTERRUPT_LINES - 1;

/// The core's instructions a second out of reset: one a cycle of the 16 MHz HSI, the system
/// clock after any reset (RM0090 6.2.2). The run then follows HCLK as the firmware sets the
/// clock tree up (`run::BoardDriver::follow_the_clock`, through rigless-0.4.0.patch's
/// `Host::set_instruction_rate`).
pub const RESET_INSTRUCTION_RATE: NonZeroU64 =
    NonZeroU64::new(rigless::soc::stm32f427::peripherals::rcc::HSI_HZ).expect("a running clock");

#[derive(Debug, Clone, Copy)]
struct Slots {
    rcc: usize,
    gpioe: usize,
    flash: usize,
    tim7: usize,
    dac: usize,
    otg_global: usize,
    otg_host: usize,
    otg_device: usize,
    otg_pwrclk: usize,
    otg_fifo: usize,
}

/// The MCU: the part and our models, each bound to its slot.
#[derive(Debug)]
pub struct F407 {
    /// rigless's part (its own models: RCC, GPIO, TIM2-5, ADC, IWDG, DWT, flash, ...).
    pub part: Stm32f427,
    /// TIM7, the control tick.
    pub tim7: BasicTimer,
    /// The DAC: the drive's force command (channel 1) and the blower (channel 2).
    pub dac: Dac,
    /// The USB OTG FS core and its virtual host.
    pub otg: OtgFs,
    /// The crystal oscillates: fitted (`hse_hz > 0`) and not stopped ([`F407::stop_crystal`]).
    /// While it does not, the HSE never reads ready, whatever rigless's RCC schedules.
    crystal_runs: bool,
    /// The flash interface never finishes a write (`FLASH_SR.BSY` stays set): a part whose
    /// option bytes cannot be programmed, say.
    pub flash_stuck_busy: bool,
    /// The PLL never locks (`RCC_CR.PLLRDY` and `RCC_CIR.PLLRDYF` stay clear, whatever
    /// rigless's RCC schedules): a part with its VDDA missing, say.
    pub pll_never_locks: bool,
    /// Level changes of PE8 (the tick heartbeat) so far, seen at every access to GPIOE and at
    /// every stop ([`F407::note_heartbeat`]): what the external enable gate's monostable counts,
    /// however fast the pin toggles between two stops.
    pub heartbeat_edges: u64,
    heartbeat_high: bool,
    slots: Slots,
}

impl F407 {
    /// The part out of reset with a `hse_hz` crystal (0: none fitted, or one that does not
    /// start) and the supply attached.
    pub fn new(hse_hz: u64) -> Result<Self, rigless::soc::Error> {
        let mut part = Stm32f427::new()?;
        part.rcc.attach_crystals(hse_hz, 0);
        part.set_supply(SUPPLY_MV);
        for adc in &mut part.adc {
            adc.set_reference(SUPPLY_MV);
        }
        let size = NonZeroU64::new(OTG_FS_FIFO_SIZE).expect("non-zero");
        static OTG_FS_LINES: [u16; 1] = [OTG_FS_IRQ];
        let otg_fifo = part.bus_mut().add_window(
            Window::new("OTG_FS_FIFO", OTG_FS_FIFO_BASE, size).raising(&OTG_FS_LINES),
        )?;
        let bus = part.bus();
        let slots = Slots {
            rcc: bus.slot("RCC")?,
            gpioe: bus.slot("GPIOE")?,
            flash: bus.slot("FLASH")?,
            tim7: bus.slot("TIM7")?,
            dac: bus.slot("DAC")?,
            otg_global: bus.slot("OTG_FS_GLOBAL")?,
            otg_host: bus.slot("OTG_FS_HOST")?,
            otg_device: bus.slot("OTG_FS_DEVICE")?,
            otg_pwrclk: bus.slot("OTG_FS_PWRCLK")?,
            otg_fifo,
        };
        Ok(Self {
            part,
            tim7: BasicTimer::default(),
            dac: Dac::default(),
            otg: OtgFs::default(),
            crystal_runs: hse_hz > 0,
            flash_stuck_busy: false,
            pll_never_locks: false,
            heartbeat_edges: 0,
            heartbeat_high: false,
            slots,
        })
    }

    /// Counts a change of PE8's level since the last look (see [`F407::heartbeat_edges`]).
    pub fn note_heartbeat(&mut self) {
        let high = crate::pins::high(&mut self.part, crate::pins::PORT_E, 8);
        if high != self.heartbeat_high {
            self.heartbeat_high = high;
            self.heartbeat_edges += 1;
        }
    }

    /// Whether the crystal oscillates.
    pub fn crystal_runs(&self) -> bool {
        self.crystal_runs
    }

    /// The crystal stops at `at` (a cracked crystal, a load capacitor come loose) and stays
    /// stopped through resets. With the clock security system on (`CSSON`) the part notices:
    /// rigless's RCC switches the system to the HSI, stops the PLL and sets `CSSF` (RM0090
    /// 6.2.7); the NMI that follows is the caller's to raise (it belongs to the core). Returns
    /// whether the part noticed, i.e. whether the NMI is due.
    pub fn stop_crystal(&mut self, at: VirtualNanos) -> bool {
        self.crystal_runs = false;
        let noticed = self.part.drive_clocks(at, |rcc, registers, context| {
            rcc.fail_hse(registers, context);
            cir::CSSF.is_set(registers.get(RccRegister::Cir))
        });
        // No frequency from the pin from now on either: a PLL set up on it gets no clock.
        // (The tick timer's clock, the core's rate and its NMI input follow at once:
        // `core_clock::CoreClock::follow`, which the run calls right after.)
        self.part.rcc.attach_crystals(0, 0);
        noticed
    }

    /// TIM7's input clock from the clock tree as it is now (RM0090 6.2: APB1's timer clock):
    /// before every access to TIM7, and after every access that may change the clock and at
    /// every stop (`core_clock::CoreClock::follow`).
    pub fn clock_the_tick_timer(&mut self) {
        let (rcc, regs) = self.part.clocks();
        self.tim7.clock_hz = rcc.timer_clock(regs, Apb::One);
    }

    /// Whether the system clock comes from the crystal: `SWS` on the HSE, or on the PLL with
    /// the HSE as its source (RM0090 6.3.2-6.3.3).
    pub fn system_clock_from_the_crystal(&mut self) -> bool {
        let (_, registers) = self.part.clocks();
        let sws = (registers.get(RccRegister::Cfgr) >> 2) & 0b11;
        let pll_on_hse = registers.get(RccRegister::Pllcfgr) & (1 << 22) != 0;
        sws == 0b01 || (sws == 0b10 && pll_on_hse)
    }

    /// A stopped or missing crystal is never ready: cleared before every access to the RCC,
    /// so the firmware never reads the `HSERDY` (and `HSERDYF`) rigless's model raises at its
    /// start-up time regardless.
    fn hold_the_crystal_down(&mut self) {
        let (_, registers) = self.part.clocks();
        let cr_value = registers.get(RccRegister::Cr);
        registers.set(RccRegister::Cr, cr::HSERDY.set(cr_value, 0));
        let cir_value = registers.get(RccRegister::Cir);
        registers.set(RccRegister::Cir, cir::HSERDYF.set(cir_value, 0));
    }
}

impl Mcu for F407 {
    fn bus(&self) -> &Bus {
        self.part.bus()
    }
    fn bus_mut(&mut self) -> &mut Bus {
        self.part.bus_mut()
    }
    fn reset(&mut self, at: VirtualNanos, cause: ResetCause) {
        self.part.reset(at, cause);
        rigless::device::Device::reset(&mut self.tim7);
        rigless::device::Device::reset(&mut self.dac);
        self.otg.reset();
    }
    fn poll(&mut self, now: VirtualNanos) {
        self.part.poll(now);
    }
    fn split(&mut self, slot: usize) -> (&mut Bus, Option<&mut dyn ErasedDevice>) {
        let s = self.slots;
        if slot == s.gpioe {
            // Before every access: the level the previous access left.
            self.note_heartbeat();
        }
        if slot == s.rcc && !self.crystal_runs {
            self.hold_the_crystal_down();
        }
        if slot == s.rcc && self.pll_never_locks {
            let (_, registers) = self.part.clocks();
            let cr_value = registers.get(RccRegister::Cr);
            registers.set(RccRegister::Cr, cr::PLLRDY.set(cr_value, 0));
            let cir_value = registers.get(RccRegister::Cir);
            registers.set(RccRegister::Cir, cir::PLLRDYF.set(cir_value, 0));
        }
        if slot == s.flash && self.flash_stuck_busy {
            let (_, registers) = self.part.program();
            let sr = registers.get(FlashRegister::Sr);
            registers.set(FlashRegister::Sr, flash_sr::BSY.set(sr, 1));
        }
        let block = if slot == s.tim7 {
            self.clock_the_tick_timer();
            return (self.part.bus_mut(), Some(&mut self.tim7));
        } else if slot == s.dac {
            self.dac.tick_ns = self.tim7.last_update_ns;
            self.dac.tim7_trgo_ns = self.tim7.last_trgo_ns;
            return (self.part.bus_mut(), Some(&mut self.dac));
        } else if slot == s.otg_global {
            OtgBlock::Global
        } else if slot == s.otg_host {
            OtgBlock::Host
        } else if slot == s.otg_device {
            OtgBlock::Device
        } else if slot == s.otg_pwrclk {
            OtgBlock::PowerClock
        } else if slot == s.otg_fifo {
            OtgBlock::Fifo
        } else {
            return self.part.split(slot);
        };
        if self.otg.block(block).is_none() {
            // A block the USB model leaves to the part (rigless's own partial, or none).
            return self.part.split(slot);
        }
        (self.part.bus_mut(), self.otg.block(block))
    }
}

/// The board: one target, the F407.
#[derive(Debug)]
pub struct VirtualF407 {
    /// The MCU.
    pub mcu: F407,
}

impl rigless::snapshot::Store for VirtualF407 {}

impl VirtualF407 {
    /// A board with its 8 MHz crystal and nothing wired to its pins yet.
    pub fn new() -> Result<Self, rigless::soc::Error> {
        Self::with_crystal(HSE_HZ)
    }

    /// A board with a `hse_hz` crystal (0: none that starts).
    pub fn with_crystal(hse_hz: u64) -> Result<Self, rigless::soc::Error> {
        Ok(Self {
            mcu: F407::new(hse_hz)?,
        })
    }
}

impl Board for VirtualF407 {
    fn name(&self) -> &'static str {
        "virtual-f407"
    }
    fn target_names(&self) -> Vec<&'static str> {
        vec!["stm32f407"]
    }
    fn mcu(&mut self, target: usize) -> Option<&mut dyn Mcu> {
        (target == 0).then_some(&mut self.mcu)
    }
    fn targets(&mut self) -> Vec<Target<'_>> {
        let core = armv7m::Core {
            variant: armv7m::Variant::M4,
            clock_hz: NonZeroU64::new(168_000_000).expect("non-zero"),
            interrupt_lines: NonZeroU32::new(u32::from(self.mcu.cpu().interrupt_lines))
                .expect("lines"),
            priority_bits: 4,
            refclk_divider: NonZeroU32::new(8).expect("non-zero"),
            instructions_per_second: RESET_INSTRUCTION_RATE,
            boot: "flash",
        }
        .spec_with_parts(
            &rigless::cpu::armv7m::windows(self.mcu.bus()),
            armv7m::Fpu::FpV4Sp,
            armv7m::MpuRegions::Eight,
        );
        vec![Target::new("stm32f407", &mut self.mcu, core)]
    }
}
