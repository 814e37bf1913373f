//! Fuzz the core's command handler as the firmware drives it: a script of host messages
//! (arbitrary bytes decoded as the wire's `HostMessage`, or one of the commands a session
//! sends: a valid jump's Configure, Arm, Start, Abort, ClearFault, AcknowledgeReset),
//! lockstep sensor frames, control ticks with any encoder motion, and the emergency-stop
//! loop opened or closed. After every step it checks:
//! - nothing panics;
//! - a fault always leaves the whole safe state: force zero, drive disabled, bed actuators off;
//! - no command while Running changes the trajectory (the jump's configuration stays);
//! - sample sequence numbers never go back.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_core::protocol::{MAX_FRAME, decode_frame, encode_payload_frame};
use sandjumper_core::{
    Command, HostMessage, JumpConfig, JumpKind, Rig, RigConfig, RigState, SensorFrame, TickInput,
    TickOutput, TickTiming, TrajectorySpec,
};

fn safe(out: &TickOutput) -> bool {
    out.force_n == 0.0
        && !out.drive_enabled
        && out.bed.blower_v == 0.0
        && out.bed.shaker_duty == 0.0
        && !out.bed.lift_enable
}

struct Driver {
    rig: Rig<64>,
    encoder: u32,
    last_seq: Option<u32>,
}

impl Driver {
    fn command(&mut self, c: &Command) {
        let (before, running) = (
            self.rig.jump_config().copied(),
            self.rig.state() == RigState::Running,
        );
        let _ = self.rig.handle(c);
        if running && self.rig.state() == RigState::Running {
            assert_eq!(
                self.rig.jump_config().copied(),
                before,
                "{c:?} changed the trajectory while running"
            );
        }
    }

    fn checked(&mut self, out: TickOutput) {
        if out.state == RigState::Faulted || out.fault.is_some() {
            assert!(safe(&out), "a fault without the whole safe state: {out:?}");
        }
        while let Some(s) = self.rig.samples().pop() {
            if let Some(last) = self.last_seq {
                assert!(s.seq > last, "sample seq went back: {last} then {}", s.seq);
            }
            self.last_seq = Some(s.seq);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(rig) = Rig::<64>::new(RigConfig::default()) else {
        return;
    };
    let mut d = Driver {
        rig,
        encoder: 0,
        last_seq: None,
    };
    let jump = JumpConfig::new(TrajectorySpec::Sine {
        kind: JumpKind::Stutter,
        amplitude_m: 0.01875,
        freq_hz: 10.0,
        tau_s: 0.0,
    });
    let mut i = 0;
    let mut next = |i: &mut usize| {
        let b = data.get(*i).copied();
        *i += 1;
        b
    };
    while let Some(op) = next(&mut i) {
        match op % 10 {
            0 => {
                // A message from the wire: these bytes as its payload behind a valid CRC.
                let len = usize::from(next(&mut i).unwrap_or(0));
                let end = (i + len).min(data.len());
                let payload = &data[i.min(end)..end];
                i = end;
                let mut frame = [0u8; MAX_FRAME];
                if let Ok(n) = encode_payload_frame(payload, &mut frame)
                    && let Ok(msg) = decode_frame::<HostMessage>(&mut frame[..n - 1])
                {
                    match msg {
                        HostMessage::Command { command, .. } => d.command(&command),
                        HostMessage::Sensor(f) => {
                            let a = d.rig.lockstep(&f, TickTiming::Unknown);
                            if a.state == RigState::Faulted || a.fault.is_some() {
                                assert!(a.force_n == 0.0 && !a.drive_enabled, "{a:?}");
                            }
                        }
                    }
                }
            }
            1 => d.command(&Command::Configure(jump)),
            2 => d.command(&Command::Arm),
            3 => d.command(&Command::Start),
            4 => d.command(&Command::Abort),
            5 => d.command(&Command::ClearFault),
            6 => d.command(&Command::AcknowledgeReset),
            7 => {
                // Ticks, the encoder moving by a signed step each.
                let n = next(&mut i).unwrap_or(1);
                let step = i32::from(next(&mut i).unwrap_or(0) as i8);
                for _ in 0..n {
                    d.encoder = d.encoder.wrapping_add_signed(step);
                    let out = d.rig.tick(&TickInput {
                        encoder_raw: d.encoder,
                        current_a: None,
                        timing: TickTiming::Unknown,
                    });
                    d.checked(out);
                }
            }
            8 => {
                let frame = SensorFrame {
                    frame: u32::from(next(&mut i).unwrap_or(0)),
                    encoder_count: d.encoder,
                    current_a: None,
                    overrun: next(&mut i).unwrap_or(0) & 1 == 1,
                    bed: None,
                };
                let a = d.rig.lockstep(&frame, TickTiming::Unknown);
                if a.state == RigState::Faulted || a.fault.is_some() {
                    assert!(a.force_n == 0.0 && !a.drive_enabled, "{a:?}");
                }
            }
            _ => {
                let open = next(&mut i).unwrap_or(0) & 1 == 1;
                d.rig.set_emergency_stop_loop(open);
            }
        }
    }
});
