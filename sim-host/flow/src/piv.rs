//! Particle image velocimetry of one image pair: FFT cross-correlation, multipass with window
//! deformation, sub-pixel peaks, validation and replacement.
//!
//! - **Passes** (default 64 -> 32 -> 16 px windows, 50 % overlap): the first pass correlates
//!   windows at the same place in both frames; every later pass deforms both frames
//!   symmetrically by the previous pass's (validated) field, interpolated bilinearly to every
//!   pixel and applied with quintic B-spline resampling, `A'(p) = A(p - d/2)`,
//!   `B'(p) = B(p + d/2)`, and measures what is left. Deformation is what keeps shear bands:
//!   a rigid window averages a gradient of 0.05 px/px over 16 px into a broadened, biased
//!   peak.
//! - **Correlation**: both windows, mean removed (masked pixels set to the mean), go through
//!   one complex FFT as `a + i b` (their spectra separate by symmetry), the cross-spectrum
//!   `conj(A) B` back through the inverse: `c(d) = sum a(x) b(x + d)`, its peak at the
//!   displacement of B relative to A.
//! - **Sub-pixel peak**: 3-point Gaussian in x and y (parabolic where a value is not
//!   positive, or by choice). Before the fit the three values are divided by the fraction of
//!   pixel pairs a circular correlation keeps at that shift, `(1 - |dx|/N)(1 - |dy|/N)`: the
//!   loss-of-pairs bias toward zero displacement is removed. With deformation the residual
//!   displacement is near zero, so the Gaussian fit works on a symmetric peak and the
//!   estimator does not lock to whole pixels (tested: bias within a tenth of a pixel's
//!   fractional part).
//! - **Validation** after every pass: peak ratio (first to second correlation peak) below
//!   `min_peak_ratio`, or the normalised median test (Westerweel & Scarano 2005: residual
//!   over the neighbours' median residual plus 0.1 px, above `median_threshold` in u or v),
//!   marks an outlier; outliers are replaced by the mean of their valid neighbours and
//!   flagged. Masked vectors (window centre in the mask) are NaN and flagged.

use rayon::prelude::*;
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// A grey image as floats, row-major, pixel `(x, y)` centred at `(x, y)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Pixels.
    pub data: Vec<f32>,
}

impl Image {
    /// From a grey frame.
    pub fn from_frame(f: &sandjumper_frame::GrayFrame) -> Self {
        let (w, h) = (f.width() as usize, f.height() as usize);
        let mut data = Vec::with_capacity(w * h);
        let mut row = Vec::new();
        for y in 0..f.height() {
            f.row_into(y, 0, f.width(), &mut row);
            data.extend_from_slice(&row);
        }
        Self {
            width: w,
            height: h,
            data,
        }
    }

    #[inline]
    fn at_clamped(&self, x: isize, y: isize) -> f32 {
        let xi = x.clamp(0, self.width as isize - 1) as usize;
        let yi = y.clamp(0, self.height as isize - 1) as usize;
        self.data[yi * self.width + xi]
    }

    /// The quintic B-spline coefficients of this image (interpolating: the spline passes
    /// through every pixel), by the recursive prefilter of Unser (two poles, mirror
    /// boundaries) along rows, then columns.
    pub fn spline_coefficients(&self) -> Image {
        let (w, h) = (self.width, self.height);
        let mut c = self.data.clone();
        c.par_chunks_mut(w).for_each(prefilter);
        let mut t = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                t[x * h + y] = c[y * w + x];
            }
        }
        t.par_chunks_mut(h).for_each(prefilter);
        for y in 0..h {
            for x in 0..w {
                c[y * w + x] = t[x * h + y];
            }
        }
        Image {
            width: w,
            height: h,
            data: c,
        }
    }

    /// Quintic B-spline value at `(x, y)`, `self` holding [`spline_coefficients`]
    /// (clamped at the edges).
    ///
    /// [`spline_coefficients`]: Self::spline_coefficients
    #[inline]
    pub fn spline(&self, x: f64, y: f64) -> f32 {
        let (xf, yf) = (x.floor(), y.floor());
        let (tx, ty) = ((x - xf) as f32, (y - yf) as f32);
        let (xi, yi) = (xf as isize, yf as isize);
        let wx = bspline5(tx);
        let wy = bspline5(ty);
        let mut sum = 0.0;
        for (j, wyj) in wy.iter().enumerate() {
            let yy = yi - 2 + j as isize;
            let mut row = 0.0;
            for (i, wxi) in wx.iter().enumerate() {
                row += wxi * self.at_clamped(xi - 2 + i as isize, yy);
            }
            sum += wyj * row;
        }
        sum
    }
}

