//! The host end of the firmware's session protocol over any byte stream (`firmware/src/
//! app_qemu.rs`; the same frames on the F407's USB CDC link):
//!
//! 1. The firmware announces itself with `RigMessage::Status`.
//! 2. The host sends `HostMessage::Command { id, .. }` (answered by `Reply` with that id) and
//!    `HostMessage::Sensor(..)` (answered by `Actuator` for that frame number); sample batches
//!    and fault reports arrive before the actuator frame.
//! 3. The host closes its end; the firmware flushes its samples and a final `Status` (its
//!    counters hold the longest tick) and, under QEMU, exits with its status.
//!
//! A reader thread decodes the incoming bytes (the core's [`FrameDecoder`]) into a channel; the
//! host waits on it with a timeout, so a hung controller fails the run within
//! [`FramedLink::answer_timeout`] instead of hanging it.

use std::io::{Read, Write};
use std::process::Child;
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::link::{LinkError, LinkReport, RigLink, corrupted_sensor_frame, reply_or_rejected};
use sandjumper_core::protocol::{FaultReport, encode_frame_vec};
use sandjumper_core::{
    ActuatorFrame, Command, FrameDecoder, HostMessage, Reply, RigMessage, SampleRecord,
    SensorFrame, Status,
};

/// What the reader thread passes on.
enum Incoming {
    Message(Box<RigMessage>),
    Rejected,
}

/// A child process behind the link (QEMU), reaped on [`RigLink::finish`] or drop.
pub struct ChildGuard {
    child: Child,
    what: String,
}

impl ChildGuard {
    /// Watch `child`, described as `what` in errors.
    pub fn new(child: Child, what: impl Into<String>) -> Self {
        Self {
            child,
            what: what.into(),
        }
    }

    fn wait(&mut self, timeout: Duration) -> Result<i32, LinkError> {
        let deadline = Instant::now() + timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return Ok(status.code().unwrap_or(-1)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(5))
                }
                Ok(None) => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    return Err(LinkError::Timeout {
                        waiting_for: format!("{} to exit", self.what),
                        seconds: timeout.as_secs_f64(),
                    });
                }
                Err(e) => {
                    return Err(LinkError::Io {
                        what: format!("waiting for {}", self.what),
                        message: e.to_string(),
                    });
                }
            }
        }
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The session protocol over a byte stream.
pub struct FramedLink {
    name: String,
    writer: Option<Box<dyn Write + Send>>,
    incoming: Receiver<Incoming>,
    reader: Option<JoinHandle<()>>,
    child: Option<ChildGuard>,
    next_id: u16,
    samples: Vec<SampleRecord>,
    faults: Vec<FaultReport>,
    last_status: Option<Status>,
    host_frames_rejected: u32,
    /// How long to wait for any answer before declaring the controller hung.
    pub answer_timeout: Duration,
    out: Vec<u8>,
    kept: Vec<Box<dyn std::any::Any + Send>>,
}

impl FramedLink {
    /// Start a session over `reader`/`writer` (a child process behind it, if any) and wait for
    /// the controller's answer to a status query.
    pub fn start(
        name: impl Into<String>,
        reader: Box<dyn Read + Send>,
        writer: Box<dyn Write + Send>,
        child: Option<ChildGuard>,
        answer_timeout: Duration,
    ) -> Result<Self, LinkError> {
        let (tx, rx) = channel();
        let handle = std::thread::spawn(move || {
            let mut reader = reader;
            let mut decoder = FrameDecoder::new();
            let mut buf = [0u8; 4096];
            loop {
                let n = match reader.read(&mut buf) {
                    Ok(0) => return,
                    Ok(n) => n,
                    Err(e)
                        if e.kind() == std::io::ErrorKind::TimedOut
                            || e.kind() == std::io::ErrorKind::Interrupted =>
                    {
                        continue;
                    }
                    Err(_) => return,
                };
                for &b in &buf[..n] {
                    let item = match decoder.push::<RigMessage>(b) {
                        None => continue,
                        Some(Ok(m)) => Incoming::Message(Box::new(m)),
                        Some(Err(_)) => Incoming::Rejected,
                    };
                    if tx.send(item).is_err() {
                        return;
                    }
                }
            }
        });
        let mut link = Self {
            name: name.into(),
            writer: Some(writer),
            incoming: rx,
            reader: Some(handle),
            child,
            next_id: 1,
            samples: Vec::new(),
            faults: Vec::new(),
            last_status: None,
            host_frames_rejected: 0,
            answer_timeout,
            out: Vec::with_capacity(64),
            kept: Vec::new(),
        };
        // The emulated firmware announces itself with a Status; a board that is already
        // running does not, so ask: either way the first reply proves the link works.
        link.command(&Command::StatusQuery)?;
        Ok(link)
    }

    /// Keep `thing` (e.g. the FIFOs' temporary directory) alive as long as the link.
    pub fn keep_alive(mut self, thing: impl std::any::Any + Send) -> Self {
        self.kept.push(Box::new(thing));
        self
    }

    fn send(&mut self, msg: &HostMessage) -> Result<(), LinkError> {
        let frame = encode_frame_vec(msg)
            .map_err(|e| LinkError::Protocol(format!("cannot encode {msg:?}: {e}")))?;
        self.out.clear();
        self.out.extend_from_slice(&frame);
        self.write_out()
    }

