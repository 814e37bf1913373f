//! A campaign on a board (the `--port` code path), against a stand-in board: a thread that
//! runs the core's `Rig` on its own clock (10 ticks per millisecond), answers commands and
//! streams sample batches over the same COBS frames, with an ideal drive and a bed apparatus
//! in software (a lift that takes 50 ms between its limit switches, a bed that a running
//! blower resets to phi 0.57 and that the shaker compacts, a height sensor with a 16-bit
//! code). What can fail: the bed prepared through `Command::Bed` and `Status.bed`, the lift
//! lowered before `Arm` (the core's interlock), the free-running jump, the records.

use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

use sandjumper_cli::campaign::command::run_on_board;
use sandjumper_core::bed::BedInputs;
use sandjumper_core::protocol::{SAMPLE_BATCH, encode_frame_vec};
use sandjumper_core::{
    FrameDecoder, HostMessage, Rig, RigConfig, RigMessage, TickInput, TickTiming,
};
use sandjumper_imaging::render::CameraModel;
use sandjumper_rig::hil::CameraFrame;
use sandjumper_rig::hil::camera::write_frames;
use sandjumper_rig::hil::framed::FramedLink;
use sandjumper_rig::hil::link::RigLink;

/// The bed's constants (as in the campaign file below) and the sensor's calibration.
const MASS_KG: f64 = 39.19;
const RHO: f64 = 1100.0;
const AREA_M2: f64 = 0.25;
const M_PER_CODE: f64 = 2e-5;
const H0_M: f64 = 0.2;

/// The bed apparatus in software, advanced once per tick.
struct Bed {
    lift: f64, // 0: down, 1: up
    phi0: f64,
    dose: f64,
    blowing_s: f64,
    fluidizations: u32,
}

impl Bed {
    fn inputs(&self) -> BedInputs {
        // Each 20 ms dose adds at most 0.008 (under twice the tolerance): no overshoot loop.
        let phi = (self.phi0 + 0.02 * (1.0 + self.dose.max(0.0) / 0.05).ln()).min(0.625);
        let h = MASS_KG / (RHO * AREA_M2 * phi);
        BedInputs {
            lift_up_limit: self.lift >= 1.0,
            lift_down_limit: self.lift <= 0.0,
            emergency_stop: false,
            height_raw: ((h - H0_M) / M_PER_CODE).round() as u16,
        }
    }

    fn step(&mut self, out: &sandjumper_core::bed::BedOutputs, dt: f64) {
        if out.lift_enable {
            let dir = if out.lift_up { 1.0 } else { -1.0 };
            self.lift = (self.lift + dir * dt / 0.05).clamp(0.0, 1.0);
        }
        if out.blower_v > 5.0 {
            self.blowing_s += dt;
            if self.blowing_s >= 0.02 && self.dose >= 0.0 {
                // Fluidized: loose again (a little scatter from the count).
                self.phi0 = 0.57 + 0.001 * f64::from(self.fluidizations % 3);
                self.dose = -1.0; // marks "reset during this blow"
            }
        } else {
            if self.dose < 0.0 {
                self.dose = 0.0;
                self.fluidizations += 1;
            }
            self.blowing_s = 0.0;
        }
        if self.dose >= 0.0 {
            self.dose += f64::from(out.shaker_duty) * dt;
        }
    }
}

fn send(stream: &mut UnixStream, msg: &RigMessage) -> bool {
    let frame = encode_frame_vec(msg).expect("encodes");
    stream.write_all(&frame).is_ok()
}

/// What the board saw.
#[derive(Default)]
struct Seen {
    commands_rejected: AtomicU32,
    blower_on_ticks: AtomicU32,
    shaker_on_ticks: AtomicU32,
    arms_with_lift_down: AtomicU32,
}

/// The rod camera of the stand-in: during a session it notes each frame the controller
/// triggers and the rod's height, which leaves the rest height [`LIFT_OFF_S`] after the
/// trajectory starts and flies a free parabola to [`APEX_M`]; when the session ends it writes
/// the frames into the capture folder, as a lab's camera software would.
struct Camera {
    frames: Vec<CameraFrame>,
    heights: Vec<f64>,
    start_tick: Option<u64>,
}

/// The stand-in jump's apex above rest, m, and its lift-off after the start, s.
const APEX_M: f64 = 0.05;
const LIFT_OFF_S: f64 = 0.05;

