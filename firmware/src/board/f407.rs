//! The reference rig board: STM32F407VG (STM32F4-Discovery class), Cortex-M4F at 168 MHz from
//! the external 8 MHz crystal. Every pin and peripheral the firmware uses is assigned here (the
//! README's wiring table mirrors this module).
//!
//! | signal | pin / peripheral | notes |
//! |---|---|---|
//! | encoder A / B | PA15 / PB3, TIM2 CH1 / CH2 (AF1) | 32-bit quadrature counter, x4 decoding, input filter f_CK_INT N = 8 ([`ENCODER_FILTER`]) |
//! | force command | PA4, DAC channel 1 | 12-bit, 0..3.3 V, mid-point = zero force ([`crate::drive`]) |
//! | drive enable | PE7, push-pull, active high | low on reset (fit a pull-down), on any fault, panic, HardFault |
//! | tick heartbeat | PE8, push-pull | toggled by every control tick (half the tick rate): retriggers the external enable gate |
//! | camera trigger | PE9, push-pull, active high | raised in the tick that starts a frame, for the jump configuration's `camera_pulse_ticks` (default 10 ticks = 1 ms) |
//! | motor current sense | PA1, ADC1 channel 1 | ADC clock PCLK2/4 = 21 MHz (limit 36 MHz); sampled at the end of each tick, read by the next |
//! | USB host link | PA11 (D-) / PA12 (D+), OTG_FS | CDC-ACM full speed |
//! | status LEDs | PD12 green (running), PD14 red (fault) | the Discovery board's LEDs |
//! | blower flow command | PA5, DAC channel 2 | 12-bit, 0..3.3 V for 0..10 V through a x3.03 stage like the drive's ([`blower_code`]); PA5 also reaches the Discovery's LIS3DSH SCK: its chip select PE3 is held high |
//! | shaker motor | PC6, TIM3 CH1 (AF2) | PWM at [`SHAKER_PWM_HZ`], duty = the core's shaker duty |
//! | lift motor enable / direction | PE10 / PE11, push-pull | enable active high (low on reset, fit a pull-down); direction high = up |
//! | lift limit switches up / down | PE12 / PE13, inputs with pull-up | switch closes to ground at its limit (low = at the limit) |
//! | emergency stop | PE14, input with pull-up, on its own connector (PE14, GND) | normally-closed contact to ground: pressed, **a broken wire or nothing plugged in** reads high = open. Reported to the core every tick whatever PE15 says ([`RigIo::emergency_stop_open`]): `Arm` is refused until the loop has read closed since reset, and it opening after that latches the emergency stop. With no stop fitted, a jumper plug on its connector closes the loop |
//! | bed apparatus present | PE15, input with pull-up | the apparatus's harness ties it to ground: until it has read low once since reset the apparatus is absent (its inputs are not reported and nothing of it can be switched on); once seen, losing PE15 reads as a stop (a harness pulled out is a stop) |
//! | bed height sensor | PA2, ADC2 channel 2 | the laser distance sensor's 0..3.3 V output, raw 12-bit code to the host (sampled at the end of each tick) |
//! | control tick | TIM7 update interrupt | highest priority, [`TICK_HZ`] |
//! | watchdog | IWDG, [`WATCHDOG_MS`] | fed by the control tick; keeps counting while the core is halted by a debugger |

use stm32f4xx_hal::{
    adc::{
        Adc,
        config::{AdcConfig, Clock, SampleTime, Sequence},
    },
    dac::{C1, C2, DacExt, DacOut, DacPin},
    gpio::{
        Analog, Input, Output, PA1, PA2, PD12, PD14, PE3, PE7, PE8, PE9, PE10, PE11, PE12, PE13,
        PE14, PE15, PushPull,
    },
    pac,
    prelude::*,
    qei::Qei,
    rcc::{Config, Rcc},
    timer::{CounterHz, Event, Flag, PwmChannel},
    watchdog::IndependentWatchdog,
};

use crate::drive;
use crate::reset_flags;
use sandjumper_core::ResetCause;
use sandjumper_core::bed::{BLOWER_MAX_V, BedInputs, BedOutputs};

/// Shaker PWM frequency, Hz (above hearing, within a motor driver's usual range).
pub const SHAKER_PWM_HZ: u32 = 20_000;

/// The DAC code of a blower command, V (0..10 V over the full 12-bit scale).
pub fn blower_code(volts: f32) -> u16 {
    let v = if volts.is_finite() {
        volts.clamp(0.0, BLOWER_MAX_V)
    } else {
        0.0
    };
    (v / BLOWER_MAX_V * 4095.0 + 0.5) as u16
}

