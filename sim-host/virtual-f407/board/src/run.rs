//! One run of the firmware on the virtual board: the emulator stops every control period of
//! virtual time ([`RunConfig::period_ns`]); at each stop the rig is played through the pins (the
//! drive's force from the DAC and the enable line moves the robot; the robot's motion becomes
//! encoder edges; the bed's inputs and the current monitor are driven), the USB host's bytes are
//! exchanged, the firmware's RTT log is drained, and [`Action`]s due are applied. Everything is
//! a function of virtual time: two runs with the same inputs are identical.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rigless::device::ResetCause;
use rigless::emulator::{self, Driver, Host, Start, Stop};
use rigless::image::Image;
use rigless::session::Session;
use rigless::time::VirtualNanos;

use crate::board::VirtualF407;
use crate::encoder::QuadratureEncoder;
use crate::rig::{self, BedWiring, METRES_PER_COUNT, Outputs, Robot};
use crate::rtt::RttLog;

/// VREFINT_CAL, the factory calibration of the internal reference (read by the HAL's ADC
/// setup); a typical part's 1.21 V at 3.3 V.
pub const VREFINT_CAL: (u64, u16) = (0x1FFF_7A2A, 1500);
/// The unique device ID (RM0090 39.1, 96 bits at 0x1FFF_7A10): the board's, fixed.
pub const UNIQUE_ID: (u64, [u32; 3]) = (0x1FFF_7A10, [0x0030_0041, 0x3532_5108, 0x3636_3830]);

/// The real host's side of the USB CDC port.
pub trait HostPort {
    /// Bytes the host sends now (empty if none); `None` once the host has closed the port.
    fn receive(&mut self) -> Option<Vec<u8>>;
    /// Bytes the board sent.
    fn send(&mut self, bytes: &[u8]);
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
    /// The USB cable is unplugged (false) or plugged in (true).
    UsbAttached(bool),
    /// Bytes from the host.
    HostBytes(Vec<u8>),
    /// The encoder's signals stop (a cable fault): the count stays where it is.
    EncoderFrozen,
    /// The encoder's count jumps (a slipping scale), counts.
    EncoderJump(i64),
    /// The core stops executing (true) or goes on (false), with time and the peripherals running
    /// on: a hang, as a debugger's halt shows it (the watchdog keeps counting: the firmware does
    /// not freeze it on debug).
    Hold(bool),
    /// The core stops at the first stop after the firmware's first log line (its boot line,
    /// the last thing `init` does before the tick starts): a hang after the watchdog's start
    /// and before the first tick (RTT blocking on a probe that stopped reading, say).
    HoldAtTheBootLine,
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
    /// The robot the drive moves (None: the drive's output goes nowhere, the encoder is still).
    pub robot: Option<Robot>,
    /// Run no faster than `pace` x real time (None: as fast as possible).
    pub pace: Option<f64>,
    /// Actions at virtual times, ns.
    pub actions: Vec<(u64, Action)>,
    /// Keep one [`TraceRow`] every this many stops (0: none).
    pub trace_every: u64,
    /// The crystal, Hz (0: none that starts).
    pub crystal_hz: u64,
}

impl RunConfig {
    /// The defaults: 100 us stops, the bed ready, no robot, unpaced, no actions, no trace.
    pub fn new(elf: impl Into<PathBuf>) -> Self {
        Self {
            elf: elf.into(),
            period_ns: 100_000,
            until_ns: None,
            bed: BedWiring::READY,
            robot: None,
            pace: None,
            actions: Vec::new(),
            trace_every: 0,
            crystal_hz: crate::board::HSE_HZ,
        }
    }
}

/// The board and the rig at one stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// Virtual time, ns.
    pub t_ns: u64,
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
}

struct BoardDriver<H> {
    cfg_period: u64,
    until: Option<u64>,
    bed: BedWiring,
    robot: Option<Robot>,
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
    host: H,
    host_closed: bool,
    wall: Instant,
    plant_error: Option<String>,
    held: bool,
    resets_seen: usize,
    holds: Vec<u64>,
    hold_at_first_log_line: bool,
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
        }
    }
}

impl<H: HostPort + Send + 'static> Driver<VirtualF407> for BoardDriver<H> {
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
        self.rtt.drain(host);
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
        // The host's bytes, both ways.
        if !self.host_closed {
            match self.host.receive() {
                Some(bytes) if !bytes.is_empty() => mcu.otg.host_send(&bytes),
                Some(_) => {}
                None => self.host_closed = true,
            }
        }
        let received = mcu.otg.host_take_received();
        if !received.is_empty() {
            self.host.send(&received);
        }
        // The rig over the next period: the drive's force as the board commands it now.
        let out = rig::outputs(mcu);
        let (mut p, mut x_r, mut x_f, mut current) = (0.0, 0.0, 0.0, 0.0);
        if let Some(robot) = self.robot.as_mut() {
            if self.plant_error.is_none() {
                if let Err(e) = robot.advance(period as f64 * 1e-9, out.force_n) {
                    self.plant_error = Some(e.to_string());
                }
            }
            let st = robot.state();
            (p, x_r, x_f, current) = (st.p, st.x_r, st.x_f, robot.current_a());
        }
        if !self.frozen {
            let target = (p / METRES_PER_COUNT).round() as i64 + self.encoder_offset;
            self.encoder.move_to(&mut mcu.part, stop.at, period, target);
        }
        rig::drive_current_sense(&mut mcu.part, if out.drive_enable { current } else { 0.0 });
        rig::drive_bed_inputs(&mut mcu.part, stop.at, self.bed, 1650);
        let row = TraceRow {
            t_ns: now,
            out,
            encoder_count: self.encoder.count(),
            p_m: p,
            x_r_m: x_r,
            x_f_m: x_f,
            usb_configured: mcu.otg.configured(),
            ticks: mcu.tim7.updates,
        };
        if self.trace_every > 0 && self.stops % self.trace_every == 0 {
            self.trace.push(row);
        }
        self.last = Some(row);
        self.stops += 1;
        if let Some(pace) = self.pace {
            let due = std::time::Duration::from_secs_f64(now as f64 * 1e-9 / pace);
            let elapsed = self.wall.elapsed();
            if due > elapsed {
                std::thread::sleep(due - elapsed);
            }
        }
        let done = self.until.is_some_and(|u| now >= u) || self.host_closed;
        (!done).then_some(VirtualNanos(now + period))
    }
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
    let board =
        VirtualF407::with_crystal(cfg.crystal_hz).map_err(|e| format!("the virtual board: {e}"))?;
    let session = Session::new(Box::new(board), 0, VirtualNanos(cfg.period_ns))
        .map_err(|e| format!("the emulator session: {e}"))?;
    let mut actions = cfg.actions;
    actions.sort_by_key(|(t, _)| *t);
    let driver = BoardDriver {
        cfg_period: cfg.period_ns,
        until: cfg.until_ns,
        bed: cfg.bed,
        robot: cfg.robot,
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
        host,
        host_closed: false,
        wall: Instant::now(),
        plant_error: None,
        held: false,
        resets_seen: 0,
        holds: Vec::new(),
        hold_at_first_log_line: false,
    };
    let wall = Instant::now();
    let finished = emulator::run(session, &Start::new(&images), driver)
        .map_err(|e| format!("the emulator stopped: {e}"))?;
    let wall_s = wall.elapsed().as_secs_f64();
    let mut session = finished.session;
    let d = finished.driver;
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
