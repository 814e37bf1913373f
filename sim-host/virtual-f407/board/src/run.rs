//! One run of the firmware on the virtual board: the emulator stops every control period of
//! virtual time ([`RunConfig::period_ns`]); at each stop the rig is played through the pins (the
//! drive's force from the DAC and the enable line moves the robot; the robot's motion becomes
//! encoder edges; the bed's inputs and the current monitor are driven), the USB host's bytes are
//! exchanged, the firmware's RTT log is drained, and [`Action`]s due are applied. Everything is
//! a function of virtual time: two runs with the same inputs are identical.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rigless::device::ResetCause;
use rigless::emulator::{self, Driver, Host, Start, Stop};
use rigless::image::Image;
use rigless::mcu::Mcu;
use rigless::session::Session;
use rigless::time::VirtualNanos;

use crate::board::VirtualF407;
use crate::core_clock::{CoreClock, clock_may_have_changed_at};
use crate::encoder::QuadratureEncoder;
use crate::rig::{self, BedWiring, EmergencyStopLoop, METRES_PER_COUNT, Outputs, Robot};
use crate::rtt::RttLog;
use sandjumper_model::intrusion_rig::{IntrusionRig, SUBSTEP_S};

/// VREFINT_CAL, the factory calibration of the internal reference (read by the HAL's ADC
/// setup); a typical part's 1.21 V at 3.3 V.
pub const VREFINT_CAL: (u64, u16) = (0x1FFF_7A2A, 1500);
/// The unique device ID (RM0090 39.1, 96 bits at 0x1FFF_7A10): the board's, fixed.
pub const UNIQUE_ID: (u64, [u32; 3]) = (0x1FFF_7A10, [0x0030_0041, 0x3532_5108, 0x3636_3830]);

/// TIM2_CNT (RM0090 18.4.10).
const TIM2_CNT: u64 = 0x4000_0024;

/// The real host's side of the USB CDC port.
pub trait HostPort {
    /// Bytes the host sends now (empty if none); `None` once the host has closed the port.
    fn receive(&mut self) -> Option<Vec<u8>>;
    /// Bytes the board sent.
    fn send(&mut self, bytes: &[u8]);
    /// The board's virtual time at a stop, ns (every control period: a host that passes it on
    /// keeps this cheap). Nothing by default.
    fn clock(&mut self, _now_ns: u64) {}
}

/// No host: nothing sent, what arrives is kept.
#[derive(Debug, Default)]
pub struct NoHost {
    /// Everything the board sent.
    pub received: Vec<u8>,
}

impl HostPort for NoHost {
    fn receive(&mut self) -> Option<Vec<u8>> {
        Some(Vec::new())
    }
    fn send(&mut self, bytes: &[u8]) {
        self.received.extend_from_slice(bytes);
    }
}

