//! The jammed cone under the foot from its shear bands: where the strain rate peaks on each
//! side of the foot's axis, row by row below the foot, and the angle of the lines through
//! those peaks (the paper: sides about 60 degrees from the horizontal).
//!
//! One sample's field is noisy (grain-scale fluctuations are as strong as the bands), so the
//! fields of the samples where the foot intrudes are averaged in the foot's frame: each row
//! at its depth below the foot's bottom at that sample.

use serde::Serialize;

/// A row's band peaks must reach this multiple of the row's median to be placed.
pub const MIN_BAND_CONTRAST: f64 = 1.5;

/// The bands' positions at one depth below the foot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BandRow {
    /// Depth below the foot's bottom, m.
    pub depth_below_foot_m: f64,
    /// Left band's distance from the axis, m (positive).
    pub left_m: f64,
    /// Right band's distance from the axis, m.
    pub right_m: f64,
    /// The bands' mean peak over the row's median within 1.5 R: how clear they are.
    pub contrast: f64,
}

/// The cone its shear bands outline.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShearBandCone {
    /// Angle of the sides from the horizontal, degrees (mean of both sides; NaN: no side
    /// narrows with depth, no cone).
    pub angle_deg: f64,
    /// Left side's angle, degrees (NaN: it does not narrow).
    pub left_deg: f64,
    /// Right side's angle, degrees.
    pub right_deg: f64,
    /// Half the difference of the two sides, degrees: a measure of the fit's spread.
    pub spread_deg: f64,
    /// Where the fitted sides meet below the foot's bottom, m (the cone's height).
    pub apex_depth_m: f64,
    /// Samples averaged.
    pub samples: usize,
    /// The rows the lines were fitted to.
    pub rows: Vec<BandRow>,
}

/// One sample's field: the shear rate on the grid (`ny` rows of `nx`, row-major), the foot's
/// bottom height on the same axis as the rows' heights.
pub struct Sample<'a> {
    /// Shear rate per node, 1/s.
    pub shear_rate: &'a [f64],
    /// Height of the foot's bottom, m (the rows' axis: up positive).
    pub foot_bottom_m: f64,
}

