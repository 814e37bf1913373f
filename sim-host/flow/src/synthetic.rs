//! Synthetic grain images with a known motion: the PIV tests' ground truth (and
//! `sandjumper piv-synthetic`'s, for a lab checking its own settings).
//!
//! Poppy seeds seen through a side wall: densely packed, overlapping disks about a grain
//! diameter across, each with its own grey level and a shaded face, on a dark background, plus
//! sensor noise. Frame B has every grain moved by a known displacement field evaluated at the
//! grain's position in frame A (grains translate rigidly: exact for uniform motion, and the
//! field sampled grain by grain otherwise; grains at rest are drawn first, moving ones in
//! front). Grains are scattered over a margin around the
//! frame, so grains move in from outside as they would in a video.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use sandjumper_frame::GrayFrame;

/// The scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GrainScene {
    /// Frame width, px.
    pub width: u32,
    /// Frame height, px.
    pub height: u32,
    /// Grain diameter, px (poppy seeds ~1 mm; at 0.2 mm/px, 5 px).
    pub grain_px: f64,
    /// Grains per grain area (1.3: densely packed, overlapping).
    pub packing: f64,
    /// Background level (gaps between grains), 8-bit units.
    pub background: f64,
    /// Grains' grey levels are uniform in this range, 8-bit units.
    pub grey_range: (f64, f64),
    /// Read noise, 8-bit units RMS (0: none). Shot noise through a 10,000-electron well is
    /// added when this is not 0.
    pub noise: f64,
    /// Seed of the grains and the noise.
    pub seed: u64,
}

impl Default for GrainScene {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            grain_px: 5.0,
            packing: 1.3,
            background: 20.0,
            grey_range: (60.0, 230.0),
            noise: 0.0,
            seed: 1,
        }
    }
}

/// One grain in frame A.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grain {
    /// Centre, px (pixel centres at whole numbers).
    pub x: f64,
    /// Centre, px, y down.
    pub y: f64,
    /// Grey level.
    pub grey: f64,
}

/// Margin around the frame where grains are scattered too, px.
const MARGIN_PX: f64 = 40.0;
/// Width of a grain's soft edge, px.
const EDGE_PX: f64 = 1.5;

impl GrainScene {
    /// The grains of frame A.
    pub fn grains(&self) -> Vec<Grain> {
        let mut rng = StdRng::seed_from_u64(self.seed);
        let (w, h) = (
            f64::from(self.width) + 2.0 * MARGIN_PX,
            f64::from(self.height) + 2.0 * MARGIN_PX,
        );
        let area = core::f64::consts::PI * 0.25 * self.grain_px * self.grain_px;
        let n = (self.packing * w * h / area).round() as usize;
        (0..n)
            .map(|_| Grain {
                x: rng.random::<f64>() * w - MARGIN_PX - 0.5,
                y: rng.random::<f64>() * h - MARGIN_PX - 0.5,
                grey: self.grey_range.0
                    + (self.grey_range.1 - self.grey_range.0) * rng.random::<f64>(),
            })
            .collect()
    }

    /// Render the grains moved by `displacement(x, y)` px (evaluated at each grain's frame-A
    /// centre), with the noise stream `noise_stream`; grains for which `hide(x, y)` holds
    /// after the move are not drawn (a foot in front of them).
    pub fn render(
        &self,
        grains: &[Grain],
        displacement: impl Fn(f64, f64) -> (f64, f64),
        hide: impl Fn(f64, f64) -> bool,
        noise_stream: u64,
    ) -> GrayFrame {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut img = vec![self.background; w * h];
        let r = 0.5 * self.grain_px;
        let reach = r + EDGE_PX;
        // Grains at rest first, moving ones in front of them: a moving body of grains (the
        // cone under a foot) pushes through the bed instead of hiding behind it.
        let moved: Vec<(Grain, f64, f64)> = grains
            .iter()
            .map(|g| {
                let (dx, dy) = displacement(g.x, g.y);
                (*g, g.x + dx, g.y + dy)
            })
            .collect();
        let still = moved.iter().filter(|m| m.1 == m.0.x && m.2 == m.0.y);
        let moving = moved.iter().filter(|m| m.1 != m.0.x || m.2 != m.0.y);
        for &(g, cx, cy) in still.chain(moving) {
            if hide(cx, cy) {
                continue;
            }
            let x0 = (cx - reach).floor().max(0.0) as usize;
            let y0 = (cy - reach).floor().max(0.0) as usize;
            let x1 = ((cx + reach).ceil() + 1.0).clamp(0.0, w as f64) as usize;
            let y1 = ((cy + reach).ceil() + 1.0).clamp(0.0, h as f64) as usize;
            for y in y0..y1 {
                for x in x0..x1 {
                    let d = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
                    let t = (d - (r - 0.5 * EDGE_PX)) / EDGE_PX;
                    let alpha = if t <= 0.0 {
                        1.0
                    } else if t >= 1.0 {
                        continue;
                    } else {
                        0.5 * (1.0 + (core::f64::consts::PI * t).cos())
                    };
                    let shade = 0.75 + 0.25 * (1.0 - (d / reach).powi(2)).max(0.0).sqrt();
                    let p = &mut img[y * w + x];
                    *p = *p * (1.0 - alpha) + g.grey * shade * alpha;
                }
            }
        }
        let mut rng = StdRng::seed_from_u64(self.seed.wrapping_mul(31).wrapping_add(noise_stream));
        let px = img
            .into_iter()
            .map(|s| {
                let v = if self.noise > 0.0 {
                    let sigma = (s.max(0.0) * 255.0 / 10_000.0 + self.noise * self.noise).sqrt();
                    let n: f64 = rng.sample(StandardNormal);
                    s + sigma * n
                } else {
                    s
                };
                v.round().clamp(0.0, 255.0) as u8
            })
            .collect();
        GrayFrame::from_u8(self.width, self.height, px)
            .unwrap_or_else(|| unreachable!("width x height pixels"))
    }

    /// A pair: frame A and frame B with the grains moved by `displacement`.
    pub fn pair(&self, displacement: impl Fn(f64, f64) -> (f64, f64)) -> (GrayFrame, GrayFrame) {
        let grains = self.grains();
        (
            self.render(&grains, |_, _| (0.0, 0.0), |_, _| false, 0),
            self.render(&grains, displacement, |_, _| false, 1),
        )
    }
}
