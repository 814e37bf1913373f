//! The free-running (`--port PATH`) code path of `sandjumper rig`, against a stand-in board: a
//! thread that runs the core's `Rig` on its own clock (10 ticks per millisecond, as the F407's
//! timer does), answers commands and streams sample batches over the same COBS frames, with an
//! ideal drive (the encoder reads the commanded position). What can fail: the session's
//! command sequence, the watchdog being fed by the status polling, sample collection across
//! batches, and the end of the run.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use sandjumper_core::protocol::{SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_core::{
    FrameDecoder, HostMessage, Rig, RigConfig, RigMessage, TickInput, TickTiming,
};
use sandjumper_model::ModelName;
use sandjumper_model::params::Params;
use sandjumper_rig::hil::framed::FramedLink;
use sandjumper_rig::hil::run::{HilSpec, jump_config};
use sandjumper_rig::tool::session::{Program, run_program};

fn send(stream: &mut UnixStream, msg: &RigMessage) -> bool {
    let frame = encode_frame_vec(msg).expect("encodes");
    stream.write_all(&frame).is_ok()
}

/// The stand-in board with its motor at `start_counts` (where the operator left it: the
/// trajectory's start): runs until the host closes its end.
fn board(mut stream: UnixStream, start_counts: i64) -> u32 {
    let mut rig: Rig = Rig::new(RigConfig::default()).unwrap();
    let mut decoder = FrameDecoder::new();
    stream
        .set_read_timeout(Some(Duration::from_millis(1)))
        .unwrap();
    let mut buf = [0u8; 4096];
    let mut encoder_counts = start_counts;
    let mut batch = heapless::Vec::<_, SAMPLE_BATCH>::new();
    let started = Instant::now();
    let mut ticks: u64 = 0;
    loop {
        match stream.read(&mut buf) {
            Ok(0) => return rig.status().counters.samples_dropped,
            Ok(n) => {
                for &b in &buf[..n] {
                    if let Some(Ok(HostMessage::Command { id, command })) =
                        decoder.push::<HostMessage>(b)
                    {
                        rig.note_frame_ok();
                        let result = rig.handle(&command).map_err(|e| (&e).into());
                        if !send(&mut stream, &RigMessage::Reply { id, result }) {
                            return 0;
                        }
                    }
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return 0,
        }
        // Real time: 10 kHz.
        let due = started.elapsed().as_micros() as u64 / 100;
        while ticks < due {
            ticks += 1;
            rig.tick(&TickInput {
                encoder_raw: encoder_counts as i32 as u32,
                current_a: None,
                timing: TickTiming::Unknown,
            });
            while let Some(r) = rig.samples().pop() {
                if rig.state().drive_enabled() {
                    encoder_counts = (f64::from(r.commanded_position_m) * 1e6).round() as i64;
                }
                // Never fails: a full batch is sent at once.
                let _ = batch.push(r);
                if batch.is_full()
                    && !send(
                        &mut stream,
                        &RigMessage::Samples(std::mem::take(&mut batch)),
                    )
                {
                    return 0;
                }
            }
        }
    }
}

#[test]
fn a_free_running_board_runs_the_jump_and_streams_every_sample() {
    let (host, device) = UnixStream::pair().unwrap();
    let board = std::thread::spawn(move || board(device, -18_750));
    let reader = host.try_clone().unwrap();
    let closer = host.try_clone().unwrap();
    let mut link = FramedLink::start(
        "board",
        Box::new(reader),
        Box::new(host),
        None,
        Duration::from_secs(2),
    )
    .expect("the board answers");
    let params = Params::preset(0.57).unwrap();
    let spec = HilSpec::new(JumpKind::Single, 10.0, 0.0, ModelName::Hard);
    let program = Program {
        config: jump_config(&params, &spec),
        tick_hz: 10_000,
        settle_s: 0.2,
        tail_s: 0.1,
        max_run_s: 5.0,
    };
    let record = run_program(&mut link, None, &program).expect("the run completes");
    // Unplug: the board sees the end of its stream.
    closer.shutdown(std::net::Shutdown::Both).unwrap();
    drop(link);
    assert!(record.completed, "the board reported Done");
    assert!(
        record.faults.is_empty(),
        "no fault (the polling fed the watchdog): {:?}",
        record.faults
    );
    let seqs: Vec<u32> = record.samples.iter().map(|s| s.seq).collect();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "no sample lost between batches"
    );
    // Armed 0.2 s, the 0.1 s trajectory, 0.1 s after Done: at least 4000 ticks recorded.
    assert!(seqs.len() > 3500, "{} samples", seqs.len());
    let running = record
        .samples
        .iter()
        .filter(|s| s.flags & sandjumper_core::sample::flags::RUNNING != 0)
        .count();
    assert!(
        (990..=1010).contains(&running),
        "{running} ticks of a 0.1 s trajectory"
    );
    assert_eq!(board.join().unwrap(), 0, "the board dropped no sample");
}