/// Quintic B-spline weights for the 6 coefficients around fraction `t` (from `floor - 2`).
#[inline]
fn bspline5(t: f32) -> [f32; 6] {
    let mut w = t;
    let mut w2 = w * w;
    let w5 = (1.0 / 120.0) * w * w2 * w2;
    w2 -= w;
    let w4 = w2 * w2;
    w -= 0.5;
    let t3 = w2 * (w2 - 3.0);
    let w0 = (1.0 / 24.0) * (1.0 / 5.0 + w2 + w4) - w5;
    let t0 = (1.0 / 24.0) * (w2 * (w2 - 5.0) + 46.0 / 5.0);
    let t1 = (-1.0 / 12.0) * w * (t3 + 4.0);
    let (w2_, w3_) = (t0 + t1, t0 - t1);
    let t0 = (1.0 / 16.0) * (9.0 / 5.0 - t3);
    let t1 = (1.0 / 24.0) * w * (w4 - w2 - 5.0);
    [w0, t0 + t1, w2_, w3_, t0 - t1, w5]
}

/// The quintic B-spline prefilter along one line (in place), mirror boundaries (Unser;
/// Thevenaz et al. 2000): the gain, then a causal and an anti-causal recursion per pole.
fn prefilter(c: &mut [f32]) {
    let n = c.len();
    if n < 2 {
        return;
    }
    const POLES: [f64; 2] = [-0.430_575_347_099_973_8, -0.043_096_288_203_264_65];
    let lambda: f64 = POLES.iter().map(|z| (1.0 - z) * (1.0 - 1.0 / z)).product();
    let mut line: Vec<f64> = c.iter().map(|&v| f64::from(v) * lambda).collect();
    for z in POLES {
        // Causal initialisation: sum of z^k c[k] to double precision.
        let horizon = n.min((f64::EPSILON.ln() / z.abs().ln()).ceil() as usize + 1);
        let (mut sum, mut zn) = (line[0], z);
        for v in line.iter().take(horizon).skip(1) {
            sum += zn * v;
            zn *= z;
        }
        line[0] = sum;
        for k in 1..n {
            line[k] += z * line[k - 1];
        }
        line[n - 1] = (z / (z * z - 1.0)) * (line[n - 1] + z * line[n - 2]);
        for k in (0..n - 1).rev() {
            line[k] = z * (line[k + 1] - line[k]);
        }
    }
    for (o, v) in c.iter_mut().zip(line) {
        *o = v as f32;
    }
}

/// How the correlation peak is refined, per axis (default: Gaussian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SubPixel {
    /// 3-point Gaussian.
    Gaussian,
    /// 3-point parabola.
    Parabolic,
}

/// The analysis settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PivConfig {
    /// Window sizes of the passes, px (each a power of two, >= 8, not growing).
    pub windows: Vec<usize>,
    /// Window overlap, 0..=0.9.
    pub overlap: f64,
    /// Deform the images by the previous pass's field (off: windows are only offset by the
    /// rounded prediction, as old PIV did).
    pub deform: bool,
    /// Sub-pixel estimator.
    pub subpixel: SubPixel,
    /// Normalised median test threshold.
    pub median_threshold: f64,
    /// Smallest peak ratio accepted.
    pub min_peak_ratio: f64,
}

impl Default for PivConfig {
    fn default() -> Self {
        Self {
            windows: vec![64, 32, 16],
            overlap: 0.5,
            deform: true,
            subpixel: SubPixel::Gaussian,
            median_threshold: 2.0,
            min_peak_ratio: 1.2,
        }
    }
}

/// Flag of a vector.
pub mod flag {
    /// Measured and accepted.
    pub const VALID: u8 = 0;
    /// An outlier (peak ratio or median test), replaced by its neighbours' mean.
    pub const REPLACED: u8 = 1;
    /// Window centre in the mask: no vector.
    pub const MASKED: u8 = 2;
}

