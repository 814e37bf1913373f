//! Image pre-processing before correlation: local contrast normalisation (the default: the
//! paper's "enhancing local contrast" that made untextured poppy seeds trackable, as a filter
//! that adds no displacement bias), CLAHE (PIVlab's default, on fixed tiles: biased by about
//! 0.07 px on real grain images), background subtraction and intensity capping.

use super::local_contrast::local_contrast;
use super::piv::Image;

/// Pre-processing settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Preprocess {
    /// Local contrast normalisation's Gaussian width, px (0: off). Default 4 px, about a
    /// poppy seed at the paper's scale (1 mm at 0.2 mm/px): narrow enough that dim grains
    /// beside bright ones get their own contrast.
    pub local_contrast_sigma_px: f64,
    /// CLAHE tile size, px (0: off, the default). PIVlab's default: 64.
    pub clahe_tile_px: usize,
    /// CLAHE clip limit: the largest share of a tile's pixels one grey level may hold
    /// (PIVlab's 0.01).
    pub clahe_clip: f64,
    /// Subtract the sequence's per-pixel minimum (the static background).
    pub subtract_background: bool,
    /// Cap intensities at median + `cap_sigma` standard deviations (0: off): bright glints
    /// no longer dominate the correlation (Shavit et al. 2007).
    pub cap_sigma: f64,
}

/// The default local contrast width, px.
pub const DEFAULT_LOCAL_CONTRAST_SIGMA_PX: f64 = 4.0;

impl Default for Preprocess {
    fn default() -> Self {
        Self {
            local_contrast_sigma_px: DEFAULT_LOCAL_CONTRAST_SIGMA_PX,
            clahe_tile_px: 0,
            clahe_clip: 0.01,
            subtract_background: false,
            cap_sigma: 0.0,
        }
    }
}

/// Bins of the CLAHE histograms.
const BINS: usize = 256;

/// CLAHE of `img` (values in `0..=max_value`), returned in 0..=255. Each tile's histogram is
/// clipped at `clip` of its pixels (the excess spread evenly over all levels), its cumulative
/// distribution is the tile's mapping, and every pixel's value is the bilinear blend of the
/// mappings of the four nearest tile centres.
pub fn clahe(img: &Image, tile: usize, clip: f64, max_value: f32) -> Image {
    let (w, h) = (img.width, img.height);
    let tile = tile.clamp(8, w.max(h));
    let (tx, ty) = (w.div_ceil(tile), h.div_ceil(tile));
    let scale = (BINS - 1) as f32 / max_value.max(1.0);
    let bin = |v: f32| ((v * scale).round().clamp(0.0, (BINS - 1) as f32)) as usize;
    let mut maps = vec![[0f32; BINS]; tx * ty];
    for j in 0..ty {
        for i in 0..tx {
            let (x0, y0) = (i * tile, j * tile);
            let (x1, y1) = ((x0 + tile).min(w), (y0 + tile).min(h));
            let mut hist = [0f64; BINS];
            for y in y0..y1 {
                for &v in &img.data[y * w + x0..y * w + x1] {
                    hist[bin(v)] += 1.0;
                }
            }
            let n = ((x1 - x0) * (y1 - y0)) as f64;
            let limit = (clip * n).max(1.0);
            let mut excess = 0.0;
            for c in hist.iter_mut() {
                if *c > limit {
                    excess += *c - limit;
                    *c = limit;
                }
            }
            let add = excess / BINS as f64;
            let mut cum = 0.0;
            let map = &mut maps[j * tx + i];
            for (m, c) in map.iter_mut().zip(hist) {
                cum += c + add;
                *m = (255.0 * cum / n) as f32;
            }
        }
    }
    let mut out = vec![0f32; w * h];
    let centre = |k: usize, len: usize| {
        (k * tile) as f32 + 0.5 * ((k * tile + tile).min(len) - k * tile) as f32 - 0.5
    };
    for y in 0..h {
        // Tile rows around y and the weight of the lower one.
        let fy = (0..ty).map(|j| centre(j, h)).collect::<Vec<_>>();
        let (j0, j1, wy) = neighbours(&fy, y as f32);
        for x in 0..w {
            let fx_i = (x / tile).min(tx - 1);
            let cx0 = centre(fx_i, w);
            let (i0, i1) = if (x as f32) < cx0 {
                (fx_i.saturating_sub(1), fx_i)
            } else {
                (fx_i, (fx_i + 1).min(tx - 1))
            };
            let (a, b) = (centre(i0, w), centre(i1, w));
            let wx = if i0 == i1 {
                0.0
            } else {
                ((x as f32 - a) / (b - a)).clamp(0.0, 1.0)
            };
            let v = bin(img.data[y * w + x]);
            let m = |i: usize, j: usize| maps[j * tx + i][v];
            let top = m(i0, j0) * (1.0 - wx) + m(i1, j0) * wx;
            let bottom = m(i0, j1) * (1.0 - wx) + m(i1, j1) * wx;
            out[y * w + x] = top * (1.0 - wy) + bottom * wy;
        }
    }
    Image {
        width: w,
        height: h,
        data: out,
    }
}