/// External crystal, Hz.
pub const HSE_HZ: u32 = 8_000_000;
/// Core clock, Hz (PLL from the crystal; 48 MHz for USB also from the PLL).
pub const SYSCLK_HZ: u32 = 168_000_000;
/// Control tick rate, Hz: 10 kHz, or `SANDJUMPER_TICK_HZ` at build time (the core accepts
/// 1,000..=100,000; TIM7 at 84 MHz makes any rate that divides it exactly).
pub const TICK_HZ: u32 = match option_env!("SANDJUMPER_TICK_HZ") {
    Some(text) => parse_hz(text),
    None => 10_000,
};

/// Decimal digits to Hz at compile time; anything else stops the build with a message.
const fn parse_hz(text: &str) -> u32 {
    let bytes = text.as_bytes();
    assert!(
        !bytes.is_empty(),
        "SANDJUMPER_TICK_HZ is empty: give the tick rate in Hz, e.g. 10000"
    );
    let mut hz: u32 = 0;
    let mut i = 0;
    while i < bytes.len() {
        let digit = bytes[i];
        assert!(
            digit.is_ascii_digit(),
            "SANDJUMPER_TICK_HZ must be decimal digits (Hz), e.g. 10000"
        );
        hz = match hz.checked_mul(10) {
            Some(v) => v + (digit - b'0') as u32,
            None => panic!("SANDJUMPER_TICK_HZ is too large"),
        };
        i += 1;
    }
    assert!(
        hz >= 1_000 && hz <= 100_000,
        "SANDJUMPER_TICK_HZ must be 1000..=100000 Hz"
    );
    hz
}
/// Cycle budget of one control tick before it counts as an overrun: 80 % of the period, so the
/// lower-priority link and telemetry always get at least a fifth of the CPU.
pub const TICK_BUDGET_CYCLES: u32 = SYSCLK_HZ / TICK_HZ * 8 / 10;
/// Independent watchdog timeout, ms (nominal): prescaler /64 and reload 4 at the LSI's
/// 17-47 kHz make it 6.8-18.8 ms, 68-188 missed ticks, before the chip resets (drive enable drops).
pub const WATCHDOG_MS: u32 = 10;

/// Drive enable: GPIOE pin 7.
pub const DRIVE_ENABLE_PIN: u32 = 7;
/// Lift motor enable: GPIOE pin 10.
pub const LIFT_ENABLE_PIN: u32 = 10;
/// The GPIOE BSRR word that drives both enables (drive, lift) low in one write.
pub const ENABLES_OFF: u32 = (1 << (16 + DRIVE_ENABLE_PIN)) | (1 << (16 + LIFT_ENABLE_PIN));
/// The DAC's channel-2 12-bit right-aligned data register (the blower's flow command).
pub const DAC_DHR12R2: u32 = 0x4000_7400 + 0x14;
/// TIM3's capture/compare register 1 (the shaker's PWM duty, RM0090 18.4.13).
pub const TIM3_CCR1: u32 = 0x4000_0400 + 0x34;
/// GPIOE's bit set/reset register (RM0090 8.4.7), for writes that need no HAL state.
pub const GPIOE_BSRR: u32 = 0x4002_1000 + 0x18;
/// The DAC's channel-1 12-bit right-aligned data register (RM0090 14.5.3).
pub const DAC_DHR12R1: u32 = 0x4000_7400 + 0x08;
/// One control period in core cycles (tick-gap detection).
pub const TICK_PERIOD_CYCLES: u32 = SYSCLK_HZ / TICK_HZ;
/// TIM2's input filter on both encoder channels (CCMR1 IC1F = IC2F = 0b0011: sampled at
/// f_CK_INT = 84 MHz, 8 samples must agree): an edge shorter than ~95 ns is rejected (noise
/// on long encoder cables), while the rig's fastest edges (1 um counts at ~2 m/s, x4
/// decoding) are 500 ns apart.
pub const ENCODER_FILTER: u8 = 0b0011;

/// Why the chip last reset (RCC_CSR's flags), then clear the flags so the next reset reads
/// its own. Call before the clock tree is set up.
pub fn take_reset_cause() -> ResetCause {
    // SAFETY: a read and a write of RCC_CSR before the HAL owns the RCC; RMVF only clears the
    // reset flags.
    unsafe {
        let rcc = &*pac::RCC::ptr();
        let csr = rcc.csr().read().bits();
        rcc.csr().modify(|_, w| w.rmvf().clear());
        reset_flags::reset_cause(csr)
    }
}

