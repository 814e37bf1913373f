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
//!
//! A board that runs in virtual time (the virtual F407, as fast as the machine lets it) gives
//! the link its clock ([`BoardClock`]): the timeout is then counted in the board's time, so a
//! busy machine that slows the board down does not fail the run, and a board whose clock
//! stands still for the timeout in wall time is reported as hung.

use std::io::{Read, Write};
use std::process::Child;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::link::{LinkError, LinkReport, RigLink, corrupted_sensor_frame, reply_or_rejected};
use sandjumper_core::protocol::{FaultReport, PROTOCOL_VERSION, encode_frame_vec};
use sandjumper_core::{
    ActuatorFrame, Command, FrameDecoder, FrameError, HostMessage, Reply, RigMessage, SampleRecord,
    SensorFrame, Status,
};

/// The board's own clock as the host reads it (a virtual board's virtual time since its
/// start); `None` while it cannot be read (not written yet).
pub type BoardClock = Arc<dyn Fn() -> Option<Duration> + Send + Sync>;

/// How often a wait reads the board's clock, wall time.
const CLOCK_READ_INTERVAL: Duration = Duration::from_millis(20);

/// How long one wait has lasted: in the board's time when there is a [`BoardClock`], else in
/// wall time.
struct Patience {
    clock: Option<BoardClock>,
    limit: Duration,
    /// Wall time the wait started.
    wall_start: Instant,
    /// The board's time at the first reading, and at the last.
    board_start: Option<Duration>,
    board_last: Option<Duration>,
    /// Wall time the board's clock last moved (or the wait started).
    moved_at: Instant,
    /// Wall time of the next reading.
    next_read: Instant,
}

/// Where a wait stands.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Waited {
    /// Not over: block at most this long (wall) before asking again.
    For(Duration),
    /// The limit has passed (in the board's time, with a clock).
    Elapsed,
    /// The board's clock stood still for the limit in wall time (where it stood, if read).
    Stalled(Option<Duration>),
}

impl Patience {
    fn new(clock: Option<BoardClock>, limit: Duration) -> Self {
        let now = Instant::now();
        let at = clock.as_ref().and_then(|c| c());
        Self {
            clock,
            limit,
            wall_start: now,
            board_start: at,
            board_last: at,
            moved_at: now,
            next_read: now + CLOCK_READ_INTERVAL,
        }
    }

    fn check(&mut self) -> Waited {
        let now = Instant::now();
        let Some(clock) = &self.clock else {
            let left = (self.wall_start + self.limit).saturating_duration_since(now);
            return if left.is_zero() {
                Waited::Elapsed
            } else {
                Waited::For(left)
            };
        };
        if now >= self.next_read {
            self.next_read = now + CLOCK_READ_INTERVAL;
            if let Some(at) = clock() {
                if self.board_last.is_none_or(|last| at > last) {
                    self.board_last = Some(at);
                    self.moved_at = now;
                }
                let start = *self.board_start.get_or_insert(at);
                if at.saturating_sub(start) >= self.limit {
                    return Waited::Elapsed;
                }
            }
        }
        let still = now.saturating_duration_since(self.moved_at);
        if still >= self.limit {
            return Waited::Stalled(self.board_last);
        }
        Waited::For(
            self.next_read
                .saturating_duration_since(now)
                .min(self.limit - still),
        )
    }

    /// The error of a wait for `waiting_for` that ended as `why` ([`Waited::Elapsed`] or
    /// [`Waited::Stalled`]).
    fn error(&self, waiting_for: &str, why: Waited) -> LinkError {
        let seconds = self.limit.as_secs_f64();
        match (why, self.clock.is_some()) {
            (Waited::Stalled(at), _) => LinkError::Io {
                what: format!("no answer to {waiting_for}"),
                message: match at {
                    Some(t) => format!(
                        "the board's virtual time stood still at {:.3} s for {seconds} s of \
                         wall time (the virtual board hung?)",
                        t.as_secs_f64()
                    ),
                    None => format!(
                        "the board's virtual time could not be read for {seconds} s of wall \
                         time (the virtual board hung?)"
                    ),
                },
            },
            (_, true) => LinkError::Timeout {
                waiting_for: format!("{waiting_for} in the board's virtual time"),
                seconds,
            },
            (_, false) => LinkError::Timeout {
                waiting_for: waiting_for.into(),
                seconds,
            },
        }
    }
}