impl Camera {
    fn note(&mut self, tick: u64, out: &sandjumper_core::rig::TickOutput) {
        if out.state == sandjumper_core::RigState::Running && self.start_tick.is_none() {
            self.start_tick = Some(tick);
        }
        let h = self.start_tick.map_or(0.0, |t0| {
            let tau = (tick - t0) as f64 * 1e-4 - LIFT_OFF_S;
            let v0 = (2.0 * 9.81 * APEX_M).sqrt();
            if tau > 0.0 {
                (v0 * tau - 0.5 * 9.81 * tau * tau).max(0.0)
            } else {
                0.0
            }
        });
        self.heights.push(h);
        if let Some(n) = out.camera_frame {
            self.frames.push(CameraFrame {
                frame: n,
                period: tick,
                t_s: tick as f64 * 1e-4,
                rod_height_m: h,
            });
        }
    }
}

/// Serve one connection until the host goes away; the rig and the bed persist; the jump's
/// frames go to `capture`.
fn serve(
    stream: UnixStream,
    rig: &mut Rig,
    bed: &mut Bed,
    encoder_counts: &mut i64,
    seen: &Seen,
    capture: &std::path::Path,
) {
    let mut camera = Camera {
        frames: Vec::new(),
        heights: Vec::new(),
        start_tick: None,
    };
    serve_link(stream, rig, bed, encoder_counts, seen, &mut camera);
    if !camera.frames.is_empty() {
        write_frames(
            &camera.frames,
            &camera.heights,
            &CameraModel::default(),
            1e-4,
            capture,
        )
        .unwrap();
        // The camera's own description stays with the lab's software.
        let _ = std::fs::remove_file(capture.join("camera.toml"));
    }
}

