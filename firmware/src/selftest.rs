//! The emulated board's self-test and tick-cost benchmark: a delayed stutter jump (the
//! longest, with gain-lowering damping) run through the core's control tick with a synthetic
//! sensor feed, the instructions of every tick counted.
//!
//! The synthetic encoder follows the commanded position one tick late (perfect tracking plus a
//! +-1 count dither), so the controller, velocity filter and gain schedule all run as on the rig.
//! Report (one line on the console):
//! `selftest: ticks=N state=.. fault=.. samples=N dropped=N max_tick_instructions=N
//!  mean_tick_instructions=N max_tick_phase=.. configure_instructions=N counts_per_1024_instructions=N`
//!
//! Exit: 0 when the jump ran clean (and, for a full run, reached Done); 16 + code when a fault
//! latched (and force was zero from that tick on); 5 when a check failed.

use crate::console::console;
use crate::session::{ExitStatus, Injection};
use crate::tick_cost::InstructionCounter;
use sandjumper_core::config::{Trajectory, TrajectorySpec};
use sandjumper_core::{
    Command, GainLowering, Gains, JumpConfig, JumpKind, Phase, Rig, RigConfig, RigState, TickInput,
    TickTiming,
};

/// Delayed stutter at 10 Hz with the paper's longest delay, amplitude = the paper's stroke.
const JUMP: TrajectorySpec = TrajectorySpec::Sine {
    kind: JumpKind::DelayedStutter,
    amplitude_m: 0.01875,
    freq_hz: 10.0,
    tau_s: 0.75,
};
/// Ticks after the trajectory's end the full run keeps going (holding the final position).
const TAIL_TICKS: u32 = 500;
/// Ticks between heartbeats (the core's host-link watchdog is 500 ms).
const HEARTBEAT_TICKS: u32 = 1000;
/// A full run that has not reached Done after this many ticks (5 s at 10 kHz) fails.
const FULL_RUN_LIMIT_TICKS: u32 = 50_000;
/// Encoder jump injected by `inject=encoder-jump`, counts (far beyond `max_counts_per_tick`).
const INJECTED_JUMP_COUNTS: u32 = 1 << 20;

/// Runs the self-test for `ticks` control ticks (0 = the whole jump plus a tail).
pub fn run(counter: &InstructionCounter, ticks: u32, inject: Option<Injection>) -> ExitStatus {
    let config = RigConfig {
        deadline_cycles: 0,
        ..RigConfig::default()
    };
    let Ok(mut rig) = Rig::<64>::new(config) else {
        console!("selftest: FAILED: default rig configuration rejected");
        return ExitStatus::SelfTestFailed;
    };
    // The integrator on too, so its anti-windup path is part of the measured cost.
    let gains = Gains {
        ki_n_per_m_s: 50_000.0,
        ..Gains::default()
    };
    let jump = JumpConfig {
        gains,
        gain_lowering: Some(GainLowering {
            kp_factor: 0.1,
            kd_factor: 0.3,
            ramp_s: 0.1,
        }),
        ..JumpConfig::new(JUMP)
    };
    let start = counter.start();
    let configured = rig.handle(&Command::Configure(jump));
    let configure_instructions = counter.instructions_since(start);
    if configured.is_err() || rig.handle(&Command::Arm).is_err() {
        console!("selftest: FAILED: configure/arm rejected: {configured:?}");
        return ExitStatus::SelfTestFailed;
    }
    // The motor starts where the trajectory starts (the rig is armed there).
    let Ok(Trajectory::Sine(sine)) = JUMP.build() else {
        console!("selftest: FAILED: the self-test trajectory is invalid");
        return ExitStatus::SelfTestFailed;
    };
    let mut commanded_m = sine.eval(0.0).position_m as f32;
    let full_run = ticks == 0;
    let ticks = if full_run {
        FULL_RUN_LIMIT_TICKS
    } else {
        ticks
    };
    let inject_at = ticks / 2;
    let metres_per_count = config.metres_per_count;

    let mut timing = TickTiming::Unknown;
    let (mut max, mut sum, mut max_phase, mut n) = (0u32, 0u64, Phase::None, 0u32);
    let mut samples = 0u32;
    let mut next_seq = 0u32;
    let mut fault_tick = None;
    let mut done_since = None;
    while n < ticks {
        // One armed tick on the start position, then start.
        if n == 1 && rig.handle(&Command::Start).is_err() {
            console!("selftest: FAILED: start rejected");
            return ExitStatus::SelfTestFailed;
        }
        // Keep the host-link watchdog fed, as a host would (10 Hz).
        if n % HEARTBEAT_TICKS == 0 && rig.handle(&Command::Heartbeat).is_err() {
            console!("selftest: FAILED: heartbeat rejected");
            return ExitStatus::SelfTestFailed;
        }
        let dither = if n % 2 == 0 { 1 } else { -1 };
        let mut raw = ((commanded_m / metres_per_count) as i32).wrapping_add(dither) as u32;
        if inject == Some(Injection::EncoderJump) && n >= inject_at {
            raw = raw.wrapping_add(INJECTED_JUMP_COUNTS);
        }
        let input = TickInput {
            encoder_raw: raw,
            current_a: Some(0.0),
            timing,
        };
        let start = counter.start();
        let out = rig.tick(&input);
        let cost = counter.instructions_since(start);
        timing = TickTiming::Cycles(cost);
        sum += u64::from(cost);
        if cost > max {
            max = cost;
            max_phase = out.phase;
        }
        n += 1;
        // Drain telemetry like the link does; sequence numbers must be consecutive.
        while let Some(record) = rig.samples().pop() {
            if record.seq != next_seq {
                console!(
                    "selftest: FAILED: sample seq {} after {}",
                    record.seq,
                    next_seq
                );
                return ExitStatus::SelfTestFailed;
            }
            next_seq = record.seq.wrapping_add(1);
            commanded_m = record.commanded_position_m;
            samples += 1;
        }
        if let Some(code) = out.fault {
            let latched_on = *fault_tick.get_or_insert(n);
            if out.force_n != 0.0 || out.drive_enabled {
                console!(
                    "selftest: FAILED: force {} N / drive {} after {code:?}",
                    out.force_n,
                    out.drive_enabled
                );
                return ExitStatus::SelfTestFailed;
            }
            // A few ticks after the fault prove it stays latched at zero force.
            if n >= latched_on + 10 {
                break;
            }
        }
        if full_run && out.state == RigState::Done {
            let since = *done_since.get_or_insert(n);
            if n >= since + TAIL_TICKS {
                break;
            }
        }
    }
    let status = rig.status();
    let mean = if n > 0 { sum / u64::from(n) } else { 0 };
    console!(
        "selftest: ticks={n} state={:?} fault={} samples={samples} dropped={} max_tick_instructions={max} \
         mean_tick_instructions={mean} max_tick_phase={max_phase:?} configure_instructions={configure_instructions} \
         counts_per_1024_instructions={}",
        status.state,
        status.fault.map_or("none", |f| f.name()),
        status.counters.samples_dropped,
        counter.counts_per_1024_instructions(),
    );
    match status.fault {
        Some(code) => ExitStatus::Fault(code.code()),
        None if status.counters.samples_dropped != 0
            || (full_run && status.state != RigState::Done) =>
        {
            console!("selftest: FAILED: dropped samples or the jump did not finish");
            ExitStatus::SelfTestFailed
        }
        None => ExitStatus::Clean,
    }
}
