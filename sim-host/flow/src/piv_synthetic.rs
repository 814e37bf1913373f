//! `sandjumper piv-synthetic` as one call: a [`SyntheticRequest`] (a known motion of rendered
//! grains, or of a real image), [`run`] (checked, the grains scattered or the image read) and
//! a [`SyntheticOutcome`] whose frames are rendered on demand ([`SyntheticOutcome::frame`]),
//! so a long sequence never sits in memory, and written with [`SyntheticOutcome::write`]
//! (`frame_NNNNNN.png`, `foot.csv` for the cone, `synthetic.toml`).

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::FlowError;
use crate::piv::Image;
use crate::synthetic::{Grain, GrainScene};
use sandjumper_frame::GrayFrame;
use sandjumper_imaging::render::write_png;
use sandjumper_imaging::sequence::decode_file;
use sandjumper_output::parse::parse_number;
use sandjumper_output::{Progress, StagedDir};

/// A known motion of `piv-synthetic` (`Shift`: by [`SyntheticRequest::shift_px`] when given).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SyntheticField {
    /// Every grain moves by (MAG, MAG/2) px per frame.
    Shift,
    /// u = MAG * (y - H/2) / (H/2) px per frame: a shear.
    Shear,
    /// A rigid rotation about the centre, MAG px per frame at the edge.
    Rotation,
    /// A flat foot (half-width H/4) descending MAG px per frame from a surface at H/4, with
    /// the 60-degree cone of grains under it moving along and the rest at rest.
    Cone,
}

/// What sequence to make: `sandjumper piv-synthetic`'s arguments, typed.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct SyntheticRequest {
    /// The motion.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub field: SyntheticField,
    /// Magnitude, px per frame.
    #[cfg_attr(feature = "clap", arg(long = "magnitude", value_name = "PX", default_value = "2.5", value_parser = parse_number))]
    pub magnitude_px: f64,
    /// Frame size WxH, px.
    #[cfg_attr(feature = "clap", arg(long = "size", value_name = "WxH", default_value = "1280x1024", value_parser = parse_size))]
    pub size_px: (u32, u32),
    /// Frames to write.
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value = "2", value_parser = clap::value_parser!(u32).range(2..=10000)))]
    pub frames: u32,
    /// Grain diameter, px.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PX", default_value = "5", value_parser = sandjumper_output::parse::parse_positive))]
    pub grain_px: f64,
    /// Read noise, 8-bit levels RMS (0: none).
    #[cfg_attr(feature = "clap", arg(long, value_name = "LEVELS", default_value = "0", value_parser = parse_number))]
    pub noise: f64,
    /// Seed.
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value = "1"))]
    pub seed: u64,
    /// Move this real image (PNG, TIFF, BMP; grey or colour) instead of rendering grains:
    /// frame n is it translated by n times the shift, exactly (a Fourier shift of its mirrored
    /// extension), written as 16-bit PNG. Only with `--field shift`.
    #[cfg_attr(feature = "clap", arg(long, value_name = "IMAGE"))]
    pub image: Option<PathBuf>,
    /// The shift per frame DX,DY, px (x right, y down) for `--field shift` (default:
    /// `--magnitude` in x and half of it in y).
    #[cfg_attr(feature = "clap", arg(long = "shift", value_name = "DX,DY", value_parser = parse_shift, allow_hyphen_values = true))]
    pub shift_px: Option<(f64, f64)>,
}

impl Default for SyntheticRequest {
    fn default() -> Self {
        Self {
            field: SyntheticField::Shift,
            magnitude_px: 2.5,
            size_px: (1280, 1024),
            frames: 2,
            grain_px: 5.0,
            noise: 0.0,
            seed: 1,
            image: None,
            shift_px: None,
        }
    }
}

impl SyntheticRequest {
    /// A real image and an explicit shift move by a uniform shift only.
    pub fn validate(&self) -> Result<(), FlowError> {
        if self.image.is_some() && self.field != SyntheticField::Shift {
            return Err(FlowError::input(format!(
                "--image moves a real image by a uniform shift: it needs --field shift (given: {:?})",
                self.field
            )));
        }
        if self.image.is_none() && self.shift_px.is_some() && self.field != SyntheticField::Shift {
            return Err(FlowError::input(
                "--shift DX,DY is the motion of --field shift only",
            ));
        }
        Ok(())
    }

    /// The shift per frame, px.
    fn shift(&self) -> (f64, f64) {
        self.shift_px
            .unwrap_or((self.magnitude_px, 0.5 * self.magnitude_px))
    }
}