/// Something done to the board at a virtual time.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// The bed apparatus's inputs change.
    Bed(BedWiring),
    /// The emergency stop's loop opens (pressed, a wire broken, its connector out) or closes.
    EmergencyStop(EmergencyStopLoop),
    /// The USB cable is unplugged (false) or plugged in (true).
    UsbAttached(bool),
    /// Bytes from the host.
    HostBytes(Vec<u8>),
    /// The encoder's signals stop (a cable fault): the count stays where it is.
    EncoderFrozen,
    /// The encoder's count jumps (a slipping scale), counts.
    EncoderJump(i64),
    /// A probe attaches, puts RTT in blocking mode and stops reading it (a debugger session left
    /// open, a probe that went away): a full buffer then blocks a writer that waits.
    ProbeStopsReading,
    /// A probe attached from power-up puts RTT in blocking mode as soon as the firmware has set
    /// its buffer up (before `init`'s first log line), and has stopped reading with the buffer
    /// full: the firmware's next log write finds no room. A firmware in blocking mode waits
    /// there forever (with every interrupt masked: defmt's lock).
    ProbeFullFromPowerUp,
    /// TIM7 stops (its update events end: a timer or clock fault, its interrupt lost) while the
    /// core and every other peripheral run on; a reset restarts it.
    TickTimerStops,
    /// The core stops executing (true) or goes on (false), with time and the peripherals running
    /// on: a hang, as a debugger's halt shows it (the watchdog keeps counting: the firmware does
    /// not freeze it on debug).
    Hold(bool),
    /// The core stops at the first stop after the firmware's first log line (its boot line,
    /// the last thing `init` does before the tick starts): a hang after the watchdog's start
    /// and before the first tick (RTT blocking on a probe that stopped reading, say).
    HoldAtTheBootLine,
    /// The core stops as soon as the independent watchdog runs (its start forces the LSI on,
    /// RM0090 6.2.9: `LSIRDY`; the firmware never starts the LSI otherwise): a hang anywhere
    /// after the watchdog's start.
    HoldOnceTheWatchdogRuns,
    /// The supply rail changes, mV. Below the brown-out level the option bytes select (RM0090
    /// 3.9.10 `BOR_LEV`; off: the ~1.75 V power-down reset) the board holds the part in reset
    /// (the core stopped, every pin at its reset state), and releases it with a reset once the
    /// supply is back above the level's rising threshold (rigless 0.4 leaves the brown-out reset
    /// out; this is the board's model of it, DS8626's typical thresholds).
    Supply(u32),
    /// The reset button (NRST pulled low): the part restarts with the pin's flag.
    ResetButton,
    /// The crystal stops for good (cracked, a load capacitor come loose). With the clock
    /// security system on, the part switches to the HSI and raises the NMI (RM0090 6.2.7);
    /// without it nothing notices, and a core clocked from the crystal (directly or through
    /// the PLL) stops with its clock while the watchdog (LSI) counts on.
    CrystalStops,
    /// The core's next access to `[from, to)` fails as a bus error (no model sees it).
    BusError {
        /// First address.
        from: u64,
        /// One past the last.
        to: u64,
    },
}

/// How to run.
pub struct RunConfig {
    /// The firmware ELF.
    pub elf: PathBuf,
    /// Virtual time between two stops, ns (one control period: 100 us).
    pub period_ns: u64,
    /// Stop after this much virtual time, ns (None: until the host closes the port).
    pub until_ns: Option<u64>,
    /// The bed apparatus at power-up.
    pub bed: BedWiring,
    /// The emergency stop's loop at power-up.
    pub emergency_stop: EmergencyStopLoop,
    /// The robot the drive moves (None: the drive's output goes nowhere, the encoder is still).
    pub robot: Option<Robot>,
    /// Or the slow-intrusion fixture (the motor clamped; `p` is the rod's travel).
    pub intrusion: Option<IntrusionRig>,
    /// Run no faster than `pace` x real time (None: as fast as possible).
    pub pace: Option<f64>,
    /// Actions at virtual times, ns.
    pub actions: Vec<(u64, Action)>,
    /// Keep one [`TraceRow`] every this many stops (0: none).
    pub trace_every: u64,
    /// The crystal, Hz (0: none that starts).
    pub crystal_hz: u64,
    /// The supply rail at power-up, mV.
    pub supply_mv: u32,
    /// The drive's power stage is on (false: the bring-up's first steps, the drive's input
    /// wired but its output off: the carriage does not follow the force).
    pub drive_powered: bool,
    /// The flash interface never finishes a write ([`crate::board::F407::flash_stuck_busy`]).
    pub flash_stuck_busy: bool,
    /// The PLL never locks ([`crate::board::F407::pll_never_locks`]).
    pub pll_never_locks: bool,
    /// Print each line of the firmware's log on stdout as it is decoded (as `probe-rs run`
    /// shows a board's), not only in the report.
    pub echo_log: bool,
    /// Serve GDB's remote protocol on this listener (rigless's debugger server: breakpoints,
    /// stepping, registers and memory, virtual time standing still while the core is held).
    pub debugger: Option<std::net::TcpListener>,
    /// With a debugger: hold the core before its first instruction until a debugger continues,
    /// steps, detaches or kills it.
    pub wait_for_debugger: bool,
}

