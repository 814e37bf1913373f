//! The release F407 binary fed random bytes and truncated frames over USB while it holds
//! and runs a jump (#54): it stays up (no reset), counts what it rejected, decodes every good
//! frame around it, still answers the host, and its pins, the robot and its status are
//! exactly those of the same run without the garbage (the virtual board is deterministic):
//! nothing the host garbles reaches the drive.

mod common;

use common::{MS, armed_actions, command_frame, rig_messages, robot_at_single_start, send};
use sandjumper_core::{Command, Reply, RigMessage, Status};
use sandjumper_virtual_f407::run::{Action, NoHost, RunConfig, RunReport, run};

/// Configure at 190 ms, Arm at 200 ms (the drive holds), Start at 300 ms (a 5 Hz single
/// sine: running to ~500 ms), heartbeats every 20 ms to the end.
const ARM_AT: u64 = 200 * MS;
const START_AT: u64 = 300 * MS;
const STATUS_AT: u64 = 880 * MS;
const END: u64 = 900 * MS;

/// A seeded xorshift: the same garbage every run.
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// COBS-encode `body` and end it with the delimiter.
fn cobs(body: &[u8]) -> Vec<u8> {
    let mut out = vec![0];
    let mut code_at = 0;
    for &b in body {
        if b == 0 || out.len() - code_at == 255 {
            out[code_at] = (out.len() - code_at) as u8;
            code_at = out.len();
            out.push(0);
            if b == 0 {
                continue;
            }
        }
        out.push(b);
    }
    out[code_at] = (out.len() - code_at) as u8;
    out.push(0);
    out
}

/// The body of a COBS frame (its delimiter dropped).
fn uncobs(frame: &[u8]) -> Vec<u8> {
    let enc = &frame[..frame.len() - 1];
    let mut out = Vec::new();
    let mut i = 0;
    while i < enc.len() {
        let code = enc[i] as usize;
        out.extend_from_slice(&enc[i + 1..i + code]);
        i += code;
        if code < 255 && i < enc.len() {
            out.push(0);
        }
    }
    out
}

/// Garbage from 150 ms (before the host configures and arms) to 760 ms, every 7-19 ms: random bytes (delimiters among them); valid
/// frames cut short and ended with a delimiter (a cable glitch mid-frame); and whole `Abort`
/// frames with one bit of their message flipped, their CRC left as it was (line noise: only
/// the CRC tells them from another command or id). Each chunk ends with a delimiter, so the
/// next frame the host sends starts clean. The count of chunks.
fn garbage() -> (Vec<(u64, Action)>, u32) {
    let mut noise = Noise(0x5a17_c0de_2026_1130);
    let mut t = 150 * MS;
    let mut out = Vec::new();
    while t < 760 * MS {
        let kind = noise.below(3);
        let bytes = if kind == 2 {
            let mut body = uncobs(&command_frame(900 + out.len() as u16, Command::Abort));
            // A bit of the version byte or the message, never of the CRC's four bytes.
            let at = noise.below(body.len() as u64 - 4) as usize;
            body[at] ^= 1 << noise.below(8);
            cobs(&body)
        } else if kind == 0 {
            let n = 1 + noise.below(300) as usize;
            let mut b: Vec<u8> = (0..n).map(|_| noise.next() as u8).collect();
            b.push(0);
            b
        } else {
            let whole = command_frame(
                900 + out.len() as u16,
                if noise.below(2) == 0 {
                    Command::Abort
                } else {
                    Command::StatusQuery
                },
            );
            // Cut before its delimiter: at least one byte missing.
            let keep = noise.below(whole.len() as u64 - 1) as usize;
            let mut b = whole[..keep].to_vec();
            b.push(0);
            b
        };
        out.push((t, Action::HostBytes(bytes)));
        t += (7 + noise.below(13)) * MS;
    }
    let n = out.len() as u32;
    (out, n)
}

/// The run with `extra` actions; its report and every message the board sent.
fn jump(extra: Vec<(u64, Action)>) -> Option<(RunReport, Vec<RigMessage>)> {
    let elf = common::firmware_elf()?;
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(END);
    cfg.trace_every = 1;
    cfg.robot = Some(robot_at_single_start());
    let mut actions = armed_actions(ARM_AT, END);
    actions.push((START_AT, send(500, Command::Start)));
    actions.push((STATUS_AT, send(501, Command::StatusQuery)));
    actions.extend(extra);
    actions.sort_by_key(|(t, _)| *t);
    cfg.actions = actions;
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let messages = rig_messages(&host.received);
    Some((r, messages))
}