/// A vector field on the last pass's grid.
#[derive(Clone, Debug, PartialEq)]
pub struct VectorField {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Grid spacing, px.
    pub step_px: usize,
    /// Window centre x of column `i`, px.
    pub xs: Vec<f64>,
    /// Window centre y of row `j`, px (down).
    pub ys: Vec<f64>,
    /// Displacement of B relative to A, px (x right), row-major; NaN where masked.
    pub u: Vec<f64>,
    /// Displacement, px (y down).
    pub v: Vec<f64>,
    /// [`flag`] per vector.
    pub flag: Vec<u8>,
    /// Peak ratio per vector (first to second peak).
    pub peak_ratio: Vec<f64>,
}

impl VectorField {
    /// Vectors by flag: (valid, replaced, masked).
    pub fn counts(&self) -> (usize, usize, usize) {
        let c = |f: u8| self.flag.iter().filter(|&&x| x == f).count();
        (c(flag::VALID), c(flag::REPLACED), c(flag::MASKED))
    }

    /// Indices of the 3 x 3 block of vectors around vector `k` (itself included) that lie on
    /// the grid.
    pub fn block(&self, k: usize) -> impl Iterator<Item = usize> + '_ {
        let (i, j) = (k % self.nx, k / self.nx);
        (j.saturating_sub(1)..(j + 2).min(self.ny)).flat_map(move |jj| {
            (i.saturating_sub(1)..(i + 2).min(self.nx)).map(move |ii| jj * self.nx + ii)
        })
    }

    /// Mean `(u, v)` of the vectors of the block around `k` for which `take` holds; `None`
    /// when there is none.
    pub fn block_mean(&self, k: usize, take: impl Fn(usize) -> bool) -> Option<(f64, f64)> {
        let (mut su, mut sv, mut c) = (0.0, 0.0, 0u32);
        for kk in self.block(k).filter(|&kk| take(kk)) {
            su += self.u[kk];
            sv += self.v[kk];
            c += 1;
        }
        (c > 0).then(|| (su / f64::from(c), sv / f64::from(c)))
    }

    /// Bilinear interpolation of the field at pixel `(x, y)` (clamped to the grid; masked
    /// neighbours count as zero displacement).
    fn sample(&self, x: f64, y: f64) -> (f64, f64) {
        let s = self.step_px as f64;
        let fx = ((x - self.xs[0]) / s).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((y - self.ys[0]) / s).clamp(0.0, (self.ny - 1) as f64);
        let (i0, j0) = (fx.floor() as usize, fy.floor() as usize);
        let (i1, j1) = ((i0 + 1).min(self.nx - 1), (j0 + 1).min(self.ny - 1));
        let (tx, ty) = (fx - i0 as f64, fy - j0 as f64);
        let get = |v: &[f64], i: usize, j: usize| {
            let x = v[j * self.nx + i];
            if x.is_finite() { x } else { 0.0 }
        };
        let lerp = |v: &[f64]| {
            let top = get(v, i0, j0) * (1.0 - tx) + get(v, i1, j0) * tx;
            let bottom = get(v, i0, j1) * (1.0 - tx) + get(v, i1, j1) * tx;
            top * (1.0 - ty) + bottom * ty
        };
        (lerp(&self.u), lerp(&self.v))
    }
}