/// The cone from `samples` on a grid with column positions `xs` (from the foot's axis, m)
/// and row heights `hs` (m, up positive, evenly spaced), for a foot of radius `radius_m`.
/// Rows from one grid spacing to `R tan 70` below the foot are fitted (the cone of the paper,
/// 60 degrees, reaches `R tan 60`); the band is sought between `0.1 R` and `1.2 R` from the
/// axis on each side, from the foot down to the first row whose peaks stand less than
/// [`MIN_BAND_CONTRAST`] above the row's median. `None` when fewer than three rows show bands.
pub fn shear_band_cone(
    samples: &[Sample<'_>],
    xs: &[f64],
    hs: &[f64],
    radius_m: f64,
) -> Option<ShearBandCone> {
    let (nx, ny) = (xs.len(), hs.len());
    if samples.is_empty() || ny < 2 || nx < 3 || radius_m <= 0.0 {
        return None;
    }
    let spacing = (hs[1] - hs[0]).abs();
    let deepest = radius_m * 70f64.to_radians().tan();
    let bins = (deepest / spacing).ceil() as usize + 1;
    let mut sum = vec![0.0; bins * nx];
    let mut count = vec![0usize; bins];
    for s in samples {
        for (j, &h) in hs.iter().enumerate() {
            let d = s.foot_bottom_m - h;
            if d < 0.0 {
                continue;
            }
            let b = (d / spacing).round() as usize;
            if b >= bins {
                continue;
            }
            count[b] += 1;
            for i in 0..nx {
                sum[b * nx + i] += s.shear_rate[j * nx + i];
            }
        }
    }
    let mut rows = Vec::new();
    let enough = samples.len().div_ceil(2);
    for b in 1..bins {
        // Rows seen in fewer than half the samples (deep under a shallow foot) are not
        // averages; the cone's sides are fitted from the foot down to the first row
        // without bands.
        if count[b] < enough {
            break;
        }
        let mean = |i: usize| sum[b * nx + i] / count[b] as f64;
        let right = (0..nx)
            .filter(|&i| xs[i] >= 0.1 * radius_m && xs[i] <= 1.2 * radius_m)
            .max_by(|&a, &c| mean(a).total_cmp(&mean(c)));
        let left = (0..nx)
            .filter(|&i| xs[i] <= -0.1 * radius_m && xs[i] >= -1.2 * radius_m)
            .max_by(|&a, &c| mean(a).total_cmp(&mean(c)));
        let (Some(l), Some(r)) = (left, right) else {
            continue;
        };
        let mut row: Vec<f64> = (0..nx)
            .filter(|&i| xs[i].abs() <= 1.5 * radius_m)
            .map(mean)
            .collect();
        row.sort_by(f64::total_cmp);
        let median = row[row.len() / 2];
        let contrast = 0.5 * (mean(l) + mean(r)) / median;
        // A row whose peaks do not stand out has no band to place (beyond the apex, or noise).
        if !(median > 0.0 && contrast >= MIN_BAND_CONTRAST) {
            break;
        }
        rows.push(BandRow {
            depth_below_foot_m: b as f64 * spacing,
            left_m: -xs[l],
            right_m: xs[r],
            contrast,
        });
    }
    if rows.len() < 3 {
        return None;
    }
    // Least squares of distance from the axis against depth: the side's slope.
    let fit = |side: &dyn Fn(&BandRow) -> f64| {
        let n = rows.len() as f64;
        let (mx, my) = (
            rows.iter().map(|r| r.depth_below_foot_m).sum::<f64>() / n,
            rows.iter().map(side).sum::<f64>() / n,
        );
        let sxy: f64 = rows
            .iter()
            .map(|r| (r.depth_below_foot_m - mx) * (side(r) - my))
            .sum();
        let sxx: f64 = rows
            .iter()
            .map(|r| (r.depth_below_foot_m - mx).powi(2))
            .sum();
        let slope = sxy / sxx;
        (slope, my - slope * mx)
    };
    let angle = |slope: f64| {
        if slope < 0.0 {
            (1.0 / -slope).atan().to_degrees()
        } else {
            f64::NAN
        }
    };
    let (ls, li) = fit(&|r: &BandRow| r.left_m);
    let (rs, ri) = fit(&|r: &BandRow| r.right_m);
    let (left_deg, right_deg) = (angle(ls), angle(rs));
    let both = [left_deg, right_deg];
    let good: Vec<f64> = both.iter().copied().filter(|a| a.is_finite()).collect();
    let angle_deg = if good.is_empty() {
        f64::NAN
    } else {
        good.iter().sum::<f64>() / good.len() as f64
    };
    // Where each side reaches the axis; the apex is their mean.
    let apex = |s: f64, i: f64| if s < 0.0 { -i / s } else { f64::NAN };
    Some(ShearBandCone {
        angle_deg,
        left_deg,
        right_deg,
        spread_deg: 0.5 * (left_deg - right_deg).abs(),
        apex_depth_m: 0.5 * (apex(ls, li) + apex(rs, ri)),
        samples: samples.len(),
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field with bands along a cone of `deg` under a foot of radius `r` at `foot` height,
    /// plus a deterministic ripple.
    fn field(xs: &[f64], hs: &[f64], r: f64, deg: f64, foot: f64) -> Vec<f64> {
        let t = deg.to_radians().tan();
        let mut f = Vec::new();
        for (j, &h) in hs.iter().enumerate() {
            let d = foot - h;
            for (i, &x) in xs.iter().enumerate() {
                let side = r - d / t; // the cone's half-width at this depth
                let band = if d > 0.0 && side > 0.0 {
                    10.0 * (-((x.abs() - side) / 0.002).powi(2)).exp()
                } else {
                    0.0
                };
                f.push(band + 1.0 + 0.3 * (((i * 7 + j * 3) % 5) as f64) / 5.0);
            }
        }
        f
    }

    #[test]
    fn the_bands_of_a_60_and_a_45_degree_cone_give_their_angles() {
        let xs: Vec<f64> = (-60..=60).map(|i| i as f64 * 1e-3).collect();
        let hs: Vec<f64> = (0..120).map(|j| -(j as f64) * 1e-3).collect();
        for deg in [60.0, 45.0] {
            let fields: Vec<(Vec<f64>, f64)> = [-0.004, -0.008, -0.012]
                .iter()
                .map(|&foot| (field(&xs, &hs, 0.03, deg, foot), foot))
                .collect();
            let samples: Vec<Sample<'_>> = fields
                .iter()
                .map(|(f, foot)| Sample {
                    shear_rate: f,
                    foot_bottom_m: *foot,
                })
                .collect();
            let c = shear_band_cone(&samples, &xs, &hs, 0.03).unwrap();
            assert!((c.angle_deg - deg).abs() < 2.0, "{deg}: {c:?}");
            let apex = 0.03 * deg.to_radians().tan();
            assert!((c.apex_depth_m - apex).abs() < 0.15 * apex, "{deg}: {c:?}");
            assert!(c.rows.iter().all(|r| r.contrast > 3.0));
        }
    }

    #[test]
    fn a_field_without_bands_has_no_cone_angle_worth_the_name() {
        let xs: Vec<f64> = (-60..=60).map(|i| i as f64 * 1e-3).collect();
        let hs: Vec<f64> = (0..120).map(|j| -(j as f64) * 1e-3).collect();
        let flat = vec![1.0; xs.len() * hs.len()];
        let s = [Sample {
            shear_rate: &flat,
            foot_bottom_m: -0.005,
        }];
        assert_eq!(shear_band_cone(&s, &xs, &hs, 0.03), None);
    }
}