/// The whole safe state with raw register writes, usable from the panic, HardFault and default
/// handlers whatever state the HAL objects are in: drive and lift enables low (one write), the
/// drive's DAC at the zero-force code, the blower's DAC at 0 V, the shaker's PWM duty at zero.
pub fn force_safe_state() {
    // SAFETY: single writes to the GPIOE bit set/reset register, the two DAC data registers and
    // TIM3's compare register 1; each touches only the rig's own pin or channel, and the handlers
    // that call this never return to the code that owns those peripherals.
    unsafe {
        let gpioe = &*pac::GPIOE::ptr();
        gpioe.bsrr().write(|w| w.bits(ENABLES_OFF));
        let dac = &*pac::DAC::ptr();
        dac.dhr12r1()
            .write(|w| w.daccdhr().bits(drive::ZERO_FORCE_CODE));
        dac.dhr12r2().write(|w| w.daccdhr().bits(0));
        (*pac::TIM3::ptr()).ccr1().write(|w| w.bits(0));
    }
}

/// ADC2 converting channel 2 (PA2, the bed-height sensor) once per software start. The HAL
/// only constructs ADC1 (its calibration reads ADC1's internal reference), so ADC2 is set up
/// here on its registers; the ADC clock prescaler (PCLK2/4) is ADC1's common setting.
pub struct BedHeightAdc {
    adc: pac::ADC2,
}

impl BedHeightAdc {
    /// Clock on, channel 2 alone in the regular sequence, 84-cycle sampling, on, first
    /// conversion started. Call after ADC1's setup (which sets the common prescaler).
    fn init(adc: pac::ADC2) -> Self {
        // SAFETY: one read-modify-write of RCC's APB2 enable register, setting only ADC2's
        // clock bit; nothing else touches ADC2's bit.
        unsafe {
            (*pac::RCC::ptr())
                .apb2enr()
                .modify(|_, w| w.adc2en().set_bit());
        }
        // RM0090 6.3.x / ES0206 2.1.13: an access right after enabling a peripheral's clock may
        // not see it enabled; the data barrier completes the enable first.
        cortex_m::asm::dsb();
        adc.smpr2().modify(|_, w| w.smp2().cycles84());
        // SAFETY: 2 is a valid channel number for SQ1 (0..=18).
        adc.sqr3().write(|w| unsafe { w.sq1().bits(2) });
        adc.sqr1().write(|w| w.l().set(0));
        adc.cr2().modify(|_, w| w.adon().set_bit());
        let s = Self { adc };
        s.start();
        s
    }

    /// Start a conversion (done long before the next tick).
    #[inline(always)]
    fn start(&self) {
        self.adc.cr2().modify(|_, w| w.swstart().set_bit());
    }

    /// The last conversion's 12-bit code.
    #[inline(always)]
    fn read(&self) -> u16 {
        self.adc.dr().read().data().bits()
    }
}

/// The rig's peripherals, owned by the control tick.
pub struct RigIo {
    encoder: Qei<pac::TIM2>,
    force_dac: C1,
    drive_enable: PE7<Output<PushPull>>,
    camera_trigger: PE9<Output<PushPull>>,
    tick_heartbeat: PE8<Output<PushPull>>,
    current_adc: Adc<pac::ADC1>,
    _current_pin: PA1<Analog>,
    running_led: PD12<Output<PushPull>>,
    fault_led: PD14<Output<PushPull>>,
    blower_dac: C2,
    shaker: PwmChannel<pac::TIM3, 0>,
    lift_enable: PE10<Output<PushPull>>,
    lift_up: PE11<Output<PushPull>>,
    lift_up_limit: PE12<Input>,
    lift_down_limit: PE13<Input>,
    emergency_stop: PE14<Input>,
    bed_present: PE15<Input>,
    bed_seen: bool,
    height_adc: BedHeightAdc,
    _height_pin: PA2<Analog>,
    _mems_cs: PE3<Output<PushPull>>,
    tick_timer: CounterHz<pac::TIM7>,
    watchdog: IndependentWatchdog,
}

/// Everything `init` hands on besides the rig: the USB peripheral for the host link.
pub struct Parts {
    pub io: RigIo,
    pub usb: stm32f4xx_hal::otg_fs::USB,
}