/// Why a pair cannot be analysed: settings that do not fit the frames, or frames that do not
/// fit each other. Each message says what is allowed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PivError {
    /// No interrogation pass.
    #[error("no passes (allowed: window sizes such as 64,32,16)")]
    NoPasses,
    /// A window that is not a power of two of at least 8 px.
    #[error("window {size_px} px not allowed (allowed: a power of two >= 8)")]
    WindowSize {
        /// The window's side, px.
        size_px: usize,
    },
    /// A window larger than the frames.
    #[error("window {size_px} px is larger than the {width}x{height} image")]
    WindowTooLarge {
        /// The window's side, px.
        size_px: usize,
        /// The frames' width, px.
        width: usize,
        /// The frames' height, px.
        height: usize,
    },
    /// A pass whose window is larger than the pass before.
    #[error("window {size_px} px after {previous_px} px (allowed: sizes that do not grow)")]
    WindowGrows {
        /// The window's side, px.
        size_px: usize,
        /// The previous pass's window side, px.
        previous_px: usize,
    },
    /// A window overlap outside 0..=0.9.
    #[error("overlap {0} not allowed (allowed: 0..=0.9)")]
    Overlap(f64),
    /// A median-test threshold that is not a positive number.
    #[error("median threshold {0} not allowed (allowed: > 0)")]
    MedianThreshold(f64),
    /// A minimum correlation peak ratio below 1.
    #[error("minimum peak ratio {0} not allowed (allowed: >= 1)")]
    MinPeakRatio(f64),
    /// Two frames of different sizes.
    #[error("the frames of a pair differ in size: {}x{} and {}x{}", first.0, first.1, second.0, second.1)]
    SizeMismatch {
        /// The first frame's width and height, px.
        first: (usize, usize),
        /// The second frame's width and height, px.
        second: (usize, usize),
    },
    /// A mask whose pixel count is not the frames'.
    #[error("the mask has {mask_px} pixels, the frames {width}x{height}")]
    MaskSize {
        /// The mask's number of pixels.
        mask_px: usize,
        /// The frames' width, px.
        width: usize,
        /// The frames' height, px.
        height: usize,
    },
}

/// Check the settings against an image size.
pub fn check_config(cfg: &PivConfig, width: usize, height: usize) -> Result<(), PivError> {
    if cfg.windows.is_empty() {
        return Err(PivError::NoPasses);
    }
    for (k, &n) in cfg.windows.iter().enumerate() {
        if n < 8 || !n.is_power_of_two() {
            return Err(PivError::WindowSize { size_px: n });
        }
        if n > width || n > height {
            return Err(PivError::WindowTooLarge {
                size_px: n,
                width,
                height,
            });
        }
        if k > 0 && n > cfg.windows[k - 1] {
            return Err(PivError::WindowGrows {
                size_px: n,
                previous_px: cfg.windows[k - 1],
            });
        }
    }
    if !(0.0..=0.9).contains(&cfg.overlap) {
        return Err(PivError::Overlap(cfg.overlap));
    }
    if !(cfg.median_threshold.is_finite() && cfg.median_threshold > 0.0) {
        return Err(PivError::MedianThreshold(cfg.median_threshold));
    }
    if !(cfg.min_peak_ratio.is_finite() && cfg.min_peak_ratio >= 1.0) {
        return Err(PivError::MinPeakRatio(cfg.min_peak_ratio));
    }
    Ok(())
}

/// Cross-correlation of two N x N windows by one complex FFT.
pub struct Correlator {
    n: usize,
    fwd: Arc<dyn Fft<f32>>,
    inv: Arc<dyn Fft<f32>>,
    z: Vec<Complex32>,
    t: Vec<Complex32>,
    scratch: Vec<Complex32>,
    /// The correlation plane, row-major, shift `(dx, dy)` at `((dy mod N), (dx mod N))`.
    pub plane: Vec<f32>,
}

impl Correlator {
    /// A correlator for `n x n` windows.
    pub fn new(n: usize) -> Self {
        let mut planner = FftPlanner::<f32>::new();
        let fwd = planner.plan_fft_forward(n);
        let inv = planner.plan_fft_inverse(n);
        let scratch_len = fwd
            .get_inplace_scratch_len()
            .max(inv.get_inplace_scratch_len());
        Self {
            n,
            fwd,
            inv,
            z: vec![Complex32::default(); n * n],
            t: vec![Complex32::default(); n * n],
            scratch: vec![Complex32::default(); scratch_len],
            plane: vec![0.0; n * n],
        }
    }

    fn transpose(n: usize, src: &[Complex32], dst: &mut [Complex32]) {
        for y in 0..n {
            for x in 0..n {
                dst[x * n + y] = src[y * n + x];
            }
        }
    }

