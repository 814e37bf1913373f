//! Probe: the sandjumper F407 release ELF on rigless 0.4.0's STM32F427, with outside models for
//! TIM7 (update IRQ 55) and the DAC bound to their unmodelled slots by a wrapping `Mcu`.
use std::num::{NonZeroU32, NonZeroU64};
use std::path::Path;
use std::time::Instant;

use rigless::device::{Device, DeviceContext, ErasedDevice, RegisterFile, ResetCause};
use rigless::emulator::{self, Driver, Host, Start, Stop};
use rigless::image::Image;
use rigless::machine::{Board, Target, armv7m};
use rigless::mcu::{Mcu, Operate};
use rigless::session::Session;
use rigless::soc::stm32f427::Stm32f427;
use rigless::soc::stm32f427::generated::{dac, tim6};
use rigless::soc::stm32f427::peripherals::gpio::Pin;
use rigless::soc::stm32f427::peripherals::rcc::Apb;
use rigless::soc::{Bus, Width};
use rigless::time::{EventId, VirtualNanos};

// ---------------------------------------------------------------- TIM7: basic timer, update IRQ
#[derive(Debug, Default)]
struct BasicTimer {
    clock_hz: u64,
    next: Option<EventId>,
    period_ns: u64,
    updates: u64,
}

impl BasicTimer {
    fn reschedule(&mut self, r: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        let cr1 = r.get(tim6::Register::Cr1);
        if cr1 & 1 == 0 || self.clock_hz == 0 {
            self.next = None;
            return;
        }
        let psc = r.get(tim6::Register::Psc) + 1;
        let arr = r.get(tim6::Register::Arr) + 1;
        self.period_ns = (psc * arr * 1_000_000_000) / self.clock_hz;
        self.next = Some(cx.schedule(VirtualNanos(cx.now().0 + self.period_ns.max(1))));
    }
}

impl Device for BasicTimer {
    type Register = tim6::Register;
    fn write(
        &mut self,
        reg: tim6::Register,
        _v: u64,
        r: &mut RegisterFile,
        cx: &mut DeviceContext<'_>,
    ) {
        match reg {
            tim6::Register::Cr1 | tim6::Register::Psc | tim6::Register::Arr => {
                self.reschedule(r, cx)
            }
            tim6::Register::Sr => {
                if r.get(tim6::Register::Sr) & 1 == 0 {
                    cx.lower(0);
                }
            }
            tim6::Register::Egr => r.set(tim6::Register::Egr, 0),
            _ => {}
        }
    }
    fn on_event(&mut self, event: EventId, r: &mut RegisterFile, cx: &mut DeviceContext<'_>) {
        if self.next != Some(event) {
            return;
        }
        self.updates += 1;
        r.set(tim6::Register::Sr, 1);
        if r.get(tim6::Register::Dier) & 1 != 0 {
            cx.raise(0); // TIM7's one line: 55
        }
        self.next = Some(cx.schedule(VirtualNanos(cx.now().0 + self.period_ns.max(1))));
    }
    fn reset(&mut self) {
        *self = Self {
            clock_hz: self.clock_hz,
            ..Self::default()
        };
    }
}

// ---------------------------------------------------------------- DAC: holding registers to volts
#[derive(Debug, Default)]
struct DacModel {
    volts: [f64; 2],
    writes: u64,
}
impl Device for DacModel {
    type Register = dac::Register;
    fn write(
        &mut self,
        reg: dac::Register,
        v: u64,
        r: &mut RegisterFile,
        _cx: &mut DeviceContext<'_>,
    ) {
        self.writes += 1;
        let code = match reg {
            dac::Register::Dhr12r1 => Some((0, v & 0xFFF)),
            dac::Register::Dhr12r2 => Some((1, v & 0xFFF)),
            _ => None,
        };
        if let Some((ch, code)) = code {
            r.set(
                if ch == 0 {
                    dac::Register::Dor1
                } else {
                    dac::Register::Dor2
                },
                code,
            );
            self.volts[ch] = code as f64 * 3.3 / 4095.0;
        }
    }
}

