//! Local contrast normalisation: each pixel's difference from its neighbourhood's mean, in
//! units of the neighbourhood's standard deviation (Gaussian weights of `sigma` px).
//!
//! It gives dim, low-contrast parts of a frame (the paper's untextured poppy seeds, an
//! unevenly lit wall) the same contrast as bright ones, as CLAHE does, but it is a filter:
//! it commutes with a translation. A frame shifted by any sub-pixel amount comes out shifted
//! by the same amount (away from the borders), so it adds no bias to the displacement PIV
//! measures. CLAHE's mappings belong to tiles fixed in the frame, which the grains move
//! through: a grain's grey levels change as it crosses them, and the measured displacement
//! is pulled towards the tiles (0.07 px on real grain images).

use rayon::prelude::*;

use super::piv::Image;

/// Added to the local variance so that flat regions (no texture, only noise) are not blown
/// up to full contrast: this share of the full scale, squared.
const FLOOR_SHARE: f32 = 0.003;

/// Grey levels per standard deviation of the output (one sd either side spans a quarter of an
/// 8-bit range).
const Z_SCALE: f32 = 32.0;

/// The normalised frame: `127.5 + 32 z` with `z = (I - m) / sqrt(s^2 + floor^2)`, `m` and
/// `s^2` the local mean and variance (three box filters in a row approximating a Gaussian of
/// `sigma_px`, mirrored at the borders). Linear in `z` and not clipped (the values are
/// floats; sparse bright particles reach `z` of 5 to 10): a saturating map would flatten
/// the particles' tops and lock the correlation peak to whole pixels.
pub fn local_contrast(img: &Image, sigma_px: f64, max_value: f32) -> Image {
    let (w, h) = (img.width, img.height);
    let mean = gaussian(&img.data, w, h, sigma_px);
    let dev: Vec<f32> = img.data.iter().zip(&mean).map(|(v, m)| v - m).collect();
    let sq: Vec<f32> = dev.iter().map(|d| d * d).collect();
    let var = gaussian(&sq, w, h, sigma_px);
    let floor = (FLOOR_SHARE * max_value.max(1.0)).powi(2);
    let data = dev
        .iter()
        .zip(&var)
        .map(|(d, v)| {
            let z = d / (v.max(0.0) + floor).sqrt();
            127.5 + Z_SCALE * z
        })
        .collect();
    Image {
        width: w,
        height: h,
        data,
    }
}

/// Box widths (odd) of three passes whose variances add up to `sigma^2` as nearly as
/// whole widths allow (Kovesi's scheme): `m` passes of `wl`, the rest of `wl + 2`.
fn box_widths(sigma: f64) -> [usize; 3] {
    let n = 3.0;
    let ideal = (12.0 * sigma * sigma / n + 1.0).sqrt();
    let mut wl = ideal.floor() as usize;
    if wl.is_multiple_of(2) {
        wl = wl.saturating_sub(1);
    }
    let wl = wl.max(1);
    let wu = wl + 2;
    let wlf = wl as f64;
    let m = ((12.0 * sigma * sigma - n * wlf * wlf - 4.0 * n * wlf - 3.0 * n) / (-4.0 * wlf - 4.0))
        .round()
        .clamp(0.0, 3.0) as usize;
    std::array::from_fn(|k| if k < m { wl } else { wu })
}

/// Mirrored index (`-1 -> 0`, `n -> n - 1`), for offsets within one length of the range.
#[inline]
fn mirror(i: isize, n: usize) -> usize {
    let n = n as isize;
    let j = if i < 0 {
        -i - 1
    } else if i >= n {
        2 * n - 1 - i
    } else {
        i
    };
    j.clamp(0, n - 1) as usize
}

/// Three box passes along rows, then along columns.
fn gaussian(data: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    let mut cur = data.to_vec();
    for width in box_widths(sigma) {
        cur = box_rows(&cur, w, (width / 2).min(w.saturating_sub(1)));
        cur = box_columns(&cur, w, h, (width / 2).min(h.saturating_sub(1)));
    }
    cur
}

fn box_rows(data: &[f32], w: usize, r: usize) -> Vec<f32> {
    let mut out = vec![0f32; data.len()];
    let norm = 1.0 / (2 * r + 1) as f64;
    out.par_chunks_mut(w)
        .zip(data.par_chunks(w))
        .for_each(|(o, row)| {
            let at = |i: isize| f64::from(row[mirror(i, w)]);
            let mut sum: f64 = (-(r as isize)..=r as isize).map(at).sum();
            for (x, ox) in o.iter_mut().enumerate() {
                *ox = (sum * norm) as f32;
                let x = x as isize;
                sum += at(x + r as isize + 1) - at(x - r as isize);
            }
        });
    out
}