/// clap value parser of [`SyntheticRequest::shift_px`]: `DX,DY`, px, each within +-1000.
pub fn parse_shift(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<Result<f64, _>> = s.split(',').map(|p| parse_number(p.trim())).collect();
    match v.as_slice() {
        [Ok(x), Ok(y)] if x.abs() <= 1000.0 && y.abs() <= 1000.0 => Ok((*x, *y)),
        _ => Err(format!(
            "`{s}` is not a shift DX,DY in px (each within +-1000)"
        )),
    }
}

/// clap value parser of [`SyntheticRequest::size_px`]: `WxH`, 16 to 16384 px each.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let v: Vec<Result<u32, _>> = s.split('x').map(str::parse).collect();
    match v.as_slice() {
        [Ok(w), Ok(h)] if (16..=16384).contains(w) && (16..=16384).contains(h) => Ok((*w, *h)),
        _ => Err(format!("`{s}` is not a size WxH (16..=16384 px each)")),
    }
}

/// What the frames are made from.
#[derive(Clone, Debug)]
enum Source {
    /// A real image (its path and grey-level scale to 16 bits) moved by Fourier shifts.
    Image {
        path: PathBuf,
        image: Image,
        size: (u32, u32),
        scale: f64,
    },
    /// Rendered grains.
    Grains {
        scene: GrainScene,
        grains: Vec<Grain>,
    },
}

/// A synthetic sequence, ready to render: each frame on demand, or all into a folder.
#[derive(Clone, Debug)]
pub struct SyntheticOutcome {
    /// The request this sequence answers.
    pub request: SyntheticRequest,
    source: Source,
}

/// Check `request` and prepare its sequence: the real image read and its shift checked (it
/// must stay within a quarter of the image), or the grains scattered.
pub fn run(
    request: &SyntheticRequest,
    progress: &dyn Progress,
) -> Result<SyntheticOutcome, FlowError> {
    let _ = progress;
    request.validate()?;
    let source = match &request.image {
        Some(path) => image_source(request, path)?,
        None => {
            let scene = GrainScene {
                width: request.size_px.0,
                height: request.size_px.1,
                grain_px: request.grain_px,
                noise: request.noise.max(0.0),
                seed: request.seed,
                ..GrainScene::default()
            };
            let grains = scene.grains();
            Source::Grains { scene, grains }
        }
    };
    Ok(SyntheticOutcome {
        request: request.clone(),
        source,
    })
}

/// The real image `path`, checked against the shift its frames move it by.
fn image_source(request: &SyntheticRequest, path: &Path) -> Result<Source, FlowError> {
    let frame = decode_file(path)
        .map_err(|e| FlowError::input(format!("--image {}: {e}", path.display())))?;
    // The shift wraps around the image's periodic extension: the last frame's shift must stay
    // within a quarter of the image, where the truth is still the image moved.
    let shift = request.shift();
    let n = f64::from(request.frames - 1);
    let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
    if (shift.0 * n).abs() > 0.25 * w || (shift.1 * n).abs() > 0.25 * h {
        return Err(FlowError::input(format!(
            "--shift {},{} over {} frames moves {} ({}x{} px) by ({}, {}) px (allowed: up to a quarter of its width and height)",
            shift.0,
            shift.1,
            request.frames,
            path.display(),
            frame.width(),
            frame.height(),
            shift.0 * n,
            shift.1 * n
        )));
    }
    Ok(Source::Image {
        path: path.to_path_buf(),
        image: Image::from_frame(&frame),
        size: (frame.width(), frame.height()),
        scale: 65535.0 / f64::from(frame.depth().max_value()),
    })
}

/// The displacement of the cone scene of a `w` x `h` px frame after `t` frames of `mag` px:
/// grains in the 60-degree cone under the foot move with it, the rest stay.
pub fn cone_displacement(w: f64, h: f64, mag: f64, t: f64) -> impl Fn(f64, f64) -> (f64, f64) {
    let (axis, surface, half) = (0.5 * w, 0.25 * h, 0.25 * h);
    let tan = 60f64.to_radians().tan();
    move |x, y| {
        let depth = y - surface;
        let r = (x - axis).abs();
        if depth >= 0.0 && r < half - depth / tan {
            (0.0, mag * t)
        } else {
            (0.0, 0.0)
        }
    }
}

impl SyntheticOutcome {
    /// Frames in the sequence.
    pub fn len(&self) -> u32 {
        self.request.frames
    }

    /// Whether the sequence has no frames (never, for a checked request).
    pub fn is_empty(&self) -> bool {
        self.request.frames == 0
    }