/// How long the start-up waits for the crystal, in core cycles: 0.1 s at the 16 MHz HSI the
/// part runs on then, 50-100 times an 8 MHz crystal's usual start-up (1-2 ms), and inside the
/// watchdog's shortest first window (0.35 s at the fastest LSI), so the report comes before the
/// watchdog's reset would. Counted by the DWT's cycle counter, not by loop turns: a turn's
/// cost depends on the flash wait states, the prefetch and the compiler's unrolling.
pub const HSE_STARTUP_CYCLES: u32 = 1_600_000;

/// How long the start-up waits for the PLL to lock, in core cycles: 0.02 s at the 16 MHz HSI,
/// about 100 times its lock time (DS8626 t_LOCK: 50-100 us), inside the early watchdog's
/// shortest window.
pub const PLL_LOCK_CYCLES: u32 = 320_000;

/// The PLL's configuration for 168 MHz and 48 MHz from the 8 MHz crystal (RM0090 6.3.2): source
/// HSE (bit 22), M = 4 (2 MHz at the VCO's input), N = 168 (336 MHz VCO), P = 2 (bits 17:16 =
/// 0), Q = 7 (48 MHz for USB).
pub const PLLCFGR_168_48: u32 = 4 | (168 << 6) | (1 << 22) | (7 << 24);

/// `RCC_PLLCFGR`'s fields (PLLM, PLLN, PLLP, PLLSRC, PLLQ); the other bits are reserved and
/// keep their reset value (bit 29 is set out of reset).
const PLLCFGR_FIELDS: u32 = 0x0F43_7FFF;

/// How long the start-up waits for an option-byte write, in core cycles: 0.2 s at the 16 MHz
/// HSI, 12 times the write's ~16 ms, inside the watchdog's shortest first window (0.35 s).
pub const OPTION_WRITE_CYCLES: u32 = 3_200_000;

/// Waits until `ready` or `cycles` core cycles have passed (the DWT's cycle counter, started
/// here if it is not running); whether `ready` came.
fn wait_for(cycles: u32, mut ready: impl FnMut() -> bool) -> bool {
    // SAFETY: DEMCR's TRCENA and DWT_CTRL's CYCCNTENA set (read-modify-write): they only let
    // the cycle counter run, which the tick's timing also reads.
    unsafe {
        let dcb = &*cortex_m::peripheral::DCB::PTR;
        dcb.demcr.modify(|r| r | (1 << 24));
        let dwt = &*cortex_m::peripheral::DWT::PTR;
        dwt.ctrl.modify(|r| r | 1);
    }
    let start = cortex_m::peripheral::DWT::cycle_count();
    loop {
        if ready() {
            return true;
        }
        if cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start) >= cycles {
            return false;
        }
    }
}

/// Starts the crystal oscillator and waits for it with a bound. The HAL's clock setup waits for
/// HSE and PLL ready with none: a board whose crystal does not start would hang there forever,
/// before the watchdog runs. Returns false if the crystal did not start.
fn start_crystal() -> bool {
    // SAFETY: RCC_CR's HSEON set and HSERDY read before the HAL owns the RCC; the HAL's freeze
    // sets HSEON again and finds the oscillator ready (and the PLL, [`pll_locks`], proven).
    unsafe {
        let rcc = &*pac::RCC::ptr();
        rcc.cr().modify(|_, w| w.hseon().set_bit());
        wait_for(HSE_STARTUP_CYCLES, || rcc.cr().read().hserdy().bit_is_set())
    }
}

/// A start-up that cannot go on (no crystal, no PLL): the whole safe state, and the red LED
/// (PD14) lit so that a board with no probe attached shows it, before the report (a panic; the
/// watchdog then restarts the chip, which fails again and lights it again).
fn startup_failed() {
    force_safe_state();
    // SAFETY: RCC_AHB1ENR's GPIODEN set (read-modify-write), then PD14 made a push-pull output
    // and set high through GPIOD's MODER and BSRR, before the HAL owns either.
    unsafe {
        (*pac::RCC::ptr())
            .ahb1enr()
            .modify(|_, w| w.gpioden().set_bit());
        cortex_m::asm::dsb();
        let gpiod = &*pac::GPIOD::ptr();
        gpiod
            .moder()
            .modify(|r, w| w.bits((r.bits() & !(0b11 << 28)) | (0b01 << 28)));
        gpiod.bsrr().write(|w| w.bits(1 << 14));
    }
}