impl RunConfig {
    /// The defaults: 100 us stops, the bed ready, no robot, unpaced, no actions, no trace.
    pub fn new(elf: impl Into<PathBuf>) -> Self {
        Self {
            elf: elf.into(),
            period_ns: 100_000,
            until_ns: None,
            bed: BedWiring::READY,
            emergency_stop: EmergencyStopLoop::Closed,
            robot: None,
            intrusion: None,
            pace: None,
            actions: Vec::new(),
            trace_every: 0,
            crystal_hz: crate::board::HSE_HZ,
            supply_mv: crate::board::SUPPLY_MV,
            drive_powered: true,
            flash_stuck_busy: false,
            pll_never_locks: false,
            echo_log: false,
            debugger: None,
            wait_for_debugger: false,
        }
    }
}

/// The board and the rig at one stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// Virtual time, ns.
    pub t_ns: u64,
    /// Instructions the core retired so far (across resets).
    pub instructions: u64,
    /// The board's outputs.
    pub out: Outputs,
    /// The encoder count the edges amount to.
    pub encoder_count: i64,
    /// The robot's motor position, m (0 without a robot).
    pub p_m: f64,
    /// The robot's rod position, m.
    pub x_r_m: f64,
    /// The robot's foot position, m.
    pub x_f_m: f64,
    /// The USB host has configured the device.
    pub usb_configured: bool,
    /// TIM7 update events so far.
    pub ticks: u64,
    /// TIM2's counter as the firmware reads it (a debugger's read).
    pub tim2_count: u32,
    /// Bulk OUT bytes the device has taken from the host so far.
    pub usb_out_bytes: u64,
}

/// What a run leaves.
#[derive(Debug)]
pub struct RunReport {
    /// Why and when the emulator stopped last.
    pub stop: String,
    /// Virtual time at the end, ns.
    pub end_ns: u64,
    /// Wall time, s.
    pub wall_s: f64,
    /// The firmware's log, decoded.
    pub log: Vec<String>,
    /// Resets (virtual time, cause).
    pub resets: Vec<(u64, String)>,
    /// The trace (see [`RunConfig::trace_every`]).
    pub trace: Vec<TraceRow>,
    /// The robot at the end.
    pub robot: Option<Robot>,
    /// Outputs at the end.
    pub last: Option<TraceRow>,
    /// SYSCLK and the 48 MHz clock at the end, Hz.
    pub clocks_hz: (u64, u64),
    /// Counts the encoder could not fit in a period (see `encoder`).
    pub encoder_deferred_counts: u64,
    /// What the session reported as reached but not modelled, refused or unmapped.
    pub gaps: Vec<String>,
    /// USB statistics of the virtual host.
    pub usb: String,
    /// The robot's plant failed (its error).
    pub plant_error: Option<String>,
    /// When the core was held ([`Action::Hold`]), ns.
    pub holds: Vec<u64>,
    /// When the supply fell below the brown-out level ([`Action::Supply`]), ns.
    pub brown_outs: Vec<u64>,
    /// What the part's models told the session (a firmware outside the manual's rules).
    pub told: Vec<String>,
    /// Flash wait states short of table 12 after a supply change ([`Action::Supply`]).
    pub flash_violations: Vec<String>,
    /// The core's instruction rate as it followed HCLK (virtual time ns, instructions per
    /// second): one instruction a cycle, the 16 MHz HSI from reset (RM0090 6.2.2).
    pub instruction_rates: Vec<(u64, u64)>,
    /// The core's NMI input is high at the end: `RCC_CIR.CSSF` set and not yet cleared by
    /// `CSSC` (RM0090 6.2.7).
    pub nmi_input_high: bool,
    /// (shortest, longest) interval between two writes of the force DAC, ns: the control
    /// tick's output jitter (100,000 ns apart when nothing delays the tick).
    pub force_dac_interval_ns: Option<(u64, u64)>,
    /// (earliest, latest) force DAC write after its tick's timer update, ns.
    pub force_dac_offset_ns: Option<(u64, u64)>,
    /// The USB serial number string the virtual host read.
    pub usb_serial: Option<String>,
    /// PA15 and PB3 (the encoder's A and B pins) read high at the end: nothing drives them on
    /// the board (the encoder model drives TIM2's inputs), so their pulls decide.
    pub encoder_pins_high: (bool, bool),
}

