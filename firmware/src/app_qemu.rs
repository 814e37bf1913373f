//! The emulated board (QEMU mps2-an386): the same core, driven by lockstep frames instead of
//! a timer and peripherals. One sensor frame in -> one core tick -> one actuator frame out.
//!
//! Session protocol on the byte link (FIFOs or UART; frames are the core protocol's COBS
//! frames, `sandjumper_core::protocol`):
//! 1. On start the firmware sends `RigMessage::Status` (state Idle): the host knows it is up.
//! 2. The host sends `HostMessage::Command { id, .. }` (answered by `RigMessage::Reply` with
//!    the same id) and `HostMessage::Sensor(..)` (answered by `RigMessage::Actuator` for the
//!    same frame number). Before an actuator frame the firmware sends any full
//!    `RigMessage::Samples` batches and, on the tick a fault is latched, `RigMessage::Fault`.
//! 3. The host ends the session by closing its end (EOF). The firmware flushes the remaining
//!    samples and a final `RigMessage::Status` (its counters hold `max_tick_cycles`: the most
//!    instructions one core tick took), then exits: 0, or 16 + fault code if a fault is
//!    latched (EOF while Armed or Running latches `LinkLost` first).

use crate::console::console;
use crate::link;
use crate::selftest;
use crate::semihosting;
use crate::session::{ExitStatus, Session};
use crate::tick_cost::InstructionCounter;
use crate::transport::{ByteLink, CmsdkUart, SemihostingFifos};
use cortex_m_rt::{ExceptionFrame, entry, exception};
use sandjumper_core::protocol::{FrameDecoder, MAX_FRAME, encode_frame};
use sandjumper_core::{FaultCode, HostMessage, Rig, RigConfig, RigMessage, RigState, TickTiming};

/// Sample-queue capacity of the emulated board's rig (drained every tick).
const SAMPLE_QUEUE: usize = 64;

#[entry]
fn main() -> ! {
    let cp = cortex_m::Peripherals::take()
        .unwrap_or_else(|| semihosting::exit(ExitStatus::Panic.code()));
    let Some(counter) = InstructionCounter::new(cp.SYST) else {
        console!(
            "sandjumper firmware (mps2-an386): SysTick does not advance; run under QEMU -icount"
        );
        semihosting::exit(ExitStatus::Usage.code())
    };
    let mut cmdline = [0u8; 512];
    let line = semihosting::command_line(&mut cmdline).unwrap_or("");
    let status = match Session::parse(line) {
        Err(e) => {
            console!(
                "sandjumper firmware (mps2-an386): cannot understand `{}` in `{line}`",
                e.0
            );
            ExitStatus::Usage
        }
        Ok(Session::Hang) => loop {
            cortex_m::asm::nop();
        },
        Ok(Session::SelfTest { ticks, inject }) => selftest::run(&counter, ticks, inject),
        Ok(Session::Fifo { input, output }) => match SemihostingFifos::open(input, output) {
            Ok(mut fifos) => serve(&mut fifos, &counter),
            Err(e) => {
                console!(
                    "sandjumper firmware (mps2-an386): cannot open FIFOs {input} {output}: {e:?}"
                );
                ExitStatus::LinkError
            }
        },
        Ok(Session::Uart) => serve(&mut CmsdkUart::uart0(), &counter),
    };
    semihosting::exit(status.code())
}

/// Encodes and writes one message; a write failure ends the session.
fn send(link: &mut impl ByteLink, msg: &RigMessage) -> Result<(), ExitStatus> {
    let mut frame = [0u8; MAX_FRAME];
    // Every RigMessage fits MAX_FRAME by construction of the protocol; an encoding failure
    // would be a build defect, reported as a link error rather than a panic.
    let n = encode_frame(msg, &mut frame).map_err(|_| ExitStatus::LinkError)?;
    link.write_all(&frame[..n])
        .map_err(|_| ExitStatus::LinkError)
}