fn neighbours(centres: &[f32], p: f32) -> (usize, usize, f32) {
    let n = centres.len();
    if p <= centres[0] || n == 1 {
        return (0, 0, 0.0);
    }
    if p >= centres[n - 1] {
        return (n - 1, n - 1, 0.0);
    }
    let k = centres.iter().position(|&c| c > p).unwrap_or(n - 1);
    let (a, b) = (centres[k - 1], centres[k]);
    (k - 1, k, (p - a) / (b - a))
}

/// Per-pixel minimum over `frames` (the static background).
pub fn background(frames: &[&Image]) -> Option<Image> {
    let first = frames.first()?;
    let mut data = first.data.clone();
    for f in &frames[1..] {
        for (m, &v) in data.iter_mut().zip(&f.data) {
            *m = m.min(v);
        }
    }
    Some(Image {
        width: first.width,
        height: first.height,
        data,
    })
}

/// Cap values above median + `sigmas` standard deviations.
pub fn cap(img: &mut Image, sigmas: f64) {
    let n = img.data.len() as f64;
    let mean = img.data.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let sd = (img
        .data
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let mut sorted = img.data.clone();
    let mid = sorted.len() / 2;
    let (_, &mut median, _) = sorted.select_nth_unstable_by(mid, f32::total_cmp);
    let limit = median + (sigmas * sd) as f32;
    for v in &mut img.data {
        *v = v.min(limit);
    }
}

/// Apply `p` to a frame (`background` already computed when asked for).
pub fn apply(p: &Preprocess, img: &Image, bg: Option<&Image>, max_value: f32) -> Image {
    let mut out = img.clone();
    if let Some(bg) = bg {
        for (o, &b) in out.data.iter_mut().zip(&bg.data) {
            *o = (*o - b).max(0.0);
        }
    }
    if p.cap_sigma > 0.0 {
        cap(&mut out, p.cap_sigma);
    }
    if p.local_contrast_sigma_px > 0.0 {
        out = local_contrast(&out, p.local_contrast_sigma_px, max_value);
    }
    if p.clahe_tile_px > 0 {
        // After a normalisation the values sit around 127.5 (one sd: 32 levels); CLAHE's bins
        // take 0..=255 and clamp the rest.
        let max = if p.local_contrast_sigma_px > 0.0 {
            255.0
        } else {
            max_value
        };
        out = clahe(&out, p.clahe_tile_px, p.clahe_clip, max);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clahe_spreads_a_dim_low_contrast_image_over_the_range_and_keeps_order() {
        let (w, h) = (128, 96);
        let data: Vec<f32> = (0..w * h)
            .map(|k| 40.0 + ((k * 37 % 101) as f32) * 0.2)
            .collect();
        let img = Image {
            width: w,
            height: h,
            data,
        };
        let out = clahe(&img, 32, 0.05, 255.0);
        let (lo, hi) = out
            .data
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(hi - lo > 150.0, "range {lo}..{hi}");
        // Monotone: a brighter input pixel never maps darker within one tile's interior.
        let (a, b) = (img.data[40 * w + 40], img.data[40 * w + 41]);
        let (oa, ob) = (out.data[40 * w + 40], out.data[40 * w + 41]);
        assert_eq!(a < b, oa < ob);
    }
}