struct BoardDriver<H> {
    cfg_period: u64,
    until: Option<u64>,
    bed: BedWiring,
    emergency_stop: EmergencyStopLoop,
    robot: Option<Robot>,
    intrusion: Option<IntrusionRig>,
    encoder: QuadratureEncoder,
    frozen: bool,
    encoder_offset: i64,
    pace: Option<f64>,
    actions: Vec<(u64, Action)>,
    next_action: usize,
    trace_every: u64,
    stops: u64,
    trace: Vec<TraceRow>,
    last: Option<TraceRow>,
    rtt: RttLog,
    /// Log lines printed so far with [`RunConfig::echo_log`] (None: not echoed).
    echoed: Option<usize>,
    host: H,
    host_closed: bool,
    wall: Instant,
    plant_error: Option<String>,
    held: bool,
    resets_seen: usize,
    holds: Vec<u64>,
    hold_at_first_log_line: bool,
    hold_when_watchdog_runs: bool,
    rtt_draining: bool,
    probe_full_pending: bool,
    supply_mv: u32,
    in_brown_out: bool,
    brown_outs: Vec<u64>,
    flash_violations: Vec<String>,
    /// The (HCLK, flash wait states) the last look saw: a change is a clock change to check.
    flash_clock_seen: (u64, u64),
    core_clock: CoreClock,
    pending_host_bytes: Vec<u8>,
    robot_released: bool,
    heartbeat_edges: u64,
    last_heartbeat_edge_ns: Option<u64>,
    drive_powered: bool,
}

impl<H> BoardDriver<H> {
    fn apply(
        &mut self,
        s: &mut Session<VirtualF407>,
        host: &mut dyn Host,
        at: u64,
        action: Action,
    ) {
        let mcu = &mut s.board_mut().mcu;
        match action {
            Action::Bed(b) => self.bed = b,
            Action::EmergencyStop(l) => self.emergency_stop = l,
            Action::UsbAttached(a) => mcu.otg.set_attached(a),
            Action::HostBytes(b) => mcu.otg.host_send(&b),
            Action::EncoderFrozen => self.frozen = true,
            Action::EncoderJump(c) => self.encoder_offset += c,
            Action::Hold(held) => {
                self.held = held;
                host.hold(held);
                if held {
                    self.holds.push(at);
                }
            }
            Action::HoldAtTheBootLine => self.hold_at_first_log_line = true,
            Action::ProbeStopsReading => {
                self.rtt.set_blocking(host);
                self.rtt_draining = false;
            }
            Action::ProbeFullFromPowerUp => {
                self.probe_full_pending = true;
                self.rtt_draining = false;
            }
            Action::TickTimerStops => mcu.tim7.halt(),
            Action::HoldOnceTheWatchdogRuns => self.hold_when_watchdog_runs = true,
            Action::BusError { from, to } => s.fail_next(from, to),
            Action::CrystalStops => {
                let clock_lost = mcu.system_clock_from_the_crystal();
                if !mcu.stop_crystal(VirtualNanos(at)) && clock_lost {
                    self.apply(s, host, at, Action::Hold(true));
                }
                // The NMI (CSSF set) and the core's rate on the HSI it fell back to.
                self.follow_the_clock(s, host, at);
            }
            Action::ResetButton => {
                let instructions = 0;
                s.reset_by_pin(VirtualNanos(at), instructions, host);
                // Back on the HSI (RM0090 6.2.2), before the first instruction.
                self.follow_the_clock(s, host, at);
            }
            Action::Supply(mv) => {
                s.board_mut().mcu.part.set_supply(mv);
                self.supply_mv = mv;
                self.check_flash_latency(s, at);
            }
        }
    }
}

/// Falling and rising brown-out thresholds of `BOR_LEV` (RM0090 3.9.10; DS8626 typical), mV.
pub fn brown_out_thresholds_mv(bor_lev: u64) -> (u32, u32) {
    match bor_lev & 0b11 {
        0b00 => (2800, 2900),
        0b01 => (2500, 2600),
        0b10 => (2200, 2300),
        _ => (1750, 1800),
    }
}

/// HCLK, Hz, and the flash's wait states (`FLASH_ACR.LATENCY`) as the part has them now.
fn flash_clock(s: &mut Session<VirtualF407>) -> (u64, u64) {
    let acr = s.board().mcu.part.bus().registers("FLASH").map_or(0, |r| {
        r.get(rigless::soc::stm32f427::generated::flash::Register::Acr)
    });
    let (rcc, regs) = s.board_mut().mcu.part.clocks();
    (rcc.hclk(regs), acr & 0xF)
}