    /// Correlate windows `a` and `b` (n x n, row-major, means removed) into [`plane`](Self::plane).
    pub fn correlate(&mut self, a: &[f32], b: &[f32]) {
        let n = self.n;
        for ((z, &x), &y) in self.z.iter_mut().zip(a).zip(b) {
            *z = Complex32::new(x, y);
        }
        self.fwd
            .process_with_scratch(&mut self.z, &mut self.scratch);
        Self::transpose(n, &self.z, &mut self.t);
        self.fwd
            .process_with_scratch(&mut self.t, &mut self.scratch);
        // t holds Z at [kx][ky]; A = (Z(k) + conj Z(-k)) / 2, B = (Z(k) - conj Z(-k)) / 2i.
        for p in 0..n {
            for q in 0..n {
                let zk = self.t[p * n + q];
                let zm = self.t[((n - p) % n) * n + (n - q) % n].conj();
                let a = (zk + zm) * 0.5;
                let b = (zk - zm) * Complex32::new(0.0, -0.5);
                self.z[p * n + q] = a.conj() * b;
            }
        }
        self.inv
            .process_with_scratch(&mut self.z, &mut self.scratch);
        Self::transpose(n, &self.z, &mut self.t);
        self.inv
            .process_with_scratch(&mut self.t, &mut self.scratch);
        for (c, t) in self.plane.iter_mut().zip(&self.t) {
            *c = t.re;
        }
    }

    #[inline]
    fn value(&self, dx: isize, dy: isize) -> f32 {
        let n = self.n as isize;
        self.plane[(dy.rem_euclid(n) * n + dx.rem_euclid(n)) as usize]
    }

    /// The peak: `(dx, dy, peak ratio)` with sub-pixel refinement; `None` when the peak lies
    /// on the plane's edge (no displacement inside a quarter window... found).
    pub fn peak(&self, subpixel: SubPixel) -> Option<(f64, f64, f64)> {
        let n = self.n as isize;
        let half = n / 2;
        let (mut best, mut bx, mut by) = (f32::MIN, 0isize, 0isize);
        for dy in -half..half {
            for dx in -half..half {
                let v = self.value(dx, dy);
                if v > best {
                    (best, bx, by) = (v, dx, dy);
                }
            }
        }
        if bx.abs() >= half - 1 || by.abs() >= half - 1 {
            return None;
        }
        let mut second = f32::MIN;
        for dy in -half..half {
            for dx in -half..half {
                if (dx - bx).abs() <= 1 && (dy - by).abs() <= 1 {
                    continue;
                }
                second = second.max(self.value(dx, dy));
            }
        }
        let ratio = if second > 0.0 {
            f64::from(best / second)
        } else {
            1e3
        };
        // Values divided by the fraction of pairs kept at their shift.
        let nf = n as f64;
        let kept = |dx: isize, dy: isize| {
            (1.0 - dx.unsigned_abs() as f64 / nf) * (1.0 - dy.unsigned_abs() as f64 / nf)
        };
        let c = |dx: isize, dy: isize| f64::from(self.value(dx, dy)) / kept(dx, dy);
        let fit = |m: f64, z: f64, p: f64| -> f64 {
            if subpixel == SubPixel::Gaussian && m > 0.0 && z > 0.0 && p > 0.0 {
                let (lm, lz, lp) = (m.ln(), z.ln(), p.ln());
                let den = 2.0 * (lm - 2.0 * lz + lp);
                if den < 0.0 {
                    return (lm - lp) / den;
                }
            }
            let den = 2.0 * (m - 2.0 * z + p);
            if den < 0.0 { (m - p) / den } else { 0.0 }
        };
        let c0 = c(bx, by);
        let sx = fit(c(bx - 1, by), c0, c(bx + 1, by)).clamp(-0.5, 0.5);
        let sy = fit(c(bx, by - 1), c0, c(bx, by + 1)).clamp(-0.5, 0.5);
        Some((bx as f64 + sx, by as f64 + sy, ratio))
    }
}

/// The grid of a pass: window centres along an axis of `len` px.
fn centres(len: usize, n: usize, step: usize) -> Vec<f64> {
    let count = (len - n) / step + 1;
    (0..count)
        .map(|i| (i * step) as f64 + (n as f64 - 1.0) / 2.0)
        .collect()
}

