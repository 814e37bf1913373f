//! The emulated-board firmware (QEMU mps2-an386, Cortex-M4F) builds, boots, runs its self-test
//! (a synthetic sensor feed through the core's control tick, lockstep) and reports its exit
//! status through semihosting: 0 when healthy, non-zero on a fault, killed when hung.
//!
//! Skips with a message when `qemu-system-arm` is missing, unless `CI` is set (then it fails).

use std::path::Path;
use std::process::{Command, Output};

use sandjumper_rig::hil::emulated_firmware;
use std::time::{Duration, Instant};

/// Own target directory: the outer `cargo test` holds the lock on `target/`'s host build.
const FIRMWARE_TARGET_DIR: &str = emulated_firmware::EMULATED_TARGET_DIR;

fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// QEMU and the firmware toolchain are there; if not, skip with a message (fail in CI).
fn qemu_available() -> bool {
    emulated_firmware::test_prerequisites("booting the emulated firmware")
        .map_err(|skip| eprintln!("{skip}"))
        .is_ok()
}

/// The emulated-board firmware, built once per test run.
fn firmware_elf() -> &'static Path {
    emulated_firmware::build_once(workspace()).unwrap_or_else(|e| panic!("{e}"))
}

fn boot(args: &[&str], timeout_s: u32) -> (Output, Duration) {
    let elf = firmware_elf();
    let start = Instant::now();
    let out = Command::new(workspace().join("firmware/qemu-run.sh"))
        .arg(elf)
        .args(args)
        .env("SANDJUMPER_QEMU_TIMEOUT", timeout_s.to_string())
        .output()
        .expect("running firmware/qemu-run.sh");
    (out, start.elapsed())
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The value of `key=` in the self-test's report line.
fn report_value(report: &str, key: &str) -> Option<u64> {
    report
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('=')?.parse().ok())
}

#[test]
fn emulated_firmware_boots_runs_its_self_test_and_exits_zero() {
    if !qemu_available() {
        return;
    }
    let (out, _) = boot(&["selftest", "ticks=500"], 60);
    let log = text(&out);
    assert_eq!(
        out.status.code(),
        Some(0),
        "self-test should exit 0:\n{log}"
    );
    let report = log
        .lines()
        .find(|l| l.starts_with("selftest:"))
        .unwrap_or_else(|| panic!("no report line:\n{log}"));
    assert_eq!(report_value(report, "ticks"), Some(500), "{report}");
    // Every tick's cost was measured: a control tick cannot take zero instructions.
    let max = report_value(report, "max_tick_instructions").unwrap_or_else(|| panic!("{report}"));
    assert!(max > 0, "{report}");
}

#[test]
fn emulated_firmware_reports_an_injected_fault_in_its_exit_status() {
    if !qemu_available() {
        return;
    }
    // The synthetic encoder jumps by more than is physically possible in one tick: the core
    // latches an encoder fault, force goes to zero, and the firmware exits non-zero.
    let (out, _) = boot(&["selftest", "ticks=500", "inject=encoder-jump"], 60);
    let log = text(&out);
    let code = out.status.code();
    assert!(
        code.is_some_and(|c| c >= 16 && c != 124),
        "expected a fault exit status, got {code:?}:\n{log}"
    );
}

#[test]
fn a_hung_emulated_firmware_is_killed_within_seconds() {
    if !qemu_available() {
        return;
    }
    let (out, elapsed) = boot(&["hang"], 2);
    assert_eq!(
        out.status.code(),
        Some(124),
        "timeout(1) reports 124:\n{}",
        text(&out)
    );
    assert!(elapsed < Duration::from_secs(10), "took {elapsed:?}");
}

/// The host end of one lockstep session over the semihosting FIFOs (the contract in
/// `firmware/src/app_qemu.rs`).
struct Session {
    child: std::process::Child,
    to_firmware: Option<std::fs::File>,
    from_firmware: std::fs::File,
    decoder: sandjumper_core::FrameDecoder,
    pending: std::collections::VecDeque<u8>,
}