/// The fewest flash wait states RM0090 table 12 allows at `hclk_hz` on a `supply_mv` rail
/// (`None`: no count does).
pub fn minimum_wait_states(hclk_hz: u64, supply_mv: u32) -> Option<u64> {
    let step_hz: u64 = match supply_mv {
        2700.. => 30_000_000,
        2400..=2699 => 24_000_000,
        2100..=2399 => 22_000_000,
        _ => 20_000_000,
    };
    let ws = hclk_hz.div_ceil(step_hz).saturating_sub(1);
    (ws <= 7).then_some(ws)
}

impl<H> BoardDriver<H> {
    /// RM0090 3.5.1 (table 12): the flash's wait states (`FLASH_ACR.LATENCY`) against HCLK on
    /// the supply; too few is a violation of the run, reported with when it was seen. Checked
    /// on every supply change and wherever the clock or the wait states changed (see
    /// `follow_the_clock`), so a clock raised before its wait states is caught (rigless 0.4
    /// checks neither).
    fn check_flash_latency(&mut self, s: &mut Session<VirtualF407>, at: u64) {
        let (hclk, latency) = flash_clock(s);
        if minimum_wait_states(hclk, self.supply_mv).is_none_or(|min| latency < min) {
            self.flash_violations.push(format!(
                "at {at} ns: {latency} flash wait states at {hclk} Hz on {} mV (RM0090 table 12)",
                self.supply_mv
            ));
        }
    }

    /// After every access to the RCC or the flash interface, and at every stop: the flash
    /// latency, checked when HCLK or the wait states changed (RM0090 3.5.1), and the core's
    /// rate and NMI input ([`CoreClock::follow`]).
    fn follow_the_clock(&mut self, s: &mut Session<VirtualF407>, host: &mut dyn Host, at: u64) {
        let now = flash_clock(s);
        if now != self.flash_clock_seen {
            self.flash_clock_seen = now;
            self.check_flash_latency(s, at);
        }
        self.core_clock.follow(&mut s.board_mut().mcu, host, at);
    }

    fn brown_out(&mut self, s: &mut Session<VirtualF407>, host: &mut dyn Host, stop: Stop) {
        let optcr = s
            .board()
            .mcu
            .part
            .bus()
            .registers("FLASH")
            .map_or(0b11 << 2, |r| {
                r.get(rigless::soc::stm32f427::generated::flash::Register::Optcr)
            });
        let (falling, rising) = brown_out_thresholds_mv(optcr >> 2);
        if !self.in_brown_out && self.supply_mv < falling {
            self.in_brown_out = true;
            self.brown_outs.push(stop.at.0);
            host.hold(true);
            // BOR drives the part's internal reset (RM0090 6.1.2: the flags are BORRSTF and
            // PINRSTF; rigless 0.4 carries no BORRSTF, so the pin's).
            Mcu::reset(
                &mut s.board_mut().mcu,
                stop.at,
                rigless::device::ResetCause::Pin,
            );
        } else if self.in_brown_out && self.supply_mv >= rising {
            self.in_brown_out = false;
            host.hold(false);
            s.reset_by_pin(stop.at, stop.instruction_count, host);
            self.follow_the_clock(s, host, stop.at.0);
        }
    }
}