/// Locks the PLL once on the running crystal with a bound, then switches it off again: the
/// HAL's clock setup, which configures it (`PLLCFGR` may be written only with the PLL off) and
/// waits for the lock with no bound, then finds a PLL known to lock. Returns false if it did not
/// lock, or did not stop after (the HAL must not write `PLLCFGR` with it on). The HAL's own
/// second lock and its switch of SYSCLK to the PLL stay bounded by the early watchdog alone.
fn pll_locks() -> bool {
    // SAFETY: RCC_PLLCFGR written with the PLL off, RCC_CR's PLLON set and cleared, PLLRDY read,
    // before the HAL owns the RCC; the system clock still runs on the HSI throughout.
    unsafe {
        let rcc = &*pac::RCC::ptr();
        rcc.pllcfgr()
            .modify(|r, w| w.bits((r.bits() & !PLLCFGR_FIELDS) | PLLCFGR_168_48));
        rcc.cr().modify(|_, w| w.pllon().set_bit());
        let locked = wait_for(PLL_LOCK_CYCLES, || rcc.cr().read().pllrdy().bit_is_set());
        rcc.cr().modify(|_, w| w.pllon().clear_bit());
        // PLLRDY falls within a few cycles of the VCO's stop; bounded all the same.
        let stopped = wait_for(PLL_LOCK_CYCLES, || rcc.cr().read().pllrdy().bit_is_clear());
        locked && stopped
    }
}