fn box_columns(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let mut out = vec![0f32; data.len()];
    let norm = 1.0 / (2 * r + 1) as f64;
    let row = |y: isize| &data[mirror(y, h) * w..][..w];
    let mut sum = vec![0f64; w];
    for y in -(r as isize)..=r as isize {
        for (s, &v) in sum.iter_mut().zip(row(y)) {
            *s += f64::from(v);
        }
    }
    for (y, o) in out.chunks_mut(w).enumerate() {
        for (ox, s) in o.iter_mut().zip(&sum) {
            *ox = (s * norm) as f32;
        }
        let y = y as isize;
        let (add, sub) = (row(y + r as isize + 1), row(y - r as isize));
        for ((s, &a), &b) in sum.iter_mut().zip(add).zip(sub) {
            *s += f64::from(a) - f64::from(b);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Image {
        Image {
            width: w,
            height: h,
            data: (0..w * h).map(|k| f(k % w, k / w)).collect(),
        }
    }

    #[test]
    fn three_boxes_have_the_variance_of_the_gaussian() {
        for sigma in [2.0, 5.0, 16.0, 40.0] {
            let var: f64 = box_widths(sigma)
                .iter()
                .map(|&b| ((b * b) as f64 - 1.0) / 12.0)
                .sum();
            assert!(
                (var.sqrt() - sigma).abs() < 0.35 + 0.02 * sigma,
                "sigma {sigma}: {}",
                var.sqrt()
            );
        }
    }

    #[test]
    fn the_blur_keeps_a_constant_and_the_mean_of_a_ramp() {
        let (w, h) = (50, 40);
        let c = gaussian(&vec![3.0; w * h], w, h, 4.0);
        assert!(c.iter().all(|&v| (v - 3.0).abs() < 1e-5));
        // Away from the borders a linear ramp is its own local mean.
        let ramp: Vec<f32> = (0..w * h).map(|k| (k % w) as f32).collect();
        let m = gaussian(&ramp, w, h, 4.0);
        for x in 15..35 {
            assert!(
                (m[20 * w + x] - x as f32).abs() < 1e-3,
                "{x}: {}",
                m[20 * w + x]
            );
        }
    }

    #[test]
    fn dim_and_bright_halves_come_out_with_the_same_contrast() {
        // The same texture at 1/10 of the brightness and contrast on the left.
        let tex = |x: usize, y: usize| ((x * 7 + y * 13) % 17) as f32;
        let img = image(128, 64, |x, y| {
            if x < 64 {
                10.0 + 0.6 * tex(x, y)
            } else {
                100.0 + 6.0 * tex(x, y)
            }
        });
        let out = local_contrast(&img, 8.0, 255.0);
        let sd = |x0: usize| {
            let v: Vec<f32> = (16..48)
                .flat_map(|y| (x0..x0 + 24).map(move |x| (x, y)))
                .map(|(x, y)| out.data[y * 128 + x])
                .collect();
            let m = v.iter().sum::<f32>() / v.len() as f32;
            (v.iter().map(|a| (a - m).powi(2)).sum::<f32>() / v.len() as f32).sqrt()
        };
        let (dim, bright) = (sd(6), sd(98));
        assert!(
            dim > 0.8 * Z_SCALE && (dim / bright - 1.0).abs() < 0.1,
            "{dim} {bright}"
        );
    }

    #[test]
    fn it_commutes_with_a_whole_pixel_shift_away_from_the_borders() {
        let f = |x: usize, y: usize| (((x * x + 3 * y) % 23) as f32) * (1.0 + x as f32 / 50.0);
        let a = image(120, 90, f);
        let b = image(120, 90, |x, y| f(x.saturating_sub(3), y.saturating_sub(2)));
        let (na, nb) = (
            local_contrast(&a, 5.0, 255.0),
            local_contrast(&b, 5.0, 255.0),
        );
        for y in 30..60 {
            for x in 30..90 {
                let d = na.data[(y - 2) * 120 + x - 3] - nb.data[y * 120 + x];
                assert!(d.abs() < 1e-3, "({x}, {y}): {d}");
            }
        }
    }
}