impl Session {
    /// `uart`: the CMSDK UART variant through QEMU's `-serial pipe:` (PATH.in / PATH.out);
    /// otherwise the semihosting FIFOs.
    fn start(name: &str, uart: bool) -> Self {
        let dir = workspace()
            .join(FIRMWARE_TARGET_DIR)
            .join(format!("session-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("session directory");
        let (input, output) = if uart {
            (dir.join("uart.in"), dir.join("uart.out"))
        } else {
            (dir.join("sensor.fifo"), dir.join("actuator.fifo"))
        };
        let made = Command::new("mkfifo")
            .arg(&input)
            .arg(&output)
            .status()
            .expect("running mkfifo");
        assert!(made.success(), "mkfifo failed");
        let mut qemu = Command::new(workspace().join("firmware/qemu-run.sh"));
        qemu.arg(firmware_elf())
            .env("SANDJUMPER_QEMU_TIMEOUT", "60");
        if uart {
            qemu.arg("uart").env(
                "SANDJUMPER_QEMU_SERIAL",
                format!("pipe:{}", dir.join("uart").display()),
            );
        } else {
            qemu.arg("fifo").arg(&input).arg(&output);
        }
        let child = qemu.spawn().expect("starting firmware/qemu-run.sh");
        // The firmware opens the sensor FIFO first, then the actuator FIFO: same order here.
        let to_firmware = std::fs::OpenOptions::new()
            .write(true)
            .open(&input)
            .expect("open sensor FIFO");
        let from_firmware = std::fs::File::open(&output).expect("open actuator FIFO");
        Self {
            child,
            to_firmware: Some(to_firmware),
            from_firmware,
            decoder: Default::default(),
            pending: Default::default(),
        }
    }

    fn send(&mut self, msg: &sandjumper_core::HostMessage) {
        use std::io::Write;
        let frame = sandjumper_core::protocol::encode_frame_vec(msg).expect("encodable");
        self.to_firmware
            .as_mut()
            .expect("open")
            .write_all(&frame)
            .expect("write to the firmware");
    }

    /// The next message, or `None` at end of file.
    fn next(&mut self) -> Option<sandjumper_core::RigMessage> {
        use std::io::Read;
        loop {
            while let Some(byte) = self.pending.pop_front() {
                if let Some(decoded) = self.decoder.push::<sandjumper_core::RigMessage>(byte) {
                    return Some(decoded.expect("the firmware sends valid frames"));
                }
            }
            let mut buf = [0u8; 4096];
            let n = self
                .from_firmware
                .read(&mut buf)
                .expect("read from the firmware");
            if n == 0 {
                return None;
            }
            self.pending.extend(&buf[..n]);
        }
    }
}

#[test]
fn a_lockstep_session_over_fifos_answers_every_sensor_frame_and_ends_cleanly() {
    use sandjumper_core::config::TrajectorySpec;
    use sandjumper_core::{
        Command, HostMessage, JumpConfig, JumpKind, Reply, RigMessage, RigState, SensorFrame,
        SineJump,
    };
    if !qemu_available() {
        return;
    }
    let mut s = Session::start("clean", false);
    let Some(RigMessage::Status(hello)) = s.next() else {
        panic!("the firmware greets with its status")
    };
    assert_eq!(hello.state, RigState::Idle);

    let (kind, amplitude_m, freq_hz, tau_s) = (JumpKind::Single, 0.01875, 10.0, 0.0);
    let spec = TrajectorySpec::Sine {
        kind,
        amplitude_m,
        freq_hz,
        tau_s,
    };
    let commands = [
        Command::Configure(JumpConfig::new(spec)),
        Command::Arm,
        Command::Start,
    ];
    for (id, command) in (1..).zip(commands) {
        s.send(&HostMessage::Command { id, command });
        assert_eq!(
            s.next(),
            Some(RigMessage::Reply {
                id,
                result: Ok(Reply::Ack)
            })
        );
    }
    // The plant tracks the commanded position exactly (1 um per count).
    let sine = SineJump::new(kind, amplitude_m, freq_hz, tau_s).expect("valid jump");
    let ticks = 1500u32; // 0.1 s jump + 0.05 s holding the end
    let mut samples = Vec::new();
    for frame in 0..ticks {
        let p = sine.eval(f64::from(frame) / 10_000.0).position_m;
        let encoder_count = (p * 1e6).round() as i32 as u32;
        s.send(&HostMessage::Sensor(SensorFrame {
            frame,
            encoder_count,
            current_a: None,
            overrun: false,
            bed: None,
        }));
        loop {
            match s.next() {
                Some(RigMessage::Actuator(a)) => {
                    assert_eq!(a.frame, frame);
                    assert_eq!(a.fault, None, "frame {frame}");
                    assert!(a.drive_enabled);
                    break;
                }
                Some(RigMessage::Samples(batch)) => samples.extend(batch.iter().map(|r| r.seq)),
                other => panic!("unexpected {other:?} before actuator frame {frame}"),
            }
        }
    }
    s.to_firmware = None; // EOF: end of session
    let mut last_status = None;
    while let Some(msg) = s.next() {
        match msg {
            RigMessage::Samples(batch) => samples.extend(batch.iter().map(|r| r.seq)),
            RigMessage::Status(status) => last_status = Some(status),
            other => panic!("unexpected {other:?} after the end"),
        }
    }
    let status = last_status.expect("a final status");
    assert_eq!(status.state, RigState::Done);
    assert_eq!(status.counters.samples_dropped, 0);
    assert_eq!(status.counters.lockstep_frames_lost, 0);
    assert!(
        status.counters.max_tick_cycles > 0,
        "the tick cost is measured"
    );
    // Every tick's record arrived, in order (the armed ticks before Start produce none here).
    assert_eq!(
        samples,
        (0..status.counters.samples_produced).collect::<Vec<_>>()
    );
    assert_eq!(samples.len(), ticks as usize);
    assert_eq!(s.child.wait().expect("QEMU exits").code(), Some(0));
}

#[test]
fn closing_the_link_mid_jump_latches_link_lost_and_exits_with_its_code() {
    use sandjumper_core::config::TrajectorySpec;
    use sandjumper_core::protocol::FaultReport;
    use sandjumper_core::{
        Command, FaultCode, HostMessage, JumpConfig, JumpKind, RigMessage, SensorFrame,
    };
    if !qemu_available() {
        return;
    }
    let mut s = Session::start("lost", false);
    assert!(matches!(s.next(), Some(RigMessage::Status(_))));
    let spec = TrajectorySpec::Sine {
        kind: JumpKind::Single,
        amplitude_m: 0.01875,
        freq_hz: 10.0,
        tau_s: 0.0,
    };
    for (id, command) in (1..).zip([Command::Configure(JumpConfig::new(spec)), Command::Arm]) {
        s.send(&HostMessage::Command { id, command });
        assert!(matches!(
            s.next(),
            Some(RigMessage::Reply { result: Ok(_), .. })
        ));
    }
    // Armed at the start position (-A for a single jump), then the host goes away.
    let encoder_count = (-0.01875e6f64).round() as i32 as u32;
    s.send(&HostMessage::Sensor(SensorFrame {
        frame: 0,
        encoder_count,
        current_a: None,
        overrun: false,
        bed: None,
    }));
    assert!(matches!(s.next(), Some(RigMessage::Actuator(a)) if a.fault.is_none()));
    s.to_firmware = None;
    let rest: Vec<RigMessage> = std::iter::from_fn(|| s.next()).collect();
    assert!(
        rest.iter().any(|m| matches!(
            m,
            RigMessage::Fault(FaultReport {
                code: FaultCode::LinkLost,
                ..
            })
        )),
        "{rest:?}"
    );
    assert_eq!(s.child.wait().expect("QEMU exits").code(), Some(16 + 8));
}

#[test]
fn the_uart_variant_speaks_the_same_protocol() {
    use sandjumper_core::{Command, HostMessage, Reply, RigMessage, RigState};
    if !qemu_available() {
        return;
    }
    let mut s = Session::start("uart", true);
    assert!(matches!(s.next(), Some(RigMessage::Status(st)) if st.state == RigState::Idle));
    s.send(&HostMessage::Command {
        id: 9,
        command: Command::StatusQuery,
    });
    assert!(matches!(
        s.next(),
        Some(RigMessage::Reply { id: 9, result: Ok(Reply::Status(st)) }) if st.counters.frames_ok == 1
    ));
    // A UART has no end of file: the host stops the emulator (SIGTERM reaches QEMU through
    // timeout(1); QEMU then exits 0, so over the UART the final StatusQuery is the verdict).
    let stopped = std::process::Command::new("kill")
        .arg(s.child.id().to_string())
        .status()
        .expect("kill");
    assert!(stopped.success());
    assert!(s.child.wait().expect("QEMU exits").code().is_some());
}