/// Serves one lockstep session on `link` until the host closes it.
fn serve(link: &mut impl ByteLink, counter: &InstructionCounter) -> ExitStatus {
    // Instruction counts stand in for cycles; no deadline on the emulator (the PIL host
    // injects overruns through the sensor frame's `overrun` flag).
    let config = RigConfig {
        deadline_cycles: 0,
        ..RigConfig::default()
    };
    let Ok(mut rig) = Rig::<SAMPLE_QUEUE>::new(config) else {
        return ExitStatus::Fault(FaultCode::InvalidConfiguration.code());
    };
    match run_session(link, &mut rig, counter) {
        Ok(()) => end_session(link, &mut rig),
        Err(status) => status,
    }
}

fn run_session<const Q: usize>(
    link: &mut impl ByteLink,
    rig: &mut Rig<Q>,
    counter: &InstructionCounter,
) -> Result<(), ExitStatus> {
    send(link, &RigMessage::Status(rig.status()))?;
    let mut decoder = FrameDecoder::new();
    let mut chunk = [0u8; 256];
    let mut previous_tick = TickTiming::Unknown;
    loop {
        let n = link.read(&mut chunk).map_err(|_| ExitStatus::LinkError)?;
        if n == 0 {
            return Ok(());
        }
        for &byte in &chunk[..n] {
            match decoder.push::<HostMessage>(byte) {
                None => {}
                Some(Err(_)) => {
                    // A burst of rejected frames latches LinkCorrupted: report it like any
                    // fault latched on a tick.
                    let fault_before = rig.fault();
                    rig.note_frame_rejected();
                    if let Some(report) = link::newly_latched(rig, fault_before) {
                        send(link, &report)?;
                    }
                }
                Some(Ok(HostMessage::Command { id, command })) => {
                    // On the rig a command runs inside a control tick: its cost is that tick's
                    // and reaches the core with the next tick, as the F407's does.
                    let start = counter.start();
                    let reply = link::reply_to(rig, id, &command);
                    previous_tick = TickTiming::Cycles(counter.instructions_since(start));
                    send(link, &reply)?;
                }
                Some(Ok(HostMessage::Sensor(frame))) => {
                    rig.note_frame_ok();
                    let fault_before = rig.fault();
                    let start = counter.start();
                    let actuator = rig.lockstep(&frame, previous_tick);
                    previous_tick = TickTiming::Cycles(counter.instructions_since(start));
                    send_telemetry(link, rig, false)?;
                    if let Some(report) = link::newly_latched(rig, fault_before) {
                        send(link, &report)?;
                    }
                    send(link, &RigMessage::Actuator(actuator))?;
                }
            }
        }
    }
}

/// Sends the waiting sample records in batches (the last partial one only if `flush`).
fn send_telemetry<const Q: usize>(
    link: &mut impl ByteLink,
    rig: &mut Rig<Q>,
    flush: bool,
) -> Result<(), ExitStatus> {
    let waiting = rig.samples().len();
    let mut result = Ok(());
    link::send_sample_batches(
        || rig.samples().pop(),
        waiting,
        flush,
        |msg| {
            if result.is_ok() {
                result = send(link, &msg);
            }
        },
    );
    result
}

/// The host closed the link: latch `LinkLost` if it left the rig mid-run, flush telemetry,
/// send the final status, and pick the exit status.
fn end_session<const Q: usize>(link: &mut impl ByteLink, rig: &mut Rig<Q>) -> ExitStatus {
    if matches!(rig.state(), RigState::Armed | RigState::Running) {
        let before = rig.fault();
        rig.raise_fault(FaultCode::LinkLost);
        if let Some(report) = link::newly_latched(rig, before) {
            let _ = send(link, &report);
        }
    }
    // The host may already have stopped reading; nothing more can be reported then.
    let _ = send_telemetry(link, rig, true);
    let _ = send(link, &RigMessage::Status(rig.status()));
    match rig.fault() {
        Some(code) => ExitStatus::Fault(code.code()),
        None => ExitStatus::Clean,
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // No drive here: leaving the session is what stops the (simulated) actuator.
    console!("sandjumper firmware (mps2-an386): panic: {info}");
    semihosting::exit(ExitStatus::Panic.code())
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    console!(
        "sandjumper firmware (mps2-an386): HardFault at pc={:#x}",
        frame.pc()
    );
    semihosting::exit(ExitStatus::HardFault.code())
}