/// What the reader thread passes on.
enum Incoming {
    Message(Box<RigMessage>),
    Rejected,
    /// A whole frame of another protocol version (its version byte).
    OtherVersion(u8),
}

/// The refusal of a board that speaks protocol version `got`.
pub fn other_version(got: u8) -> LinkError {
    LinkError::Protocol(format!(
        "the board speaks protocol version {got}, this host speaks {PROTOCOL_VERSION}: flash the \
         firmware built from this checkout (`cargo build -p sandjumper-firmware --target \
         thumbv7em-none-eabihf --release`, then `sandjumper rig flash`), or use the host tools \
         of the board's version"
    ))
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

    /// Wait for the child to exit, `timeout` counted as [`Patience`] counts it (in the board's
    /// time with a `clock`); kill it when it does not.
    fn wait(&mut self, clock: Option<BoardClock>, timeout: Duration) -> Result<i32, LinkError> {
        let mut patience = Patience::new(clock, timeout);
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return Ok(status.code().unwrap_or(-1)),
                Ok(None) => match patience.check() {
                    Waited::For(d) => std::thread::sleep(d.min(Duration::from_millis(5))),
                    over => {
                        let _ = self.child.kill();
                        let _ = self.child.wait();
                        return Err(patience.error(&format!("{} to exit", self.what), over));
                    }
                },
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
    /// How long to wait for any answer before declaring the controller hung: in the board's
    /// time when the link has its [`BoardClock`], else wall time.
    pub answer_timeout: Duration,
    /// The board's clock, if the host can read it (a virtual board).
    clock: Option<BoardClock>,
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
        Self::start_clocked(name, reader, writer, child, answer_timeout, None)
    }

    /// [`FramedLink::start`] with the board's `clock` (if any): every wait, this first one
    /// included, counts `answer_timeout` in the board's time, and fails as hung when the clock
    /// stands still for `answer_timeout` of wall time.
    pub fn start_clocked(
        name: impl Into<String>,
        reader: Box<dyn Read + Send>,
        writer: Box<dyn Write + Send>,
        child: Option<ChildGuard>,
        answer_timeout: Duration,
        clock: Option<BoardClock>,
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
                        Some(Err(FrameError::Version { got })) => Incoming::OtherVersion(got),
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
            clock,
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
        let mut patience = Patience::new(self.clock.clone(), self.answer_timeout);
        loop {
            // What has already arrived first: a host starved of CPU time must not declare a
            // timeout with the answer waiting in the queue.
            let queued = match self.incoming.try_recv() {
                Ok(item) => Some(item),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => {
                    return Err(LinkError::Closed {
                        waiting_for: waiting_for.into(),
                    });
                }
            };
            let item = match queued {
                Some(item) => item,
                None => {
                    let left = match patience.check() {
                        Waited::For(left) => left,
                        over => return Err(patience.error(waiting_for, over)),
                    };
                    match self.incoming.recv_timeout(left) {
                        Ok(item) => item,
                        Err(RecvTimeoutError::Timeout) => continue,
                        Err(RecvTimeoutError::Disconnected) => {
                            return Err(LinkError::Closed {
                                waiting_for: waiting_for.into(),
                            });
                        }
                    }
                }
            };
            match item {
                Incoming::Rejected => self.host_frames_rejected += 1,
                Incoming::OtherVersion(got) => return Err(other_version(got)),
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
        let mut patience = Patience::new(self.clock.clone(), self.answer_timeout);
        loop {
            let left = match patience.check() {
                Waited::For(left) => left,
                over if self.child.is_some() => {
                    return Err(patience.error("the firmware to end the session", over));
                }
                _ => break, // a real board stays connected
            };
            match self.incoming.recv_timeout(left) {
                Ok(Incoming::Message(m)) => self.absorb(*m),
                Ok(Incoming::Rejected | Incoming::OtherVersion(_)) => {
                    self.host_frames_rejected += 1
                }
                Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
        if let Some(h) = self.reader.take()
            && self.child.is_some()
        {
            let _ = h.join();
        }
        let exit_code = match self.child.as_mut() {
            Some(c) => Some(c.wait(self.clock.clone(), self.answer_timeout)?),
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::{Sender, channel};

    /// The reading end of an in-memory pipe.
    struct PipeIn {
        rx: Receiver<Vec<u8>>,
        left: Vec<u8>,
    }

    impl Read for PipeIn {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.left.is_empty() {
                match self.rx.recv() {
                    Ok(bytes) => self.left = bytes,
                    Err(_) => return Ok(0),
                }
            }
            let n = buf.len().min(self.left.len());
            buf[..n].copy_from_slice(&self.left[..n]);
            self.left.drain(..n);
            Ok(n)
        }
    }

    /// The writing end.
    struct PipeOut(Sender<Vec<u8>>);

    impl Write for PipeOut {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0
                .send(buf.to_vec())
                .map_err(|_| std::io::Error::from(std::io::ErrorKind::BrokenPipe))?;
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// A board that answers every command `delay` of wall time after it arrives (never, for
    /// `None`) and closes its end when the host closes its own: the host's ends of the link.
    fn board(delay: Option<Duration>) -> (Box<dyn Read + Send>, Box<dyn Write + Send>) {
        let (to_board, from_host) = channel::<Vec<u8>>();
        let (to_host, from_board) = channel::<Vec<u8>>();
        std::thread::spawn(move || {
            let mut decoder = FrameDecoder::new();
            while let Ok(bytes) = from_host.recv() {
                for b in bytes {
                    let Some(Ok(HostMessage::Command { id, .. })) = decoder.push::<HostMessage>(b)
                    else {
                        continue;
                    };
                    let Some(delay) = delay else { continue };
                    std::thread::sleep(delay);
                    let reply = RigMessage::Reply {
                        id,
                        result: Ok(Reply::Ack),
                    };
                    let frame = encode_frame_vec(&reply).expect("encodes");
                    if to_host.send(frame.to_vec()).is_err() {
                        return;
                    }
                }
            }
        });
        (
            Box::new(PipeIn {
                rx: from_board,
                left: Vec::new(),
            }),
            Box::new(PipeOut(to_board)),
        )
    }

    /// A board clock running at `rate` x wall time from now.
    fn clock_at(rate: f64) -> BoardClock {
        let t0 = Instant::now();
        Arc::new(move || Some(t0.elapsed().mul_f64(rate)))
    }

    /// A board clock standing at 1 s.
    fn stopped_clock() -> BoardClock {
        Arc::new(|| Some(Duration::from_secs(1)))
    }

    fn start(delay: Option<Duration>, clock: Option<BoardClock>) -> Result<FramedLink, LinkError> {
        let (reader, writer) = board(delay);
        FramedLink::start_clocked(
            "test",
            reader,
            writer,
            None,
            Duration::from_millis(100),
            clock,
        )
    }

    #[test]
    fn a_slow_board_answers_within_the_timeout_counted_in_its_time() {
        // 300 ms of wall time per answer at 0.1x real time: 30 ms of the board's time, within
        // the 100 ms timeout.
        let mut link = start(Some(Duration::from_millis(300)), Some(clock_at(0.1)))
            .expect("the first answer comes in the board's time");
        link.command(&Command::Heartbeat).expect("and the next");
        // On the wall clock the same board is too slow.
        let e = start(Some(Duration::from_millis(300)), None)
            .err()
            .expect("too slow in wall time");
        assert!(matches!(e, LinkError::Timeout { .. }), "{e}");
        assert!(!e.to_string().contains("virtual"), "{e}");
    }

    #[test]
    fn a_board_whose_clock_stands_still_is_reported_hung() {
        let wall = Instant::now();
        let e = start(None, Some(stopped_clock()))
            .err()
            .expect("a stalled clock");
        let text = e.to_string();
        assert!(
            text.contains("no answer to command StatusQuery")
                && text.contains("the board's virtual time stood still at 1.000 s"),
            "{text}"
        );
        assert!(
            wall.elapsed() >= Duration::from_millis(100),
            "{:?}",
            wall.elapsed()
        );
        // A clock that cannot be read is no progress either.
        let e = start(None, Some(Arc::new(|| None)))
            .err()
            .expect("an unreadable clock");
        assert!(e.to_string().contains("could not be read"), "{e}");
    }

    #[test]
    fn no_answer_in_the_boards_time_is_a_timeout_in_virtual_time() {
        // A board at 10x real time: its 1 s passes in ~0.1 s of wall time.
        let (reader, writer) = board(None);
        let wall = Instant::now();
        let e = FramedLink::start_clocked(
            "test",
            reader,
            writer,
            None,
            Duration::from_secs(1),
            Some(clock_at(10.0)),
        )
        .err()
        .expect("no answer");
        assert!(
            matches!(&e, LinkError::Timeout { seconds, .. } if *seconds == 1.0),
            "{e}"
        );
        assert!(e.to_string().contains("in the board's virtual time"), "{e}");
        assert!(
            wall.elapsed() < Duration::from_millis(900),
            "{:?}",
            wall.elapsed()
        );
    }

    #[cfg(unix)]
    #[test]
    fn the_childs_exit_is_awaited_in_the_boards_time() {
        let sleep = |s: &str| {
            std::process::Command::new("sleep")
                .arg(s)
                .spawn()
                .expect("sleep runs")
        };
        // 0.3 s of wall time at 0.1x: 30 ms of the board's time, within 100 ms.
        let mut child = ChildGuard::new(sleep("0.3"), "the test child");
        assert_eq!(
            child.wait(Some(clock_at(0.1)), Duration::from_millis(100)),
            Ok(0)
        );
        // A child whose clock stands still is killed as hung.
        let mut child = ChildGuard::new(sleep("10"), "the test child");
        let wall = Instant::now();
        let e = child
            .wait(Some(stopped_clock()), Duration::from_millis(100))
            .expect_err("hung");
        assert!(
            e.to_string()
                .contains("no answer to the test child to exit")
                && e.to_string().contains("stood still"),
            "{e}"
        );
        assert!(wall.elapsed() < Duration::from_secs(5));
        assert!(matches!(child.child.try_wait(), Ok(Some(_))), "killed");
    }

    #[cfg(unix)]
    #[test]
    fn a_slow_board_finishes_its_session_in_its_time() {
        // The board program exits 0.3 s of wall time after the host closes its end.
        let (reader, writer) = board(Some(Duration::ZERO));
        let child = std::process::Command::new("sleep")
            .arg("0.3")
            .spawn()
            .expect("sleep runs");
        let mut link = FramedLink::start_clocked(
            "test",
            reader,
            writer,
            Some(ChildGuard::new(child, "the test child")),
            Duration::from_millis(100),
            Some(clock_at(0.1)),
        )
        .expect("answers");
        let report = link.finish().expect("the session ends in the board's time");
        assert_eq!(report.exit_code, Some(0));
    }

    /// Issue 48: a board of another protocol version (firmware flashed from another checkout)
    /// is refused at the first answer, with a message that says which version it speaks and
    /// what to do, not a timeout.
    #[test]
    fn a_board_of_another_protocol_version_is_refused_with_a_clear_message() {
        let (to_host, from_board) = channel::<Vec<u8>>();
        let (to_board, _from_host) = channel::<Vec<u8>>();
        // The board announces itself in protocol version 3: a frame whose version byte is 3.
        let mut frame = encode_frame_vec(&RigMessage::Reply {
            id: 1,
            result: Ok(Reply::Ack),
        })
        .expect("encodes")
        .to_vec();
        frame.pop(); // the delimiter
        let mut body = vec![0u8; frame.len()];
        let n = cobs::decode(&frame, &mut body).expect("COBS").frame_size();
        body.truncate(n);
        body[0] = 3;
        let crc_at = body.len() - 4;
        let crc = sandjumper_core::replay::CRC32.checksum(&body[..crc_at]);
        body[crc_at..].copy_from_slice(&crc.to_le_bytes());
        let mut old = vec![0u8; body.len() + body.len() / 254 + 2];
        let m = cobs::encode(&body, &mut old);
        old.truncate(m);
        old.push(0);
        to_host.send(old).expect("sent");
        let err = FramedLink::start(
            "old board",
            Box::new(PipeIn {
                rx: from_board,
                left: Vec::new(),
            }),
            Box::new(PipeOut(to_board)),
            None,
            Duration::from_secs(5),
        )
        .err()
        .expect("refused");
        let text = err.to_string();
        assert!(
            text.contains("protocol version 3")
                && text.contains(&format!("speaks {PROTOCOL_VERSION}")),
            "{text}"
        );
        assert!(
            text.contains("flash the firmware built from this checkout"),
            "{text}"
        );
    }
}
