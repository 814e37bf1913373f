//! Speed of the rod camera's analysis: 200 rendered 256 x 1024 8-bit PNG frames of a ball in
//! flight (the default camera: 0.12 mm/px, noise, motion blur), read from disk and tracked on
//! one core, decoding included. Target: at least 2,000 frames/s (criterion's throughput line
//! prints frames/s). Beside it, the two halves: decoding alone, and finding the ball in
//! frames already in memory.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sandjumper_imaging::ball::BallFinder;
use sandjumper_imaging::frame::Roi;
use sandjumper_imaging::render::{CameraModel, write_png};
use sandjumper_imaging::sequence::ImageSequence;
use sandjumper_imaging::track::{FrameClock, TrackSpec, track_sequence};
use std::hint::black_box;

const FRAMES: u64 = 200;

fn frames_on_disk() -> (tempfile::TempDir, CameraModel) {
    let dir = tempfile::tempdir().unwrap();
    let camera = CameraModel::default();
    let background = camera.background_image();
    for n in 0..FRAMES {
        // At rest for 20 frames, then a 60 mm hop: up at 1.1 m/s, down under gravity.
        let t0 = (n as f64 - 20.0).max(0.0) / 200.0;
        let height = |t: f64| {
            let t = t + t0;
            if n < 20 {
                0.0
            } else {
                (1.1 * t - 4.905 * t * t).max(0.0)
            }
        };
        let frame = camera.render_on(&background, 0.0, |t| camera.centre_px(height(t)), n);
        write_png(&frame, &dir.path().join(format!("frame_{n:06}.png"))).unwrap();
    }
    (dir, camera)
}

fn track(c: &mut Criterion) {
    let (dir, camera) = frames_on_disk();
    let seq = ImageSequence::open(dir.path().to_str().unwrap()).unwrap();
    let spec = TrackSpec::new(camera.m_per_px);
    let mut g = c.benchmark_group("rod camera, 200 frames 256x1024 8-bit PNG, one core");
    g.throughput(Throughput::Elements(FRAMES));
    g.sample_size(20);
    g.bench_function("track (decode + find + height + apex)", |b| {
        b.iter(|| track_sequence(black_box(&seq), &spec, &FrameClock::Fps(200.0)).unwrap())
    });
    g.bench_function("decode only", |b| {
        b.iter(|| {
            for f in seq.frames() {
                black_box(f.unwrap());
            }
        })
    });
    let decoded: Vec<_> = seq.frames().map(|f| f.unwrap().frame).collect();
    let finder = BallFinder::new(camera.ball_diameter_m, camera.m_per_px);
    let roi = Roi {
        x: 0,
        y: 0,
        width: camera.width_px,
        height: camera.height_px,
    };
    g.bench_function("find only (frames in memory, tracked window)", |b| {
        b.iter(|| {
            for f in &decoded {
                black_box(finder.find(f, roi, Some((128.0, 700.0)), 2.0 * finder.radius_px));
            }
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: criterion's group summary needs a system font this crate does not ship.
    config = Criterion::default().without_plots();
    targets = track
}
criterion_main!(benches);