/// Analyse one pair. `mask[y * width + x]` true: not grain flow.
pub fn piv_pair(
    a: &Image,
    b: &Image,
    mask: Option<&[bool]>,
    cfg: &PivConfig,
) -> Result<VectorField, PivError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(PivError::SizeMismatch {
            first: (a.width, a.height),
            second: (b.width, b.height),
        });
    }
    check_config(cfg, a.width, a.height)?;
    if let Some(m) = mask
        && m.len() != a.width * a.height
    {
        return Err(PivError::MaskSize {
            mask_px: m.len(),
            width: a.width,
            height: a.height,
        });
    }
    let mut field: Option<VectorField> = None;
    let splines = cfg
        .deform
        .then(|| (a.spline_coefficients(), b.spline_coefficients()));
    for (pass, &n) in cfg.windows.iter().enumerate() {
        let step = ((n as f64 * (1.0 - cfg.overlap)).round() as usize).max(1);
        let (aw, bw) = match (&field, &splines) {
            (Some(f), Some((sa, sb))) => deform_pair(sa, sb, f),
            _ => (a.clone(), b.clone()),
        };
        let xs = centres(a.width, n, step);
        let ys = centres(a.height, n, step);
        let (nx, ny) = (xs.len(), ys.len());
        let predictor = field.as_ref();
        let results: Vec<(f64, f64, f64, u8)> = (0..ny)
            .into_par_iter()
            .map_init(
                || (Correlator::new(n), vec![0f32; n * n], vec![0f32; n * n]),
                |(corr, wa, wb), j| {
                    let mut row = Vec::with_capacity(nx);
                    for &x in &xs {
                        let y = ys[j];
                        let (cx, cy) = (x.round() as usize, y.round() as usize);
                        if mask.is_some_and(|m| {
                            m[cy.min(a.height - 1) * a.width + cx.min(a.width - 1)]
                        }) {
                            row.push((f64::NAN, f64::NAN, 0.0, flag::MASKED));
                            continue;
                        }
                        let (pu, pv) = predictor.map_or((0.0, 0.0), |f| f.sample(x, y));
                        // Without deformation the windows are offset by the rounded prediction.
                        let (ox, oy) = if cfg.deform || predictor.is_none() {
                            (0isize, 0isize)
                        } else {
                            (pu.round() as isize, pv.round() as isize)
                        };
                        let x0 = (x - (n as f64 - 1.0) / 2.0) as isize;
                        let y0 = (y - (n as f64 - 1.0) / 2.0) as isize;
                        extract(&aw, mask, x0 - ox / 2, y0 - oy / 2, n, wa);
                        extract(&bw, mask, x0 + ox - ox / 2, y0 + oy - oy / 2, n, wb);
                        corr.correlate(wa, wb);
                        match corr.peak(cfg.subpixel) {
                            Some((dx, dy, ratio)) => {
                                let (bu, bv) = if cfg.deform {
                                    (pu, pv)
                                } else {
                                    (ox as f64, oy as f64)
                                };
                                row.push((bu + dx, bv + dy, ratio, flag::VALID));
                            }
                            None => row.push((pu, pv, 0.0, flag::REPLACED)),
                        }
                    }
                    row
                },
            )
            .flatten()
            .collect();
        let mut f = VectorField {
            nx,
            ny,
            step_px: step,
            xs,
            ys,
            u: results.iter().map(|r| r.0).collect(),
            v: results.iter().map(|r| r.1).collect(),
            flag: results.iter().map(|r| r.3).collect(),
            peak_ratio: results.iter().map(|r| r.2).collect(),
        };
        validate(&mut f, cfg);
        if pass + 1 < cfg.windows.len() {
            smooth(&mut f);
        }
        field = Some(f);
    }
    field.ok_or(PivError::NoPasses)
}

/// Copy an n x n window at `(x0, y0)` (clamped at the edges), remove the mean of its
/// unmasked pixels and set masked ones to zero.
fn extract(img: &Image, mask: Option<&[bool]>, x0: isize, y0: isize, n: usize, out: &mut [f32]) {
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (x0 + i as isize, y0 + j as isize);
            let v = img.at_clamped(x, y);
            let masked = mask.is_some_and(|m| {
                let xi = x.clamp(0, img.width as isize - 1) as usize;
                let yi = y.clamp(0, img.height as isize - 1) as usize;
                m[yi * img.width + xi]
            });
            if masked {
                out[j * n + i] = f32::NAN;
            } else {
                out[j * n + i] = v;
                sum += f64::from(v);
                count += 1;
            }
        }
    }
    let mean = if count > 0 {
        (sum / count as f64) as f32
    } else {
        0.0
    };
    for o in out.iter_mut() {
        *o = if o.is_nan() { 0.0 } else { *o - mean };
    }
}