/// The board's answer to the status query at `STATUS_AT`.
fn status_of(messages: &[RigMessage]) -> Option<Status> {
    messages.iter().find_map(|m| match m {
        RigMessage::Reply {
            id: 501,
            result: Ok(Reply::Status(s)),
        } => Some(*s),
        _ => None,
    })
}

#[test]
fn the_test_frames_coding_is_cobs() {
    let frame = command_frame(7, Command::Abort);
    assert_eq!(cobs(&uncobs(&frame)), frame);
    assert_eq!(cobs(&[0, 1, 0]), [1, 2, 1, 1, 0]);
    assert_eq!(uncobs(&[1, 2, 1, 1, 0]), [0, 1, 0]);
}

#[test]
fn random_and_truncated_frames_over_usb_change_nothing_the_drive_does() {
    let (chunks, n) = garbage();
    let Some((clean, clean_messages)) = jump(Vec::new()) else {
        return;
    };
    let (r, messages) = jump(chunks).expect("the firmware is there");
    let before = status_of(&clean_messages).expect("the clean run answers its status query");

    assert!(
        r.resets.is_empty(),
        "the board reset: {:?}; log {:?}",
        r.resets,
        r.log
    );
    let status = status_of(&messages).unwrap_or_else(|| {
        panic!(
            "no answer to the status query after the garbage; log {:?}",
            r.log
        )
    });
    // Every chunk ended in a delimiter: each is at least one rejected frame; the host's own
    // frames were all decoded, none eaten by the garbage before them.
    assert_eq!(before.counters.frames_rejected, 0);
    assert!(
        status.counters.frames_rejected >= n,
        "{} frames rejected for {n} chunks of garbage: {status:?}",
        status.counters.frames_rejected
    );
    assert_eq!(
        status.counters.frames_ok, before.counters.frames_ok,
        "frames decoded"
    );
    // Otherwise the same rig: state, phase, fault and when, every other counter. (On hard
    // ground this jump ends in the tracking error's safe stop at ~607 ms, with or without the
    // garbage: tests/faults.rs covers that path.)
    let mut same = status;
    same.counters.frames_rejected = 0;
    // The longest tick is a timing measure: rejecting garbage in the USB interrupt may add a
    // few cycles to it, never a budget's worth.
    assert!(
        status.counters.max_tick_cycles <= before.counters.max_tick_cycles + 200,
        "the longest tick {} cycles against {} without the garbage",
        status.counters.max_tick_cycles,
        before.counters.max_tick_cycles
    );
    same.counters.max_tick_cycles = before.counters.max_tick_cycles;
    assert_eq!(same, before, "the garbage changed the rig's status");
    // The jump ran (the drive was on and the motor moved)...
    let moved = r
        .trace
        .iter()
        .map(|row| row.p_m)
        .fold(0.0f64, |m, p| m.max((p - r.trace[0].p_m).abs()));
    assert!(moved > 0.01, "the motor moved only {moved} m: no jump ran");
    assert!(r.trace.iter().any(|row| row.out.drive_enable));
    // ...exactly as without the garbage, pin for pin and bit for bit of the motion, at the
    // same stops (the emulator stops on an instruction boundary: the extra instructions that
    // rejected the garbage move a stop by a few ns, never by a tick).
    assert_eq!(clean.trace.len(), r.trace.len());
    for (a, b) in clean.trace.iter().zip(&r.trace) {
        assert!(
            a.t_ns.abs_diff(b.t_ns) < 1_000,
            "stops {} and {} ns: the garbage moved the board's time",
            a.t_ns,
            b.t_ns
        );
        assert_eq!(
            (a.out, a.p_m.to_bits(), a.x_r_m.to_bits()),
            (b.out, b.p_m.to_bits(), b.x_r_m.to_bits()),
            "at {} ns the garbage changed the outputs or the motion",
            a.t_ns
        );
    }
    eprintln!(
        "{n} chunks of garbage: {} frames rejected, {} decoded; state {:?}, fault {:?}",
        status.counters.frames_rejected, status.counters.frames_ok, status.state, status.fault
    );
}