/// The chip's 96-bit unique ID (RM0090 39.1) as 24 hex digits: the USB serial number, so two
/// boards on one host are told apart.
pub fn serial_number(buf: &'static mut [u8; 24]) -> &'static str {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    for word in 0..3 {
        // SAFETY: the unique ID's three words, read-only system memory on every STM32F4.
        let w = unsafe { core::ptr::read_volatile((0x1FFF_7A10 + 4 * word) as *const u32) };
        for nibble in 0..8 {
            buf[word * 8 + nibble] = HEX[((w >> (28 - 4 * nibble)) & 0xF) as usize];
        }
    }
    // Only ASCII hex digits were written.
    core::str::from_utf8(buf).unwrap_or("F407")
}

/// Flash wait states at 168 MHz (RM0090 table 12): 7, which holds for any supply down to 2.1 V,
/// where the HAL's 5 need at least 2.7 V. A Discovery board runs at about 3.0 V, too close to
/// the 2.8 V brown-out level 3 for comfort, so the board uses level 2 (about 2.5 V falling)
/// and the wait states that level allows.
pub const FLASH_WAIT_STATES: u32 = 7;

/// The brown-out reset at level 2 in the option bytes (RM0090 3.9.10, `BOR_LEV` = 0b01; the
/// part leaves the factory with it off, 0b11, where only the ~1.7 V power-down reset acts): a
/// sagging supply holds the part in reset instead of running its flash out of specification.
/// Programmed only where the option bytes say BOR off (the factory's 0b11): a level set on
/// purpose is left alone. Programmed once (the option bytes keep it); a no-op afterwards.
fn ensure_brown_out_reset() {
    const BOR_LEVEL_2: u32 = 0b01;
    const BOR_OFF: u32 = 0b11;
    // SAFETY: the flash interface's option registers, before anything else uses the flash
    // interface's registers; the unlock keys are RM0090 3.7.2's.
    unsafe {
        let flash = &*pac::FLASH::ptr();
        let optcr = flash.optcr().read().bits();
        if (optcr >> 2) & 0b11 != BOR_OFF {
            return;
        }
        flash.optkeyr().write(|w| w.bits(0x0819_2A3B));
        flash.optkeyr().write(|w| w.bits(0x4C5D_6E7F));
        flash
            .optcr()
            .modify(|r, w| w.bits((r.bits() & !(0b11 << 2)) | (BOR_LEVEL_2 << 2)));
        flash.optcr().modify(|r, w| w.bits(r.bits() | 0b10)); // OPTSTRT
        // Bounded inside the early watchdog's shortest window: a write that never ends is
        // reported instead of reset silently over and over.
        let written = wait_for(OPTION_WRITE_CYCLES, || {
            flash.sr().read().bsy().bit_is_clear()
        });
        flash.optcr().modify(|r, w| w.bits(r.bits() | 0b01)); // OPTLOCK
        // OPERR, WRPERR, PGAERR, PGPERR, PGSERR (RM0090 3.9.5): the level did not take.
        let errors = flash.sr().read().bits() & 0xF2;
        if errors != 0 || !written {
            defmt::warn!(
                "option bytes: the brown-out level was not programmed (FLASH_SR {=u32:#x}); the board runs with BOR off",
                errors
            );
        }
    }
}

/// The brown-out reset level in the option bytes (RM0090 3.9.10): 3, 2, 1, or 0 for off.
pub fn brown_out_level() -> u8 {
    // SAFETY: a read of FLASH_OPTCR.
    let optcr = unsafe { (*pac::FLASH::ptr()).optcr().read().bits() };
    match (optcr >> 2) & 0b11 {
        0b00 => 3,
        0b01 => 2,
        0b10 => 1,
        _ => 0,
    }
}

/// Refresh the watchdog while `init` runs at its reset settings (IWDG_KR's reload key).
fn feed_early_watchdog() {
    // SAFETY: IWDG_KR's reload key; `init` owns the IWDG until it hands it to `RigIo`.
    unsafe {
        (*pac::IWDG::ptr()).kr().write(|w| w.key().bits(0xAAAA));
    }
}

/// Clocks, pins and peripherals. The drive stays disabled at zero force; the tick timer is
/// configured but not started ([`Rig::start_ticking`]). A crystal that does not start ends
/// here in the safe state with a report (a panic): the board cannot keep time without it.
pub fn init(dp: pac::Peripherals) -> Parts {
    // The watchdog first, at its reset settings (prescaler /4, reload 0xFFF: 0.35-0.96 s over
    // the LSI's 17-47 kHz): a hang anywhere in the start-up (the HAL's own waits have no
    // bound; the crystal's and the PLL's are proven first with one) resets the chip instead of holding it, and the reset cause says so. The 10 ms
    // setting replaces it at the end of `init`.
    // SAFETY: IWDG_KR's start key; nothing else owns the IWDG yet.
    unsafe {
        (*pac::IWDG::ptr()).kr().write(|w| w.key().bits(0xCCCC));
    }
    ensure_brown_out_reset();
    // Each bounded wait of the start-up fits the early watchdog's shortest window by itself:
    // refreshed between them, they never add up to a reset before their report.
    feed_early_watchdog();
    // More wait states before the clock rises (RM0090 3.5.1: raise LATENCY first).
    // SAFETY: FLASH_ACR's LATENCY, read back as the manual asks before the clock changes.
    unsafe {
        let acr = (*pac::FLASH::ptr()).acr();
        acr.modify(|_, w| w.latency().bits(FLASH_WAIT_STATES as u8));
        while u32::from(acr.read().latency().bits()) != FLASH_WAIT_STATES {}
    }
    let crystal_started = start_crystal();
    feed_early_watchdog();
    if !crystal_started {
        startup_failed();
        defmt::panic!("the 8 MHz crystal (HSE) did not start: check X2 and its load capacitors");
    }
    let pll_locked = pll_locks();
    feed_early_watchdog();
    if !pll_locked {
        startup_failed();
        defmt::panic!(
            "the PLL did not lock on the 8 MHz crystal within 20 ms (or did not stop after): check the supply (VDDA) and the crystal"
        );
    }
    let mut rcc: Rcc = dp.RCC.freeze(
        Config::hse(HSE_HZ.Hz())
            .sysclk(SYSCLK_HZ.Hz())
            .require_pll48clk(),
    );
    // The HAL's freeze sets the 5 wait states that hold from 2.7 V up: back to ours.
    // SAFETY: FLASH_ACR's LATENCY; more wait states are always safe at a given clock.
    unsafe {
        (*pac::FLASH::ptr())
            .acr()
            .modify(|_, w| w.latency().bits(FLASH_WAIT_STATES as u8));
    }
    // Clock security system: if the crystal stops, the part switches to HSI and raises the NMI,
    // whose handler (`NonMaskableInt`, fault_f407.rs) puts the rig in the safe state.
    // SAFETY: RCC_CR's CSSON, set once the HAL has switched SYSCLK to the PLL on HSE.
    unsafe {
        (*pac::RCC::ptr()).cr().modify(|_, w| w.csson().set_bit());
    }
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let gpiod = dp.GPIOD.split(&mut rcc);
    let gpioe = dp.GPIOE.split(&mut rcc);

    // Safe outputs first: drive disabled, zero force.
    let drive_enable = gpioe
        .pe7
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
    let (mut force_dac, mut blower_dac) = dp
        .DAC
        .constrain((gpioa.pa4.into_analog(), gpioa.pa5.into_analog()), &mut rcc);
    // Output buffers off (BOFF1, BOFF2): buffered, the DAC is linear only from 0.2 V to
    // VDDA - 0.2 V (DS8626 table 70), which would cut the force range to about +-260 N unseen
    // and leave the blower at 0.6 V when off. Unbuffered, the output (up to 15 kOhm) needs a
    // load of 1.5 MOhm or more: the drive's and the blower's stages are fed through unity-gain
    // followers (docs/firmware.md, wiring).
    // SAFETY: a read-modify-write of DAC_CR's two BOFF bits before either channel is enabled.
    unsafe {
        (*pac::DAC::ptr())
            .cr()
            .modify(|_, w| w.boff1().set_bit().boff2().set_bit());
    }
    force_dac.set_value(drive::ZERO_FORCE_CODE);
    force_dac.enable();
    // The bed apparatus: everything off.
    blower_dac.set_value(0);
    blower_dac.enable();
    let lift_enable = gpioe
        .pe10
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
    let lift_up = gpioe
        .pe11
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
    let mems_cs = gpioe
        .pe3
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::High);
    let gpioc = dp.GPIOC.split(&mut rcc);
    let (_, (shaker_ch, ..)) = dp.TIM3.pwm_hz(SHAKER_PWM_HZ.Hz(), &mut rcc);
    let mut shaker = shaker_ch.with(gpioc.pc6);
    shaker.set_duty(0);
    shaker.enable();
    // Toggled by every control tick: a retriggerable monostable on this line gates the drive's
    // enable, so a halted or locked-up core drops the drive within the monostable's period.
    let tick_heartbeat = gpioe
        .pe8
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
    let camera_trigger = gpioe
        .pe9
        .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);

    // PA15/PB3 leave reset as JTAG pins (AF0); SWD debugging does not need them. PB3 is also
    // SWO: no trace output on this board. Pull-ups: an unplugged encoder holds its count
    // instead of counting noise on floating inputs.
    let encoder = Qei::new(
        dp.TIM2,
        (
            gpioa.pa15.into_pull_up_input(),
            gpiob.pb3.into_pull_up_input(),
        ),
        &mut rcc,
    );
    // SAFETY: CCMR1's input-filter fields of TIM2, which the encoder owns; counting goes on.
    unsafe {
        (*pac::TIM2::ptr())
            .ccmr1_input()
            .modify(|_, w| w.ic1f().bits(ENCODER_FILTER).ic2f().bits(ENCODER_FILTER));
    }

    let current_pin = gpioa.pa1.into_analog();
    // PCLK2 is 84 MHz: /4 gives 21 MHz, within the ADC's 36 MHz limit (/2 would be 42).
    let mut current_adc = Adc::new(
        dp.ADC1,
        true,
        AdcConfig::default().clock(Clock::Pclk2_div_4),
        &mut rcc,
    );
    current_adc.configure_channel(&current_pin, Sequence::One, SampleTime::Cycles_84);
    current_adc.enable();
    current_adc.start_conversion();

    let height_pin = gpioa.pa2.into_analog();
    let height_adc = BedHeightAdc::init(dp.ADC2);

    let mut tick_timer = dp.TIM7.counter_hz(&mut rcc);
    tick_timer.listen(Event::Update);

    let usb = stm32f4xx_hal::otg_fs::USB::new(
        (dp.OTG_FS_GLOBAL, dp.OTG_FS_DEVICE, dp.OTG_FS_PWRCLK),
        (gpioa.pa11, gpioa.pa12),
        &rcc.clocks,
    );

    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    // Not frozen while the core is halted: a breakpoint or a probe halt while Armed must not
    // hold the force (the watchdog resets the chip and the enable line drops).
    watchdog.stop_on_debug(&dp.DBGMCU, false);
    watchdog.start(WATCHDOG_MS.millis());
    // The counter starts from 0xFFF at the new prescaler (~8 s) and takes the new reload only
    // at the first refresh: refresh as soon as the prescaler and reload have reached the LSI
    // domain (PVU, RVU clear: at most 5 LSI periods, ~160 us), so a hang before the first tick
    // resets the chip within one watchdog period.
    // SAFETY: reads of IWDG_SR.
    let iwdg_sr = unsafe { &(*pac::IWDG::ptr()).sr() };
    let mut spins: u32 = 0;
    while iwdg_sr.read().bits() & 0b11 != 0 && spins < SYSCLK_HZ / 1_000 {
        spins += 1;
    }
    watchdog.feed();

    Parts {
        io: RigIo {
            encoder,
            force_dac,
            drive_enable,
            camera_trigger,
            tick_heartbeat,
            current_adc,
            _current_pin: current_pin,
            running_led: gpiod.pd12.into_push_pull_output(),
            fault_led: gpiod.pd14.into_push_pull_output(),
            blower_dac,
            shaker,
            lift_enable,
            lift_up,
            lift_up_limit: gpioe.pe12.into_pull_up_input(),
            lift_down_limit: gpioe.pe13.into_pull_up_input(),
            emergency_stop: gpioe.pe14.into_pull_up_input(),
            bed_present: gpioe.pe15.into_pull_up_input(),
            bed_seen: false,
            height_adc,
            _height_pin: height_pin,
            _mems_cs: mems_cs,
            tick_timer,
            watchdog,
        },
        usb,
    }
}