    /// Frame `n` (0-based): 8-bit grains, or the real image moved, 16-bit.
    pub fn frame(&self, n: u32) -> Result<GrayFrame, FlowError> {
        match &self.source {
            Source::Image {
                image, size, scale, ..
            } => {
                let (t, shift) = (f64::from(n), self.request.shift());
                let moved = crate::shift::translate(image, shift.0 * t, shift.1 * t);
                let px: Vec<u16> = moved
                    .data
                    .iter()
                    .map(|&v| (f64::from(v) * scale).round().clamp(0.0, 65535.0) as u16)
                    .collect();
                GrayFrame::from_u16(size.0, size.1, px)
                    .ok_or_else(|| FlowError::internal("shifted frame size"))
            }
            Source::Grains { scene, grains } => Ok(self.render(scene, grains, n)),
        }
    }

    /// Frame `n` of the grain scene.
    fn render(&self, scene: &GrainScene, grains: &[Grain], n: u32) -> GrayFrame {
        let r = &self.request;
        let (t, mag, shift) = (f64::from(n), r.magnitude_px, r.shift());
        let (w, h) = (f64::from(r.size_px.0), f64::from(r.size_px.1));
        let none = |_: f64, _: f64| false;
        match r.field {
            SyntheticField::Shift => {
                scene.render(grains, |_, _| (shift.0 * t, shift.1 * t), none, n.into())
            }
            SyntheticField::Shear => scene.render(
                grains,
                |_, y| (mag * t * (y - 0.5 * h) / (0.5 * h), 0.0),
                none,
                n.into(),
            ),
            SyntheticField::Rotation => {
                let om = mag / (0.5 * w.min(h));
                let rotated = |x: f64, y: f64| {
                    let (dx, dy) = (x - 0.5 * w, y - 0.5 * h);
                    let (c, s) = ((om * t).cos(), (om * t).sin());
                    (dx * c - dy * s - dx, dx * s + dy * c - dy)
                };
                scene.render(grains, rotated, none, n.into())
            }
            SyntheticField::Cone => {
                let surface = 0.25 * h;
                let hide = move |_: f64, y: f64| y < surface;
                scene.render(grains, cone_displacement(w, h, mag, t), hide, n.into())
            }
        }
    }

    /// `foot.csv` of the cone (`frame,x_px,y_px`: the foot's four corners per frame).
    pub fn foot_csv(&self) -> Option<String> {
        let r = &self.request;
        if r.field != SyntheticField::Cone || r.image.is_some() {
            return None;
        }
        let (w, h) = (f64::from(r.size_px.0), f64::from(r.size_px.1));
        let mut foot = String::from("frame,x_px,y_px\n");
        for n in 0..r.frames {
            let bottom = 0.25 * h + r.magnitude_px * f64::from(n);
            let (x0, x1) = (0.5 * w - 0.25 * h, 0.5 * w + 0.25 * h);
            for (x, y) in [(x0, 0.0), (x1, 0.0), (x1, bottom), (x0, bottom)] {
                foot += &format!("{n},{x},{y}\n");
            }
        }
        Some(foot)
    }

    /// `synthetic.toml`: what the sequence is.
    pub fn settings_toml(&self) -> Result<String, FlowError> {
        let r = &self.request;
        Ok(match &self.source {
            Source::Image { path, .. } => {
                let shift = r.shift();
                format!(
                    "# sandjumper piv-synthetic: {} moved by ({}, {}) px per frame (Fourier shift)\nimage = {:?}\nshift_px = [{}, {}]\nframes = {}\n",
                    path.display(),
                    shift.0,
                    shift.1,
                    path.display().to_string(),
                    shift.0,
                    shift.1,
                    r.frames
                )
            }
            Source::Grains { scene, .. } => format!(
                "# sandjumper piv-synthetic: {:?}, {} px per frame\nfield = \"{:?}\"\nmagnitude_px = {}\nframes = {}\n{}",
                r.field,
                r.magnitude_px,
                r.field,
                r.magnitude_px,
                r.frames,
                toml::to_string(scene).map_err(FlowError::internal)?
            ),
        })
    }

    /// Write every frame as `frame_NNNNNN.png`, `foot.csv` (cone) and `synthetic.toml` into
    /// the folder `dir`, atomically, and return its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, FlowError> {
        let staged = StagedDir::create(dir)?;
        for n in 0..self.request.frames {
            write_png(&self.frame(n)?, &staged.file(&format!("frame_{n:06}.png")))
                .map_err(FlowError::internal)?;
        }
        if let Some(foot) = self.foot_csv() {
            staged.write_text("foot.csv", &foot)?;
        }
        staged.write_text("synthetic.toml", &self.settings_toml()?)?;
        Ok(staged.commit()?)
    }
}
