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

/// Largest move of a band from one row to the next, grid spacings.
pub const MAX_BAND_STEP: f64 = 2.0;

/// Largest difference of the two sides' angles for the cone to have one angle, degrees.
pub const MAX_SIDE_DIFFERENCE_DEG: f64 = 10.0;

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
    /// Angle of the sides from the horizontal, degrees: the mean of both sides when both
    /// narrow with depth and differ by at most [`MAX_SIDE_DIFFERENCE_DEG`] (NaN otherwise: no
    /// cone to speak of; the sides are still reported).
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
/// [`MIN_BAND_CONTRAST`] above the row's median or move more than [`MAX_BAND_STEP`] grid
/// spacings from the row above. `None` when fewer than three rows show bands.
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
    // Per cell: the sum of the finite values and their count (an empty coarse-graining cell
    // is NaN: it must neither poison the average nor be taken for a band).
    let mut sum = vec![0.0; bins * nx];
    let mut cells = vec![0usize; bins * nx];
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
                let v = s.shear_rate[j * nx + i];
                if v.is_finite() {
                    sum[b * nx + i] += v;
                    cells[b * nx + i] += 1;
                }
            }
        }
    }
    let mut rows: Vec<BandRow> = Vec::new();
    let enough = samples.len().div_ceil(2);
    for b in 1..bins {
        // Rows seen in fewer than half the samples (deep under a shallow foot) are not
        // averages; the cone's sides are fitted from the foot down to the first row
        // without bands.
        if count[b] < enough {
            break;
        }
        let mean = |i: usize| match cells[b * nx + i] {
            0 => f64::NAN,
            n => sum[b * nx + i] / n as f64,
        };
        let finite = |i: &usize| mean(*i).is_finite();
        let right = (0..nx)
            .filter(|&i| xs[i] >= 0.1 * radius_m && xs[i] <= 1.2 * radius_m)
            .filter(finite)
            .max_by(|&a, &c| mean(a).total_cmp(&mean(c)));
        let left = (0..nx)
            .filter(|&i| xs[i] <= -0.1 * radius_m && xs[i] >= -1.2 * radius_m)
            .filter(finite)
            .max_by(|&a, &c| mean(a).total_cmp(&mean(c)));
        let (Some(l), Some(r)) = (left, right) else {
            continue;
        };
        let mut row: Vec<f64> = (0..nx)
            .filter(|&i| xs[i].abs() <= 1.5 * radius_m)
            .map(mean)
            .filter(|v| v.is_finite())
            .collect();
        if row.is_empty() {
            break;
        }
        row.sort_by(f64::total_cmp);
        let median = row[row.len() / 2];
        let contrast = 0.5 * (mean(l) + mean(r)) / median;
        // A row whose peaks do not stand out has no band to place (beyond the apex, or noise).
        if !(median > 0.0 && contrast >= MIN_BAND_CONTRAST) {
            break;
        }
        // A band follows a line: a jump of more than two grid spacings from the row above is
        // another feature (or noise), where the band as a line has ended.
        if let Some(prev) = rows.last() {
            let (dl, dr) = ((-xs[l] - prev.left_m).abs(), (xs[r] - prev.right_m).abs());
            if dl > MAX_BAND_STEP * spacing || dr > MAX_BAND_STEP * spacing {
                break;
            }
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
    // One angle only when both sides narrow and agree: a one-sided or lopsided fit is no cone.
    let angle_deg = if left_deg.is_finite()
        && right_deg.is_finite()
        && (left_deg - right_deg).abs() <= MAX_SIDE_DIFFERENCE_DEG
    {
        0.5 * (left_deg + right_deg)
    } else {
        f64::NAN
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

    /// The samples of `(field, foot bottom)` pairs.
    fn samples_of(fields: &[(Vec<f64>, f64)]) -> Vec<Sample<'_>> {
        fields
            .iter()
            .map(|(f, foot)| Sample {
                shear_rate: f,
                foot_bottom_m: *foot,
            })
            .collect()
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
            let samples = samples_of(&fields);
            let c = shear_band_cone(&samples, &xs, &hs, 0.03).unwrap();
            assert!((c.angle_deg - deg).abs() < 2.0, "{deg}: {c:?}");
            let apex = 0.03 * deg.to_radians().tan();
            assert!((c.apex_depth_m - apex).abs() < 0.15 * apex, "{deg}: {c:?}");
            assert!(c.rows.iter().all(|r| r.contrast > 3.0));
        }
    }

    #[test]
    fn an_empty_cell_neither_poisons_the_average_nor_becomes_the_band() {
        let xs: Vec<f64> = (-60..=60).map(|i| i as f64 * 1e-3).collect();
        let hs: Vec<f64> = (0..120).map(|j| -(j as f64) * 1e-3).collect();
        let mut fields: Vec<(Vec<f64>, f64)> = [-0.004, -0.008, -0.012]
            .iter()
            .map(|&foot| (field(&xs, &hs, 0.03, 60.0, foot), foot))
            .collect();
        // One empty cell near the right band, 10 mm below the first sample's foot.
        let (j, i) = (14, 80);
        fields[0].0[j * xs.len() + i] = f64::NAN;
        let samples = samples_of(&fields);
        let c = shear_band_cone(&samples, &xs, &hs, 0.03).unwrap();
        assert!(c.rows.len() > 40, "{} rows", c.rows.len());
        assert!((c.angle_deg - 60.0).abs() < 2.0, "{c:?}");
    }

    #[test]
    fn one_sided_bands_give_no_cone_angle() {
        let xs: Vec<f64> = (-60..=60).map(|i| i as f64 * 1e-3).collect();
        let hs: Vec<f64> = (0..120).map(|j| -(j as f64) * 1e-3).collect();
        // The left half's band stays at the foot's edge (vertical), the right narrows.
        let mut f: Vec<f64> = field(&xs, &hs, 0.03, 60.0, -0.004);
        let right_only = f.clone();
        for (j, &h) in hs.iter().enumerate() {
            for (i, &x) in xs.iter().enumerate() {
                if x < 0.0 {
                    let d = -0.004 - h;
                    let band = if d > 0.0 && d < 0.04 {
                        10.0 * (-((x.abs() - 0.03) / 0.002).powi(2)).exp()
                    } else {
                        0.0
                    };
                    f[j * xs.len() + i] = right_only[j * xs.len() + i].min(1.3) + band;
                }
            }
        }
        let s = [Sample {
            shear_rate: &f,
            foot_bottom_m: -0.004,
        }];
        let c = shear_band_cone(&s, &xs, &hs, 0.03).unwrap();
        assert!(c.angle_deg.is_nan(), "{c:?}");
        assert!((c.right_deg - 60.0).abs() < 3.0, "{c:?}");
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