impl RigIo {
    /// Starts the control tick timer at `tick_hz`.
    pub fn start_ticking(&mut self, tick_hz: u32) {
        // A rate the timer cannot make is a build-time configuration error: stay disabled.
        if self.tick_timer.start(tick_hz.Hz()).is_err() {
            force_safe_state();
        }
    }

    /// Acknowledges the tick interrupt.
    #[inline(always)]
    pub fn acknowledge_tick(&mut self) {
        self.tick_timer.clear_flags(Flag::Update);
    }

    /// The raw 32-bit quadrature count (the core extends it to 64 bits).
    #[inline(always)]
    pub fn encoder_count(&self) -> u32 {
        self.encoder.count()
    }

    /// The current-sense sample started at the end of the previous tick (raw 12-bit code).
    #[inline(always)]
    pub fn current_sense_code(&self) -> u16 {
        self.current_adc.current_sample()
    }

    /// Starts the next current-sense conversion (done long before the next tick).
    #[inline(always)]
    pub fn start_current_sample(&mut self) {
        self.current_adc.start_conversion();
    }

    /// Writes the force command (a DAC code from the core's `DriveCalibration`; its zero code
    /// when disabled) and the enable line: enabling after the code is written, disabling before.
    #[inline(always)]
    pub fn set_drive(&mut self, code: u16, enable: bool) {
        if enable {
            self.force_dac.set_value(code);
            self.drive_enable.set_high();
        } else {
            self.drive_enable.set_low();
            self.force_dac.set_value(code);
        }
    }

