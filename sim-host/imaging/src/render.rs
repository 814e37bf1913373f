//! The rod camera, simulated: frames of the 9.5 mm ball on the thrust rod as a high-speed
//! camera records them (docs/model.md section 6), from the rod's height over each exposure.
//!
//! What the camera adds, all seeded and deterministic: motion blur (the ball's image averaged
//! over the exposure, sampled finely enough that sub-images overlap), shading of the ball
//! (brighter in the middle, a white sphere under diffuse light), an uneven background (a tilt
//! and vignetting), optional defocus (a softer edge), photon shot noise (Poisson, through the
//! sensor's full-well capacity), read noise, and quantisation to 8 or 16 bits. Image `y` grows
//! downward; the rod's height is up.

use std::path::Path;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use super::frame::{BitDepth, GrayFrame};

/// The camera and the scene it looks at.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraModel {
    /// Frame width (region of interest), px.
    pub width_px: u32,
    /// Frame height, px.
    pub height_px: u32,
    /// Scale, metres per pixel (the same in x and y).
    pub m_per_px: f64,
    /// Ball diameter, m (the paper's 9.5 mm white plastic ball).
    pub ball_diameter_m: f64,
    /// Ball centre at the rod's rest height, px (x, y).
    pub rest_centre_px: (f64, f64),
    /// Exposure time, s (starts at the trigger's rising edge).
    pub exposure_s: f64,
    /// Mean background level, in units of the 8-bit range (0..255).
    pub background_level: f64,
    /// Ball brightness above the background at its centre, 8-bit units.
    pub ball_contrast: f64,
    /// Background tilt: relative change from the left edge to the right and from the top to
    /// the bottom (an uneven light).
    pub background_tilt: f64,
    /// Vignetting: relative darkening at the frame's corners.
    pub vignetting: f64,
    /// Full-well capacity at the top of the range, electrons (sets the shot noise).
    pub full_well_electrons: f64,
    /// Read noise, 8-bit units (RMS).
    pub read_noise: f64,
    /// Defocus: width of the ball's soft edge, px (0: in focus, a 1 px edge).
    pub defocus_px: f64,
    /// Bits per pixel of the frames (8 or 16).
    pub bits: u32,
    /// Noise seed (frame `n` uses its own stream derived from it).
    pub seed: u64,
}

impl Default for CameraModel {
    /// A 256 x 1024 region at 0.12 mm/px, 1 ms exposure, a ball 79 px across resting 700 px
    /// down (so 79 mm of rise and 34 mm of descent stay fully in view: a delayed stutter's
    /// whole motion on loose sand), 8 bits, realistic noise.
    fn default() -> Self {
        Self {
            width_px: 256,
            height_px: 1024,
            m_per_px: 1.2e-4,
            ball_diameter_m: 9.5e-3,
            rest_centre_px: (128.0, 700.0),
            exposure_s: 1e-3,
            background_level: 45.0,
            ball_contrast: 150.0,
            background_tilt: 0.2,
            vignetting: 0.15,
            full_well_electrons: 10_000.0,
            read_noise: 1.5,
            defocus_px: 0.0,
            bits: 8,
            seed: 1,
        }
    }
}