fn serve_link(
    mut stream: UnixStream,
    rig: &mut Rig,
    bed: &mut Bed,
    encoder_counts: &mut i64,
    seen: &Seen,
    camera: &mut Camera,
) {
    let mut decoder = FrameDecoder::new();
    stream
        .set_read_timeout(Some(Duration::from_millis(1)))
        .unwrap();
    let mut buf = [0u8; 4096];
    let mut batch = heapless::Vec::<_, SAMPLE_BATCH>::new();
    let started = Instant::now();
    let mut ticks: u64 = 0;
    loop {
        match stream.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => {
                for &b in &buf[..n] {
                    if let Some(Ok(HostMessage::Command { id, command })) =
                        decoder.push::<HostMessage>(b)
                    {
                        rig.note_frame_ok();
                        let result = rig.handle(&command);
                        if result.is_err() {
                            seen.commands_rejected.fetch_add(1, Ordering::Relaxed);
                        } else if command == sandjumper_core::Command::Arm
                            && rig.bed().inputs().lift_down_limit
                        {
                            seen.arms_with_lift_down.fetch_add(1, Ordering::Relaxed);
                        }
                        let result = result.map_err(|e| (&e).into());
                        if !send(&mut stream, &RigMessage::Reply { id, result }) {
                            return;
                        }
                    }
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return,
        }
        let due = started.elapsed().as_micros() as u64 / 100;
        while ticks < due {
            ticks += 1;
            rig.set_bed_inputs(bed.inputs());
            let out = rig.tick(&TickInput {
                encoder_raw: *encoder_counts as i32 as u32,
                current_a: None,
                timing: TickTiming::Unknown,
            });
            bed.step(&out.bed, 1e-4);
            camera.note(ticks - 1, &out);
            if out.bed.blower_v > 0.0 {
                seen.blower_on_ticks.fetch_add(1, Ordering::Relaxed);
            }
            if out.bed.shaker_duty > 0.0 {
                seen.shaker_on_ticks.fetch_add(1, Ordering::Relaxed);
            }
            while let Some(r) = rig.samples().pop() {
                if rig.state().drive_enabled() {
                    *encoder_counts = (f64::from(r.commanded_position_m) * 1e6).round() as i64;
                }
                let _ = batch.push(r);
                if batch.is_full()
                    && !send(
                        &mut stream,
                        &RigMessage::Samples(std::mem::take(&mut batch)),
                    )
                {
                    return;
                }
            }
        }
    }
}

const CAMPAIGN: &str = r#"
name = "on-a-board"
seed = 3
model = "eq4"

[grid]
kinds = ["single"]
frequencies_hz = [10.0]
phis = [0.58, 0.6]

[bed]
grain_mass_kg = 39.19
grain_density_kg_m3 = 1100.0
area_m2 = 0.25
tolerance = 0.005
max_attempts = 20
fluidize_s = 0.05
blower_v = 7.5
settle_s = 0.01
dose_s = 0.02
shaker_duty = 1.0
height_readings = 3
lift_timeout_s = 2.0

[bed.height_sensor]
metres_per_code = 2e-5
height_at_zero_code_m = 0.2

[camera]
fps = 200
capture_dir = "CAPTURE"

[analysis]
track = true
replay = true
"#;

#[test]
fn a_campaign_on_a_board_prepares_its_bed_through_the_controller_and_jumps() {
    let tmp = tempfile::tempdir().unwrap();
    let sock = tmp.path().join("board.sock");
    let listener = UnixListener::bind(&sock).unwrap();
    listener.set_nonblocking(true).unwrap();
    let capture = tmp.path().join("camera");
    std::fs::create_dir_all(&capture).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let seen = Arc::new(Seen::default());
    let board = {
        let (stop, seen, capture) = (stop.clone(), seen.clone(), capture.clone());
        std::thread::spawn(move || {
            let mut rig: Rig = Rig::new(RigConfig::default()).unwrap();
            // Loose and lifted out, where the last session left it.
            let mut bed = Bed {
                lift: 1.0,
                phi0: 0.57,
                dose: 0.0,
                blowing_s: 0.0,
                fluidizations: 0,
            };
            // The motor rests at a single jump's start position.
            let mut counts: i64 = -18_750;
            while !stop.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((s, _)) => {
                        s.set_nonblocking(false).unwrap();
                        serve(s, &mut rig, &mut bed, &mut counts, &seen, &capture);
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(5)),
                }
            }
        })
    };
    let file = tmp.path().join("board.toml");
    std::fs::write(
        &file,
        CAMPAIGN.replace("CAPTURE", capture.to_str().unwrap()),
    )
    .unwrap();
    let out = tmp.path().join("campaign");
    let sock2 = sock.clone();
    let connect = Box::new(move || {
        let host = UnixStream::connect(&sock2).map_err(|e| e.to_string())?;
        let reader = host.try_clone().map_err(|e| e.to_string())?;
        FramedLink::start(
            "board",
            Box::new(reader),
            Box::new(host),
            None,
            Duration::from_secs(2),
        )
        .map(|l| Box::new(l) as Box<dyn RigLink>)
        .map_err(|e| e.to_string())
    });
    let r = run_on_board(&file, &out, connect, None);
    stop.store(true, Ordering::Relaxed);
    board.join().unwrap();
    r.unwrap_or_else(|e| panic!("{}", e.message));

    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut lines = results.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|c| *c == n).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "{results}");
    for r in &rows {
        assert_eq!(r[col("status")], "done", "{r:?}");
        let target: f64 = r[col("target_phi")].parse().unwrap();
        let achieved: f64 = r[col("achieved_phi")].parse().unwrap();
        assert!((achieved - target).abs() <= 0.005, "{r:?}");
        let predicted: f64 = r[col("predicted_jump_height_m")].parse().unwrap();
        assert!(predicted > 0.02, "{r:?}");
        // The lab's frames, moved into the point's folder and tracked: the stand-in camera's
        // apex within 0.2 mm.
        let measured: f64 = r[col("measured_jump_height_m")].parse().unwrap();
        assert!(
            (measured - APEX_M).abs() < 2e-4,
            "camera {measured} m: {r:?}"
        );
        assert_eq!(r[col("frames_flagged")], "0", "{r:?}");
        assert!(r[col("faults")].is_empty(), "{r:?}");
        let folder = out.join(r[col("folder")]);
        assert!(folder.join("acquisition.csv").is_file());
        assert!(folder.join("frames/frame_000000.png").is_file());
    }
    // The bed was worked through the controller: blown, shaken; each jump armed with the lift
    // down, and nothing refused.
    assert!(seen.blower_on_ticks.load(Ordering::Relaxed) > 0);
    assert!(seen.shaker_on_ticks.load(Ordering::Relaxed) > 0);
    assert_eq!(seen.arms_with_lift_down.load(Ordering::Relaxed), 2);
    assert_eq!(seen.commands_rejected.load(Ordering::Relaxed), 0);
    assert_eq!(
        std::fs::read_dir(&capture).unwrap().count(),
        0,
        "every frame moved out of the capture folder"
    );
}