    /// Toggles the tick heartbeat (PE8): a 5 kHz square wave at 10 kHz ticks while the tick
    /// runs, for the external enable gate.
    #[inline(always)]
    pub fn toggle_heartbeat(&mut self) {
        self.tick_heartbeat.toggle();
    }

    /// Camera trigger line level.
    #[inline(always)]
    pub fn set_camera_trigger(&mut self, high: bool) {
        self.camera_trigger.set_state(high.into());
    }

    /// Status LEDs.
    #[inline(always)]
    pub fn set_leds(&mut self, running: bool, fault: bool) {
        self.running_led.set_state(running.into());
        self.fault_led.set_state(fault.into());
    }

    /// The emergency-stop loop reads open (PE14 high: the normally-closed contact pressed, a
    /// wire broken, or nothing plugged into its connector). Read every tick, whatever the bed
    /// apparatus's harness says.
    #[inline(always)]
    pub fn emergency_stop_open(&self) -> bool {
        self.emergency_stop.is_high()
    }

    /// The bed apparatus's inputs (limit switches low at their limit) and starts the next
    /// bed-height conversion. `None` until the apparatus's presence line (PE15) has read low
    /// once since reset: a board with nothing wired has no apparatus. Once seen, a presence
    /// line that goes high reads as the apparatus's stop (`emergency_stop`: a harness pulled
    /// out is a stop). The emergency stop itself is [`Self::emergency_stop_open`].
    #[inline(always)]
    pub fn bed_inputs(&mut self) -> Option<BedInputs> {
        let present = self.bed_present.is_low();
        self.bed_seen |= present;
        if !self.bed_seen {
            return None;
        }
        let inputs = BedInputs {
            lift_up_limit: self.lift_up_limit.is_low(),
            lift_down_limit: self.lift_down_limit.is_low(),
            emergency_stop: !present,
            height_raw: self.height_adc.read(),
        };
        self.height_adc.start();
        Some(inputs)
    }

    /// Applies the bed apparatus's outputs.
    #[inline(always)]
    pub fn set_bed(&mut self, out: &BedOutputs) {
        self.blower_dac.set_value(blower_code(out.blower_v));
        let duty = if out.shaker_duty.is_finite() {
            out.shaker_duty.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let max = self.shaker.get_max_duty();
        self.shaker.set_duty((f32::from(max) * duty) as u16);
        self.lift_up.set_state(out.lift_up.into());
        self.lift_enable.set_state(out.lift_enable.into());
    }

    /// Feeds the independent watchdog.
    #[inline(always)]
    pub fn feed_watchdog(&mut self) {
        self.watchdog.feed();
    }
}