impl CameraModel {
    /// Check the model: sizes and scale positive, levels inside the range.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("camera {name} = {v} (allowed: finite and > 0)"))
            }
        };
        if self.width_px == 0
            || self.height_px == 0
            || self.width_px > 16384
            || self.height_px > 16384
        {
            return Err(format!(
                "camera size {}x{} (allowed: 1..=16384 px each way)",
                self.width_px, self.height_px
            ));
        }
        positive("m_per_px", self.m_per_px)?;
        positive("ball_diameter_m", self.ball_diameter_m)?;
        positive("full_well_electrons", self.full_well_electrons)?;
        for (name, v) in [
            ("exposure_s", self.exposure_s),
            ("background_level", self.background_level),
            ("ball_contrast", self.ball_contrast),
            ("read_noise", self.read_noise),
            ("defocus_px", self.defocus_px),
            ("background_tilt", self.background_tilt),
            ("vignetting", self.vignetting),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("camera {name} = {v} (allowed: finite and >= 0)"));
            }
        }
        if self.background_level + self.ball_contrast > 255.0 {
            return Err(format!(
                "camera background_level + ball_contrast = {} (allowed: <= 255, the 8-bit range)",
                self.background_level + self.ball_contrast
            ));
        }
        if self.bits != 8 && self.bits != 16 {
            return Err(format!("camera bits = {} (allowed: 8 or 16)", self.bits));
        }
        Ok(())
    }

    /// The defaults with the keys of a TOML file on top (an unknown key, a wrong type or a
    /// value [`validate`](Self::validate) refuses is an error naming the file).
    pub fn from_toml_file(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        Self::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The defaults with the keys of `text` (TOML) on top.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let mut table: toml::Table = toml::to_string(&Self::default())
            .map_err(|e| e.to_string())?
            .parse()
            .map_err(|e: toml::de::Error| e.to_string())?;
        let given: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
        for (k, v) in given {
            if !table.contains_key(&k) {
                return Err(format!(
                    "unknown key `{k}` (allowed: {})",
                    table.keys().cloned().collect::<Vec<_>>().join(", ")
                ));
            }
            table.insert(k, v);
        }
        let camera: Self = table
            .try_into()
            .map_err(|e: toml::de::Error| e.to_string())?;
        camera.validate()?;
        Ok(camera)
    }

    /// Ball radius, px.
    pub fn ball_radius_px(&self) -> f64 {
        0.5 * self.ball_diameter_m / self.m_per_px
    }

    /// Ball centre in the image for a rod height above rest, px.
    pub fn centre_px(&self, rod_height_m: f64) -> (f64, f64) {
        (
            self.rest_centre_px.0,
            self.rest_centre_px.1 - rod_height_m / self.m_per_px,
        )
    }

    fn depth(&self) -> BitDepth {
        if self.bits == 16 {
            BitDepth::Sixteen
        } else {
            BitDepth::Eight
        }
    }

    /// Background level at the pixel centred at `(x, y)` (column, row), 8-bit units.
    fn background(&self, x: f64, y: f64) -> f64 {
        let (w, h) = (f64::from(self.width_px), f64::from(self.height_px));
        // Relative to the frame's centre, ((w - 1) / 2, (h - 1) / 2), in frame widths.
        let (u, v) = ((x + 0.5) / w - 0.5, (y + 0.5) / h - 0.5);
        let tilt = 1.0 + self.background_tilt * (u + v);
        let vignette = 1.0 - self.vignetting * 2.0 * (u * u + v * v);
        self.background_level * tilt * vignette
    }

    /// The background image, 8-bit units (what [`render`](Self::render) starts from; compute
    /// it once when rendering many frames, see [`render_on`](Self::render_on)).
    pub fn background_image(&self) -> Vec<f32> {
        let (w, h) = (self.width_px as usize, self.height_px as usize);
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                out.push(self.background(x as f64, y as f64) as f32);
            }
        }
        out
    }

    /// A frame exposed from `t_start_s` for the exposure time, the ball's centre at
    /// `centre_at(t)` px; `frame_number` selects the noise stream.
    pub fn render(
        &self,
        t_start_s: f64,
        centre_at: impl Fn(f64) -> (f64, f64),
        frame_number: u64,
    ) -> GrayFrame {
        self.render_on(&self.background_image(), t_start_s, centre_at, frame_number)
    }

    /// [`render`](Self::render) on a precomputed [`background_image`](Self::background_image).
    pub fn render_on(
        &self,
        background: &[f32],
        t_start_s: f64,
        centre_at: impl Fn(f64) -> (f64, f64),
        frame_number: u64,
    ) -> GrayFrame {
        let r = self.ball_radius_px();
        // Sub-exposures: at most a fifth of a pixel of motion between two.
        let (a, b) = (centre_at(t_start_s), centre_at(t_start_s + self.exposure_s));
        let travel = (a.0 - b.0).hypot(a.1 - b.1);
        let subs = if self.exposure_s > 0.0 {
            ((travel * 5.0).ceil() as usize).clamp(1, 400)
        } else {
            1
        };
        let centres: Vec<(f64, f64)> = (0..subs)
            .map(|k| centre_at(t_start_s + self.exposure_s * (k as f64 + 0.5) / subs as f64))
            .collect();
        let edge = self.defocus_px.max(1.0);
        let reach = r + edge;
        let (w, h) = (self.width_px as usize, self.height_px as usize);
        let mut signal: Vec<f32> = background.to_vec();
        signal.resize(w * h, 0.0);
        // The ball: the mean over the sub-exposures of a shaded disc with a linear edge.
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(cx, cy) in &centres {
            x0 = x0.min(cx - reach);
            x1 = x1.max(cx + reach);
            y0 = y0.min(cy - reach);
            y1 = y1.max(cy + reach);
        }
        let clampi = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n);
        let (px0, px1) = (clampi(x0, w), clampi(x1 + 1.0, w));
        let (py0, py1) = (clampi(y0, h), clampi(y1 + 1.0, h));
        let scale = self.ball_contrast / subs as f64;
        for y in py0..py1 {
            // Pixel (row y, column x) is centred at (x, y), as numpy, scikit-image, trackpy
            // and OpenCV have it.
            let yc = y as f64;
            for x in px0..px1 {
                let xc = x as f64;
                let mut sum = 0.0;
                for &(cx, cy) in &centres {
                    let d2 = (xc - cx) * (xc - cx) + (yc - cy) * (yc - cy);
                    if d2 >= reach * reach {
                        continue;
                    }
                    let d = d2.sqrt();
                    let cover = ((r - d) / edge + 0.5).clamp(0.0, 1.0);
                    let shade = 0.7 + 0.3 * (1.0 - (d2 / (r * r)).min(1.0)).sqrt();
                    sum += cover * shade;
                }
                signal[y * w + x] += (scale * sum) as f32;
            }
        }
        // The sensor: shot noise through the full well, read noise, quantisation.
        let mut rng =
            StdRng::seed_from_u64(self.seed ^ frame_number.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let units_per_electron = (255.0 / self.full_well_electrons) as f32;
        let read_var = (self.read_noise * self.read_noise) as f32;
        let (out_scale, max) = match self.depth() {
            BitDepth::Eight => (1.0_f32, 255.0_f32),
            BitDepth::Sixteen => (257.0, 65535.0),
        };
        let noisy = signal.into_iter().map(|s| {
            // Poisson shot noise as a Gaussian of variance = electrons (s / units_per_electron).
            let sigma = (s.max(0.0) * units_per_electron + read_var).sqrt();
            let n: f32 = rng.sample(StandardNormal);
            ((s + sigma * n) * out_scale).round().clamp(0.0, max)
        });
        match self.depth() {
            BitDepth::Eight => GrayFrame::from_u8(
                self.width_px,
                self.height_px,
                noisy.map(|v| v as u8).collect(),
            ),
            BitDepth::Sixteen => GrayFrame::from_u16(
                self.width_px,
                self.height_px,
                noisy.map(|v| v as u16).collect(),
            ),
        }
        .unwrap_or_else(|| unreachable!("the buffer has width x height pixels"))
    }

    /// A frame with the ball held still at `centre` px (the tests' known positions).
    pub fn render_still(&self, centre: (f64, f64), frame_number: u64) -> GrayFrame {
        self.render(0.0, |_| centre, frame_number)
    }
}

/// Write a frame as PNG (fast compression, no filtering: quick to write and to read back).
pub fn write_png(frame: &GrayFrame, path: &Path) -> Result<(), String> {
    use image::ImageEncoder;
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let file = std::fs::File::create(path)
        .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let encoder = PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        CompressionType::Fast,
        FilterType::NoFilter,
    );
    let (w, h) = (frame.width(), frame.height());
    let result = match frame.pixels() {
        super::frame::Pixels::Eight(p) => {
            encoder.write_image(p, w, h, image::ExtendedColorType::L8)
        }
        super::frame::Pixels::Sixteen(p) => {
            let bytes: Vec<u8> = p.iter().flat_map(|v| v.to_ne_bytes()).collect();
            encoder.write_image(&bytes, w, h, image::ExtendedColorType::L16)
        }
    };
    result.map_err(|e| format!("cannot write {}: {e}", path.display()))
}