    fn write_out(&mut self) -> Result<(), LinkError> {
        let Some(w) = self.writer.as_mut() else {
            return Err(LinkError::Closed {
                waiting_for: "a write".into(),
            });
        };
        w.write_all(&self.out)
            .and_then(|()| w.flush())
            .map_err(|e| LinkError::Io {
                what: format!("writing to {}", self.name),
                message: e.to_string(),
            })
    }

    /// Handle telemetry; return what `want` picks out of the first message it accepts.
    fn wait_for<T>(
        &mut self,
        waiting_for: &str,
        mut want: impl FnMut(&RigMessage) -> Option<T>,
    ) -> Result<T, LinkError> {
        let deadline = Instant::now() + self.answer_timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let item = match self.incoming.recv_timeout(left) {
                Ok(item) => item,
                Err(RecvTimeoutError::Timeout) => {
                    return Err(LinkError::Timeout {
                        waiting_for: waiting_for.into(),
                        seconds: self.answer_timeout.as_secs_f64(),
                    });
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(LinkError::Closed {
                        waiting_for: waiting_for.into(),
                    });
                }
            };
            match item {
                Incoming::Rejected => self.host_frames_rejected += 1,
                Incoming::Message(m) => {
                    if let Some(t) = want(&m) {
                        return Ok(t);
                    }
                    self.absorb(*m);
                }
            }
        }
    }

    fn absorb(&mut self, m: RigMessage) {
        match m {
            RigMessage::Samples(batch) => self.samples.extend(batch.iter().copied()),
            RigMessage::Fault(f) => self.faults.push(f),
            RigMessage::Status(s) => self.last_status = Some(s),
            RigMessage::Reply { .. } | RigMessage::Actuator(_) => {}
        }
    }
}

impl RigLink for FramedLink {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn command(&mut self, command: &Command) -> Result<Reply, LinkError> {
        let id = self.next_id;
        self.next_id = self.next_id.wrapping_add(1);
        self.send(&HostMessage::Command {
            id,
            command: command.clone(),
        })?;
        let result = self.wait_for(
            &format!("command {:?} (id {id})", command.kind()),
            |m| match m {
                RigMessage::Reply { id: got, result } if *got == id => Some(*result),
                _ => None,
            },
        )?;
        reply_or_rejected(command, result)
    }

    fn exchange(&mut self, frame: &SensorFrame) -> Result<ActuatorFrame, LinkError> {
        self.send(&HostMessage::Sensor(*frame))?;
        let want = frame.frame;
        self.wait_for("an actuator frame", |m| match m {
            RigMessage::Actuator(a) if a.frame == want => Some(*a),
            _ => None,
        })
    }

    fn send_corrupted(&mut self, frame: &SensorFrame) -> Result<(), LinkError> {
        self.out = corrupted_sensor_frame(frame);
        self.write_out()
    }

    fn silent_period(&mut self) -> Result<Option<ActuatorFrame>, LinkError> {
        // The firmware ticks only on frames: silence is seen as the end of the stream. Close
        // our end; the firmware latches LinkLost (if a run was going) and reports it.
        if self.writer.is_none() {
            return Ok(None);
        }
        self.writer = None;
        let report = self.wait_for("the link-lost fault report", |m| match m {
            RigMessage::Fault(f) => Some(*f),
            _ => None,
        })?;
        self.faults.push(report);
        Ok(Some(ActuatorFrame {
            frame: u32::MAX,
            force_n: 0.0,
            trigger: false,
            drive_enabled: false,
            camera_frame: None,
            state: sandjumper_core::RigState::Faulted,
            fault: Some(report.code),
            bed: sandjumper_core::bed::BedOutputs::default(),
        }))
    }

    fn take_samples(&mut self) -> Vec<SampleRecord> {
        std::mem::take(&mut self.samples)
    }

    fn take_faults(&mut self) -> Vec<FaultReport> {
        std::mem::take(&mut self.faults)
    }

    fn finish(&mut self) -> Result<LinkReport, LinkError> {
        self.writer = None;
        // Drain until the firmware closes its end.
        let deadline = Instant::now() + self.answer_timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.incoming.recv_timeout(left) {
                Ok(Incoming::Message(m)) => self.absorb(*m),
                Ok(Incoming::Rejected) => self.host_frames_rejected += 1,
                Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => {
                    if self.child.is_some() {
                        return Err(LinkError::Timeout {
                            waiting_for: "the firmware to end the session".into(),
                            seconds: self.answer_timeout.as_secs_f64(),
                        });
                    }
                    break; // a real board stays connected
                }
            }
        }
        if let Some(h) = self.reader.take()
            && self.child.is_some()
        {
            let _ = h.join();
        }
        let exit_code = match self.child.as_mut() {
            Some(c) => Some(c.wait(self.answer_timeout)?),
            None => None,
        };
        Ok(LinkReport {
            final_status: self.last_status,
            max_tick_instructions: self
                .last_status
                .map(|s| s.counters.max_tick_cycles)
                .filter(|_| exit_code.is_some()),
            exit_code,
            host_frames_rejected: self.host_frames_rejected,
            simulated_jump_height_m: None,
            board_realtime_factor: None,
        })
    }
}