/// Both frames deformed half-way by `field`: `A(p - d/2)`, `B(p + d/2)`, sampled by quintic
/// B-splines (`a` and `b` hold the frames' spline coefficients). The interpolator matters:
/// its phase error depends on the fractional shift, and the symmetric deformation doubles it
/// into a bias: ~0.05 px sin(pi d) with Keys' cubic convolution, ~0.007 px with cubic
/// B-splines, ~0.004 px with quintic ones (measured on 5 px grains).
fn deform_pair(a: &Image, b: &Image, field: &VectorField) -> (Image, Image) {
    let (w, h) = (a.width, a.height);
    let mut da = vec![0f32; w * h];
    let mut db = vec![0f32; w * h];
    da.par_chunks_mut(w)
        .zip(db.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (ra, rb))| {
            for x in 0..w {
                let (u, v) = field.sample(x as f64, y as f64);
                ra[x] = a.spline(x as f64 - 0.5 * u, y as f64 - 0.5 * v);
                rb[x] = b.spline(x as f64 + 0.5 * u, y as f64 + 0.5 * v);
            }
        });
    (
        Image {
            width: w,
            height: h,
            data: da,
        },
        Image {
            width: w,
            height: h,
            data: db,
        },
    )
}

/// Peak-ratio and normalised-median validation; outliers replaced by their valid neighbours'
/// mean and flagged [`flag::REPLACED`].
pub fn validate(f: &mut VectorField, cfg: &PivConfig) {
    let (nx, ny) = (f.nx, f.ny);
    let mut outlier = vec![false; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            if f.flag[k] == flag::MASKED {
                continue;
            }
            if f.flag[k] == flag::REPLACED || f.peak_ratio[k] < cfg.min_peak_ratio {
                outlier[k] = true;
                continue;
            }
            let neighbours: Vec<usize> = f
                .block(k)
                .filter(|&kk| {
                    kk != k && f.flag[kk] != flag::MASKED && f.peak_ratio[kk] >= cfg.min_peak_ratio
                })
                .collect();
            let mut nu: Vec<f64> = neighbours.iter().map(|&kk| f.u[kk]).collect();
            let mut nv: Vec<f64> = neighbours.iter().map(|&kk| f.v[kk]).collect();
            if nu.len() < 3 {
                continue;
            }
            let test = |vals: &mut Vec<f64>, x: f64| {
                let m = median(vals);
                let mut res: Vec<f64> = vals.iter().map(|v| (v - m).abs()).collect();
                let rm = median(&mut res);
                (x - m).abs() / (rm + 0.1)
            };
            if test(&mut nu, f.u[k]) > cfg.median_threshold
                || test(&mut nv, f.v[k]) > cfg.median_threshold
            {
                outlier[k] = true;
            }
        }
    }
    for (fl, &out) in f.flag.iter_mut().zip(&outlier) {
        if out {
            *fl = flag::REPLACED;
        }
    }
    // Replace: repeated sweeps, each filling outliers that have valid (or filled) neighbours.
    let mut filled: Vec<bool> = (0..nx * ny).map(|k| !outlier[k]).collect();
    for _ in 0..(nx + ny) {
        let mut changed = false;
        let snapshot = filled.clone();
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                if snapshot[k] || f.flag[k] == flag::MASKED {
                    continue;
                }
                if let Some((u, v)) =
                    f.block_mean(k, |kk| snapshot[kk] && f.flag[kk] != flag::MASKED)
                {
                    f.u[k] = u;
                    f.v[k] = v;
                    filled[k] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    for (k, &done) in filled.iter().enumerate() {
        if !done && f.flag[k] != flag::MASKED {
            f.u[k] = 0.0;
            f.v[k] = 0.0;
        }
    }
}

/// A 3 x 3 mean of the unmasked vectors: the predictor a later pass deforms with. A noisy
/// predictor would otherwise add its own noise to every later pass (the new residual only
/// corrects its average over a window), so iterating would not converge.
fn smooth(f: &mut VectorField) {
    let means: Vec<Option<(f64, f64)>> = (0..f.nx * f.ny)
        .map(|k| {
            if f.flag[k] == flag::MASKED {
                return None;
            }
            f.block_mean(k, |kk| f.flag[kk] != flag::MASKED && f.u[kk].is_finite())
        })
        .collect();
    for (k, m) in means.into_iter().enumerate() {
        if let Some((u, v)) = m {
            f.u[k] = u;
            f.v[k] = v;
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