impl<H: HostPort + Send + 'static> Driver<VirtualF407> for BoardDriver<H> {
    fn on_settled(
        &mut self,
        s: &mut Session<VirtualF407>,
        host: &mut dyn Host,
        settled: emulator::Settled,
    ) {
        if let Some(at) = clock_may_have_changed_at(&settled) {
            self.follow_the_clock(s, host, at);
        }
    }

    fn on_stop(
        &mut self,
        s: &mut Session<VirtualF407>,
        stop: Stop,
        host: &mut dyn Host,
    ) -> Option<VirtualNanos> {
        let now = stop.at.0;
        // A reset restarts a held core (a hang ends with the reset that ends it).
        let resets = s.resets().len();
        if resets > self.resets_seen {
            self.resets_seen = resets;
            if self.held {
                self.held = false;
                host.hold(false);
            }
        }
        if self.rtt_draining {
            self.rtt.drain(host);
        }
        if self.probe_full_pending && self.rtt.block_full(host) {
            self.probe_full_pending = false;
        }
        self.brown_out(s, host, stop);
        if self.hold_when_watchdog_runs {
            let (_, regs) = s.board_mut().mcu.part.clocks();
            let csr = regs.get(rigless::soc::stm32f427::generated::rcc::Register::Csr);
            if csr & (1 << 1) != 0 {
                // LSIRDY
                self.hold_when_watchdog_runs = false;
                self.apply(s, host, now, Action::Hold(true));
            }
        }
        if let Some(printed) = self.echoed.as_mut().filter(|p| **p < self.rtt.lines.len()) {
            let mut out = std::io::stdout().lock();
            for line in &self.rtt.lines[*printed..] {
                let _ = writeln!(out, "{line}");
            }
            let _ = out.flush();
            *printed = self.rtt.lines.len();
        }
        if self.hold_at_first_log_line && !self.rtt.lines.is_empty() {
            self.hold_at_first_log_line = false;
            self.apply(s, host, now, Action::Hold(true));
        }
        while let Some((at, action)) = self.actions.get(self.next_action).cloned() {
            if at > now {
                break;
            }
            self.next_action += 1;
            self.apply(s, host, now, action);
        }
        let period = self.cfg_period;
        let mcu = &mut s.board_mut().mcu;
        // The host's bytes, both ways. A real host cannot open the port before the device is
        // enumerated: what it writes earlier waits here, not in the virtual host (which, like
        // a bus with no device, discards it).
        if !self.host_closed {
            match self.host.receive() {
                Some(bytes) => self.pending_host_bytes.extend_from_slice(&bytes),
                None => self.host_closed = true,
            }
        }
        if mcu.otg.configured() && !self.pending_host_bytes.is_empty() {
            mcu.otg.host_send(&self.pending_host_bytes);
            self.pending_host_bytes.clear();
        }
        let received = mcu.otg.host_take_received();
        if !received.is_empty() {
            self.host.send(&received);
        }
        self.host.clock(now);
        // The rig over the next period: the drive's force as the board commands it now.
        let mut out = rig::outputs(mcu);
        // The external enable gate: retriggered by every heartbeat edge, counted at every access
        // to GPIOE (a pin toggled many times between two stops retriggers it as on silicon).
        mcu.note_heartbeat();
        if mcu.heartbeat_edges != self.heartbeat_edges {
            self.heartbeat_edges = mcu.heartbeat_edges;
            self.last_heartbeat_edge_ns = Some(now);
        }
        let gate_open = self
            .last_heartbeat_edge_ns
            .is_some_and(|t| now - t <= rig::MONOSTABLE_NS);
        out.drive_gated = out.drive_enable && gate_open;
        out.lift_gated = out.lift_enable && gate_open;
        if !out.drive_gated || !self.drive_powered {
            out.force_n = 0.0;
        }
        let (mut p, mut x_r, mut x_f, mut current) = (0.0, 0.0, 0.0, 0.0);
        // The carriage is held where it is until the drive first takes it (on the rig it rests
        // on its support, not in free fall along the rod): the plant starts moving then.
        self.robot_released |= out.drive_gated;
        if let Some(robot) = self.robot.as_mut() {
            if self.robot_released
                && self.plant_error.is_none()
                && let Err(e) = robot.advance(period as f64 * 1e-9, out.force_n)
            {
                self.plant_error = Some(e.to_string());
            }
            let st = robot.state();
            (p, x_r, x_f, current) = (st.p, st.x_r, st.x_f, robot.current_a());
        }
        if let Some(rig) = self.intrusion.as_mut() {
            let steps = ((period as f64 * 1e-9) / SUBSTEP_S).round().max(1.0) as u32;
            if self.robot_released
                && self.plant_error.is_none()
                && let Err(e) = rig.advance_steps(steps, out.force_n)
            {
                self.plant_error = Some(e.to_string());
            }
            p = rig.position_m();
            current = rig.motor_force_n() / rig.force_constant_n_a();
        }
        // Edges reach the count only once TIM2 counts in encoder mode (CEN, SMS 1-3): before
        // that the firmware has not set it up, and edges it cannot count would put its zero
        // off the plant's (the first period's burst to the robot's start position was lost so,
        // 0.83 mm). The count then starts at the plant's position, as the lockstep rigs' does:
        // the rig's encoder zeroed at p = 0.
        if !self.frozen && tim2_counts_the_encoder(&mut mcu.part) {
            let target = (p / METRES_PER_COUNT).round() as i64 + self.encoder_offset;
            self.encoder.move_to(&mut mcu.part, stop.at, period, target);
        }
        rig::drive_current_sense(&mut mcu.part, if out.drive_enable { current } else { 0.0 });
        rig::drive_bed_inputs(&mut mcu.part, stop.at, self.bed, self.emergency_stop, 1650);
        let row = TraceRow {
            t_ns: now,
            instructions: stop.instruction_count,
            out,
            encoder_count: self.encoder.count(),
            p_m: p,
            x_r_m: x_r,
            x_f_m: x_f,
            usb_configured: mcu.otg.configured(),
            usb_out_bytes: mcu.otg.out_bytes(),
            ticks: mcu.tim7.updates,
            tim2_count: rigless::mcu::Operate::peek(
                mcu,
                stop.at,
                TIM2_CNT,
                rigless::soc::Width::W32,
            )
            .unwrap_or(0) as u32,
        };
        if self.trace_every > 0 && self.stops.is_multiple_of(self.trace_every) {
            self.trace.push(row);
        }
        self.last = Some(row);
        self.stops += 1;
        if let Some(pace) = self.pace {
            // Saturating: no pace makes the wait panic (the CLI keeps it within 0.001-1000).
            let due = std::time::Duration::try_from_secs_f64(now as f64 * 1e-9 / pace)
                .unwrap_or(std::time::Duration::MAX);
            let elapsed = self.wall.elapsed();
            if due > elapsed {
                std::thread::sleep(due - elapsed);
            }
        }
        let done = self.until.is_some_and(|u| now >= u) || self.host_closed;
        (!done).then_some(VirtualNanos(now + period))
    }
}