// ---------------------------------------------------------------- the part, with those two bound
#[derive(Debug)]
struct F407 {
    part: Stm32f427,
    tim7: BasicTimer,
    tim7_slot: usize,
    dac: DacModel,
    dac_slot: usize,
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
        Device::reset(&mut self.tim7);
        self.dac = DacModel::default();
    }
    fn poll(&mut self, now: VirtualNanos) {
        self.part.poll(now);
    }
    fn split(&mut self, slot: usize) -> (&mut Bus, Option<&mut dyn ErasedDevice>) {
        if slot == self.tim7_slot {
            let (rcc, regs) = self.part.clocks();
            self.tim7.clock_hz = rcc.timer_clock(regs, Apb::One);
            return (self.part.bus_mut(), Some(&mut self.tim7));
        }
        if slot == self.dac_slot {
            return (self.part.bus_mut(), Some(&mut self.dac));
        }
        self.part.split(slot)
    }
}

#[derive(Debug)]
struct VirtualF407 {
    mcu: F407,
}
impl rigless::snapshot::Store for VirtualF407 {}

impl VirtualF407 {
    fn new(models: bool) -> Result<Self, Box<dyn std::error::Error>> {
        let mut part = Stm32f427::new()?;
        part.rcc.attach_crystals(8_000_000, 0);
        part.set_supply(3300);
        for adc in &mut part.adc {
            adc.set_reference(3300);
        }
        let (tim7_slot, dac_slot) = if models {
            (part.bus().slot("TIM7")?, part.bus().slot("DAC")?)
        } else {
            (usize::MAX, usize::MAX)
        };
        Ok(Self {
            mcu: F407 {
                part,
                tim7: BasicTimer::default(),
                tim7_slot,
                dac: DacModel::default(),
                dac_slot,
            },
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
            clock_hz: NonZeroU64::new(168_000_000).unwrap(),
            interrupt_lines: NonZeroU32::new(u32::from(self.mcu.cpu().interrupt_lines)).unwrap(),
            priority_bits: 4,
            refclk_divider: NonZeroU32::new(8).unwrap(),
            instructions_per_second: armv7m::INSTRUCTIONS_PER_SECOND,
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

// ---------------------------------------------------------------- driver: 1 ms stops, RTT drain
struct Probe {
    rtt: u64,
    end: u64,
    bytes: Vec<u8>,
    log: Vec<String>,
}

fn rd(host: &mut dyn Host, a: u64) -> u64 {
    host.read(a, Width::W32).unwrap_or(0)
}

impl Probe {
    fn drain(&mut self, host: &mut dyn Host) {
        let up = self.rtt + 24;
        let (buf, size, wr, rdo) = (
            rd(host, up + 4),
            rd(host, up + 8),
            rd(host, up + 12),
            rd(host, up + 16),
        );
        if size == 0 || buf == 0 {
            return;
        }
        let mut r = rdo;
        while r != wr {
            self.bytes
                .push(host.read(buf + r, Width::W8).unwrap_or(0) as u8);
            r = (r + 1) % size;
        }
        let _ = host.write(up + 16, Width::W32, r);
    }
}

impl Driver<VirtualF407> for Probe {
    fn on_stop(
        &mut self,
        s: &mut Session<VirtualF407>,
        stop: Stop,
        host: &mut dyn Host,
    ) -> Option<VirtualNanos> {
        self.drain(host);
        let p = &mut s.board_mut().mcu.part;
        let (rcc, regs) = p.clocks();
        let sys = rcc.sysclk(regs);
        let pll48 = rcc.pll48(regs);
        let mut pins = String::new();
        for (port, pin) in [(4usize, 10u8), (4, 13), (4, 14), (3, 12)] {
            let (g, r) = p.port(port);
            pins += &format!(
                " P{}{}={:?}",
                (b'A' + port as u8) as char,
                pin,
                g.level(Pin::new(pin).unwrap(), r)
            );
        }
        let m = &s.board().mcu;
        self.log.push(format!(
            "t={:>9} n={:>9} {:?} sysclk={} pll48={} tim7_updates={} dac_writes={} dac_v={:.3?}{}",
            stop.at.0,
            stop.instruction_count,
            stop.reason,
            sys,
            pll48,
            m.tim7.updates,
            m.dac.writes,
            m.dac.volts,
            pins
        ));
        (stop.at.0 < self.end).then_some(VirtualNanos(stop.at.0 + 1_000_000))
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let Some(elf) = args.next() else {
        eprintln!(
            "usage: probe ELF [MS]  (ELF: target/thumbv7em-none-eabihf/release/sandjumper-firmware; MS: virtual milliseconds, default 10)"
        );
        std::process::exit(2);
    };
    let ms: u64 = args.next().map(|s| s.parse().unwrap()).unwrap_or(10);
    let models = std::env::var("NO_MODELS").is_err();
    let vrefint = std::env::var("NO_VREFINT").is_err();
    // _SEGGER_RTT from the symbol table (llvm-nm), passed in by env for the probe
    let rtt = u64::from_str_radix(
        std::env::var("RTT")
            .unwrap_or("20010a10".into())
            .trim_start_matches("0x"),
        16,
    )?;

    if std::env::var("WINDOW").is_ok() {
        let mut part = Stm32f427::new()?;
        let w = rigless::soc::Window::new(
            "OTG_FS_FIFO",
            0x5000_1000,
            NonZeroU64::new(0x1_0000).unwrap(),
        );
        println!(
            "add_window(0x5000_1000): {:?}",
            part.bus_mut().add_window(w)
        );
        for name in [
            "OTG_FS_GLOBAL",
            "OTG_FS_HOST",
            "OTG_FS_DEVICE",
            "OTG_FS_PWRCLK",
            "TIM7",
            "DAC",
        ] {
            let p = part.bus().peripheral(name).unwrap();
            println!(
                "{name}: base={:#x} size={:#x} irqs={:?} slot={:?}",
                p.base,
                p.size,
                p.interrupts,
                part.bus().slot_of(name)
            );
        }
        let g = part.bus().registers("OTG_FS_GLOBAL").unwrap();
        let _ = g;
        for a in [0x5000_0020u64, 0x5000_003C, 0x5000_1000] {
            println!("slot_at({a:#x})={:?}", part.bus().slot_at(a));
        }
        return Ok(());
    }
    let mut images = vec![Image::read(Path::new(&elf), None)?];
    if vrefint {
        // VREFINT_CAL (0x1FFF_7A2A), a typical 1.21 V at 3.3 V calibration: 1500
        images.push(Image::new(
            Path::new("vrefint_cal.bin"),
            1500u16.to_le_bytes().to_vec(),
            Some(0x1FFF_7A2A),
        )?);
    }
    let session = Session::new(
        Box::new(VirtualF407::new(models)?),
        0,
        VirtualNanos(1_000_000),
    )?;
    let wall = Instant::now();
    let finished = emulator::run(
        session,
        &Start::new(&images),
        Probe {
            rtt,
            end: ms * 1_000_000,
            bytes: vec![],
            log: vec![],
        },
    );
    let wall = wall.elapsed();
    let finished = match finished {
        Ok(f) => f,
        Err(e) => {
            eprintln!("run error: {e}");
            eprintln!("debug: {e:?}");
            std::process::exit(1);
        }
    };
    for l in &finished.driver.log {
        println!("{l}");
    }
    println!(
        "wall={:?} for {} ms virtual; stop={:?}",
        wall, ms, finished.stop
    );
    std::fs::write("rtt.bin", &finished.driver.bytes)?;
    println!("rtt bytes={} (rtt.bin)", finished.driver.bytes.len());
    let s = &finished.session;
    for u in s.unmapped() {
        println!("unmapped {u}");
    }
    for (a, f) in s.refused() {
        println!("refused at={a:#x} {f}");
    }
    for (a, u) in s.unimplemented() {
        println!("unimplemented at={a:#x} {u:?}");
    }
    for (a, u) in s.undefined() {
        println!("undefined at={a:#x} {u:?}");
    }
    for (i, n) in s.unrouted() {
        println!("unrouted {i} {n}");
    }
    for r in s.resets() {
        println!("reset {r:?}");
    }
    for t in s.told() {
        println!("told {t:?}");
    }
    Ok(())
}
