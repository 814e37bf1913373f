//! Exact sub-pixel translation of a real image: the test of a PIV on real texture, where no
//! renderer knows the truth.
//!
//! The image is mirrored into a periodic one of twice its width and height (no jump at the
//! borders to ring), its spectrum multiplied by the translation's phase, and the original
//! quarter cut back out: for the band-limited image the samples describe, the result is the
//! image moved by exactly `(dx, dy)`. Near the borders the mirror's kink leaves a small
//! error: keep a margin of a few shifts.

use rustfft::FftPlannerScalar;
use rustfft::num_complex::Complex;

use super::piv::Image;

/// `img` moved by `(dx, dy)` px (x right, y down): `out(x, y) = img(x - dx, y - dy)`.
pub fn translate(img: &Image, dx: f64, dy: f64) -> Image {
    let (w, h) = (img.width, img.height);
    let (ew, eh) = (2 * w, 2 * h);
    let mut buf: Vec<Complex<f64>> = (0..ew * eh)
        .map(|k| {
            let (x, y) = (k % ew, k / ew);
            let sx = if x < w { x } else { ew - 1 - x };
            let sy = if y < h { y } else { eh - 1 - y };
            Complex::new(f64::from(img.data[sy * w + sx]), 0.0)
        })
        .collect();
    // The scalar planner: this test tool needs no SIMD, and the full planner's AVX and SSE
    // kernels for f64 took two thirds of the crate's build (about 130 s of CPU on 2 cores).
    let mut planner = FftPlannerScalar::new();
    let (row_fwd, col_fwd) = (planner.plan_fft_forward(ew), planner.plan_fft_forward(eh));
    let (row_inv, col_inv) = (planner.plan_fft_inverse(ew), planner.plan_fft_inverse(eh));
    row_fwd.process(&mut buf);
    transpose_apply(&mut buf, ew, eh, |col| col_fwd.process(col));
    // Phase of the translation; frequencies above Nyquist are the negative ones.
    let freq = |k: usize, n: usize| {
        if 2 * k > n {
            k as f64 - n as f64
        } else if 2 * k == n {
            0.0 // the Nyquist term of a real image cannot move by a fraction: leave it
        } else {
            k as f64
        }
    };
    let tau = std::f64::consts::TAU;
    for (k, v) in buf.iter_mut().enumerate() {
        let (kx, ky) = (freq(k % ew, ew), freq(k / ew, eh));
        let phase = -tau * (kx * dx / ew as f64 + ky * dy / eh as f64);
        *v *= Complex::from_polar(1.0, phase);
    }
    transpose_apply(&mut buf, ew, eh, |col| col_inv.process(col));
    row_inv.process(&mut buf);
    let norm = 1.0 / (ew * eh) as f64;
    let data = (0..w * h)
        .map(|k| (buf[(k / w) * ew + k % w].re * norm) as f32)
        .collect();
    Image {
        width: w,
        height: h,
        data,
    }
}

/// Run `f` on every column of the `w x h` row-major `buf` (through a transposed copy).
fn transpose_apply(
    buf: &mut [Complex<f64>],
    w: usize,
    h: usize,
    mut f: impl FnMut(&mut [Complex<f64>]),
) {
    let mut t = vec![Complex::new(0.0, 0.0); w * h];
    for y in 0..h {
        for x in 0..w {
            t[x * h + y] = buf[y * w + x];
        }
    }
    for col in t.chunks_mut(h) {
        f(col);
    }
    for y in 0..h {
        for x in 0..w {
            buf[y * w + x] = t[x * h + y];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_whole_pixel_shift_moves_the_samples_and_a_smooth_field_moves_exactly() {
        let (w, h) = (40, 30);
        let f = |x: f64, y: f64| (0.3 * x).sin() * (0.2 * y).cos() + 0.01 * x;
        let img = Image {
            width: w,
            height: h,
            data: (0..w * h)
                .map(|k| f((k % w) as f64, (k / w) as f64) as f32)
                .collect(),
        };
        for (dx, dy) in [(2.0, 1.0), (0.25, -0.75), (1.5, 2.25)] {
            let out = translate(&img, dx, dy);
            for y in 8..h - 8 {
                for x in 8..w - 8 {
                    let want = f(x as f64 - dx, y as f64 - dy);
                    let got = f64::from(out.data[y * w + x]);
                    assert!(
                        (got - want).abs() < 0.02,
                        "({dx}, {dy}) at ({x}, {y}): {got} vs {want}"
                    );
                }
            }
        }
    }
}