/// PA15 and PB3 read high.
fn encoder_pins_high(part: &mut rigless::soc::stm32f427::Stm32f427) -> (bool, bool) {
    (
        rig::high(part, rig::PORT_A, 15),
        rig::high(part, rig::PORT_B, 3),
    )
}

/// TIM2 is enabled (CR1.CEN) in one of the encoder modes (SMCR.SMS 1-3, RM0090 18.3.12).
fn tim2_counts_the_encoder(part: &mut rigless::soc::stm32f427::Stm32f427) -> bool {
    use rigless::soc::stm32f427::generated::tim2::Register;
    let (_, regs) = part.timer(0);
    regs.get(Register::Cr1) & 1 != 0 && (1..=3).contains(&(regs.get(Register::Smcr) & 0b111))
}

/// Runs the firmware `cfg.elf` on the board with `host` on its USB port; gives the host back.
pub fn run<H: HostPort + Send + 'static>(
    cfg: RunConfig,
    host: H,
) -> Result<(RunReport, H), String> {
    let elf_bytes = std::fs::read(&cfg.elf)
        .map_err(|e| format!("cannot read the firmware {}: {e}", cfg.elf.display()))?;
    let rtt = RttLog::new(&elf_bytes)?;
    let images = firmware_images(&cfg.elf)?;
    let mut board =
        VirtualF407::with_crystal(cfg.crystal_hz).map_err(|e| format!("the virtual board: {e}"))?;
    board.mcu.part.set_supply(cfg.supply_mv);
    board.mcu.flash_stuck_busy = cfg.flash_stuck_busy;
    board.mcu.pll_never_locks = cfg.pll_never_locks;
    let session = Session::new(Box::new(board), 0, VirtualNanos(cfg.period_ns))
        .map_err(|e| format!("the emulator session: {e}"))?;
    let mut actions = cfg.actions;
    actions.sort_by_key(|(t, _)| *t);
    let (debugger, wait_for_debugger) = (cfg.debugger, cfg.wait_for_debugger);
    let driver = BoardDriver {
        cfg_period: cfg.period_ns,
        until: cfg.until_ns,
        bed: cfg.bed,
        emergency_stop: cfg.emergency_stop,
        robot: cfg.robot,
        intrusion: cfg.intrusion,
        encoder: QuadratureEncoder::default(),
        frozen: false,
        encoder_offset: 0,
        pace: cfg.pace,
        actions,
        next_action: 0,
        trace_every: cfg.trace_every,
        stops: 0,
        trace: Vec::new(),
        last: None,
        rtt,
        echoed: cfg.echo_log.then_some(0),
        host,
        host_closed: false,
        wall: Instant::now(),
        plant_error: None,
        held: false,
        resets_seen: 0,
        holds: Vec::new(),
        hold_at_first_log_line: false,
        hold_when_watchdog_runs: false,
        rtt_draining: true,
        probe_full_pending: false,
        supply_mv: cfg.supply_mv,
        in_brown_out: false,
        brown_outs: Vec::new(),
        flash_violations: Vec::new(),
        flash_clock_seen: (0, 0),
        core_clock: CoreClock::default(),
        pending_host_bytes: Vec::new(),
        robot_released: false,
        heartbeat_edges: 0,
        last_heartbeat_edge_ns: None,
        drive_powered: cfg.drive_powered,
    };
    let mut start = Start::new(&images);
    start.debugger = debugger.as_ref();
    start.wait_for_debugger = wait_for_debugger;
    let finished =
        emulator::run(session, &start, driver).map_err(|e| format!("the emulator stopped: {e}"))?;
    let mut session = finished.session;
    let d = finished.driver;
    let wall_s = d.wall.elapsed().as_secs_f64();
    let mut gaps = Vec::new();
    for u in session.unmapped() {
        gaps.push(format!("unmapped {u}"));
    }
    for (a, f) in session.refused() {
        gaps.push(format!("refused at {a:#x}: {f}"));
    }
    for (a, u) in session.unimplemented() {
        gaps.push(format!("unimplemented at {a:#x}: {u:?}"));
    }
    let told = session.told().map(|t| format!("{t:?}")).collect();
    let resets = session
        .resets()
        .iter()
        .map(|r| (r.at.0, format!("{:?}", r.cause)))
        .collect();
    let mcu = &mut session.board_mut().mcu;
    let (rcc, regs) = mcu.part.clocks();
    let clocks_hz = (rcc.sysclk(regs), rcc.pll48(regs));
    let _ = ResetCause::PowerOn;
    let report = RunReport {
        stop: format!("{:?}", finished.stop),
        end_ns: d.last.map_or(0, |r| r.t_ns),
        wall_s,
        log: d.rtt.lines.clone(),
        resets,
        trace: d.trace,
        robot: d.robot,
        last: d.last,
        clocks_hz,
        encoder_deferred_counts: d.encoder.deferred_counts,
        gaps,
        usb: format!("{:?}", mcu.otg.stats()),
        plant_error: d.plant_error,
        holds: d.holds,
        brown_outs: d.brown_outs,
        told,
        flash_violations: d.flash_violations,
        instruction_rates: d.core_clock.rates.clone(),
        nmi_input_high: d.core_clock.nmi_high(),
        force_dac_interval_ns: mcu.dac.ch1_interval_ns,
        force_dac_offset_ns: mcu.dac.ch1_offset_ns,
        usb_serial: mcu.otg.device_info().serial.clone(),
        encoder_pins_high: encoder_pins_high(&mut mcu.part),
    };
    Ok((report, d.host))
}

/// The ELF and the factory calibration the HAL reads.
pub fn firmware_images(elf: &Path) -> Result<Vec<Image>, String> {
    let firmware =
        Image::read(elf, None).map_err(|e| format!("cannot load {}: {e}", elf.display()))?;
    let cal = Image::new(
        Path::new("vrefint_cal.bin"),
        VREFINT_CAL.1.to_le_bytes().to_vec(),
        Some(VREFINT_CAL.0),
    )
    .map_err(|e| format!("VREFINT_CAL image: {e}"))?;
    let uid: Vec<u8> = UNIQUE_ID.1.iter().flat_map(|w| w.to_le_bytes()).collect();
    let uid = Image::new(Path::new("unique_id.bin"), uid, Some(UNIQUE_ID.0))
        .map_err(|e| format!("unique ID image: {e}"))?;
    Ok(vec![firmware, cal, uid])
}
