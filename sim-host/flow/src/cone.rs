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

/// Steepest side that still counts as narrowing, degrees from the horizontal (a steeper fit
/// is a wall within the noise).
pub const MAX_SIDE_ANGLE_DEG: f64 = 85.0;

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
    let nx = xs.len();
    let frame = FootFrame::average(
        samples.iter().map(|s| (s.shear_rate, s.foot_bottom_m, 1.0)),
        nx,
        hs,
        radius_m,
    )?;
    if samples.is_empty() {
        return None;
    }
    let mut rows: Vec<BandRow> = Vec::new();
    let enough = samples.len().div_ceil(2);
    for b in 1..frame.bins {
        // Rows seen in fewer than half the samples (deep under a shallow foot) are not
        // averages; the cone's sides are fitted from the foot down to the first row
        // without bands.
        if frame.count[b] < enough {
            break;
        }
        let mean = |i: usize| frame.mean(b, i);
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
            if dl > MAX_BAND_STEP * frame.spacing || dr > MAX_BAND_STEP * frame.spacing {
                break;
            }
        }
        rows.push(BandRow {
            depth_below_foot_m: b as f64 * frame.spacing,
            left_m: -xs[l],
            right_m: xs[r],
            contrast,
        });
    }
    cone_from_rows(rows, samples.len())
}

/// Fields averaged in the foot's frame: rows binned by their depth below the foot's bottom
/// (one grid spacing a bin, down to `R tan 70`), per bin and column the sum of the finite
/// values (an empty coarse-graining cell is NaN: it must neither poison the average nor be
/// taken for a feature) and their count, and per bin the samples that reached it.
struct FootFrame {
    nx: usize,
    sum: Vec<f64>,
    cells: Vec<usize>,
    count: Vec<usize>,
    bins: usize,
    spacing: f64,
}

impl FootFrame {
    /// Average `fields` (`(field, foot bottom, scale)`: each value times `scale`) on a grid
    /// of `nx` columns and rows at heights `hs`; None for a grid too small or no radius.
    fn average<'a>(
        fields: impl Iterator<Item = (&'a [f64], f64, f64)>,
        nx: usize,
        hs: &[f64],
        radius_m: f64,
    ) -> Option<Self> {
        if hs.len() < 2 || nx < 3 || radius_m <= 0.0 {
            return None;
        }
        let spacing = (hs[1] - hs[0]).abs();
        let bins = (radius_m * 70f64.to_radians().tan() / spacing).ceil() as usize + 1;
        let mut f = Self {
            nx,
            sum: vec![0.0; bins * nx],
            cells: vec![0; bins * nx],
            count: vec![0; bins],
            bins,
            spacing,
        };
        for (field, foot_bottom_m, scale) in fields {
            for (j, &h) in hs.iter().enumerate() {
                let d = foot_bottom_m - h;
                if d < 0.0 {
                    continue;
                }
                let b = (d / spacing).round() as usize;
                if b >= bins {
                    continue;
                }
                f.count[b] += 1;
                for i in 0..nx {
                    let v = field[j * nx + i];
                    if v.is_finite() {
                        f.sum[b * nx + i] += scale * v;
                        f.cells[b * nx + i] += 1;
                    }
                }
            }
        }
        Some(f)
    }

    /// The mean in bin `b`, column `i` (NaN: no finite value fell there).
    fn mean(&self, b: usize, i: usize) -> f64 {
        match self.cells[b * self.nx + i] {
            0 => f64::NAN,
            n => self.sum[b * self.nx + i] / n as f64,
        }
    }
}

/// The cone through `rows` (at least three; `None` otherwise): each side's least-squares line
/// of distance from the axis against depth, its angle from the horizontal, one angle when
/// both sides narrow and agree, the apex where they reach the axis.
fn cone_from_rows(rows: Vec<BandRow>, samples: usize) -> Option<ShearBandCone> {
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
        let a = (1.0 / -slope).atan().to_degrees();
        if slope < 0.0 && a <= MAX_SIDE_ANGLE_DEG {
            a
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
        samples,
        rows,
    })
}

/// One sample's vertical velocity on the grid (`ny` rows of `nx`, row-major, up positive),
/// with the foot's bottom height and down speed.
pub struct MotionSample<'a> {
    /// Vertical velocity per node, m/s (up positive; NaN: an empty cell).
    pub v_up_m_s: &'a [f64],
    /// Height of the foot's bottom, m (the rows' axis).
    pub foot_bottom_m: f64,
    /// The foot's down speed, m/s (positive).
    pub foot_speed_m_s: f64,
}

/// The jammed cone as the region that moves down with the foot: the grains' down speed over
/// the foot's, averaged over `samples` in the foot's frame (as [`shear_band_cone`] averages
/// the shear rate); in each row below the foot the cone's edge on each side is where that
/// ratio, going out from the axis, first falls below half the row's own axis ratio
/// (interpolated between grid columns): the middle of the velocity step a shear band makes,
/// wherever the step's height (a region slowing with depth keeps its walls where they are).
/// The axis's ratio is the mean of the columns within 0.1 R of it. Rows are taken from one
/// grid spacing below the foot down to the first whose axis moves slower than half the foot
/// (below, nothing moves with it), and the sides' lines are fitted through the rows whose
/// edges lie inside the foot's radius (the slanted part; above it the region is as wide as
/// the foot). `contrast` in its rows is the axis's ratio. `None` when fewer than three rows
/// have edges inside the radius; a side steeper than [`MAX_SIDE_ANGLE_DEG`] does not narrow.
pub fn comoving_cone(
    samples: &[MotionSample<'_>],
    xs: &[f64],
    hs: &[f64],
    radius_m: f64,
) -> Option<ShearBandCone> {
    let nx = xs.len();
    let moving: Vec<&MotionSample<'_>> =
        samples.iter().filter(|s| s.foot_speed_m_s > 0.0).collect();
    if moving.is_empty() {
        return None;
    }
    let frame = FootFrame::average(
        moving
            .iter()
            .map(|s| (s.v_up_m_s, s.foot_bottom_m, -1.0 / s.foot_speed_m_s)),
        nx,
        hs,
        radius_m,
    )?;
    let axis = (0..nx).min_by(|&a, &b| xs[a].abs().total_cmp(&xs[b].abs()))?;
    let enough = moving.len().div_ceil(2);
    let mut rows = Vec::new();
    for b in 1..frame.bins {
        if frame.count[b] < enough {
            break;
        }
        let mean = |i: usize| frame.mean(b, i);
        // The axis's ratio: the mean of the columns within 0.1 R of it (one column alone may
        // be empty, or hold a grain or two).
        let near: Vec<f64> = (0..nx)
            .filter(|&i| xs[i].abs() <= (0.1 * radius_m).max(xs[axis].abs()))
            .map(mean)
            .filter(|m| m.is_finite())
            .collect();
        let on_axis = near.iter().sum::<f64>() / near.len() as f64;
        if on_axis.is_nan() || on_axis < 0.5 {
            break;
        }
        // Out from the axis on one side (`step` +1: right, -1: left): where the ratio first
        // falls below half the axis's, interpolated; None if it never does within 1.5 R.
        let half = 0.5 * on_axis;
        let edge = |step: isize| {
            let mut prev = (xs[axis].abs(), on_axis);
            let mut i = axis as isize + step;
            while i >= 0 && (i as usize) < nx && xs[i as usize].abs() <= 1.5 * radius_m {
                let m = mean(i as usize);
                if m.is_finite() {
                    let x = xs[i as usize].abs();
                    if m < half {
                        return Some(prev.0 + (prev.1 - half) / (prev.1 - m) * (x - prev.0));
                    }
                    prev = (x, m);
                }
                i += step;
            }
            None
        };
        let (Some(left), Some(right)) = (edge(-1), edge(1)) else {
            continue;
        };
        if left < radius_m && right < radius_m {
            rows.push(BandRow {
                depth_below_foot_m: b as f64 * frame.spacing,
                left_m: left,
                right_m: right,
                contrast: on_axis,
            });
        }
    }
    cone_from_rows(rows, samples.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_region_moving_with_the_foot_gives_its_cone() {
        // Grains inside a 60 degree cone under a 10 mm foot move down with it, the rest stand
        // still, with a smooth step one grid spacing wide; two samples at different depths.
        let xs: Vec<f64> = (-40..=40).map(|i| i as f64 * 0.0005).collect();
        let hs: Vec<f64> = (0..120).map(|j| -0.06 + j as f64 * 0.0005).collect();
        let (r, t) = (0.01, 60f64.to_radians().tan());
        let field = |foot: f64, v: f64| -> Vec<f64> {
            let mut f = Vec::new();
            for &h in &hs {
                let d = foot - h;
                for &x in &xs {
                    let side = r - d / t;
                    let inside = 0.5 - 0.5 * ((x.abs() - side) / 0.0005).tanh();
                    f.push(if d > 0.0 { -v * inside } else { f64::NAN });
                }
            }
            f
        };
        let (a, b) = (field(-0.005, 0.2), field(-0.008, 0.1));
        let samples = [
            MotionSample {
                v_up_m_s: &a,
                foot_bottom_m: -0.005,
                foot_speed_m_s: 0.2,
            },
            MotionSample {
                v_up_m_s: &b,
                foot_bottom_m: -0.008,
                foot_speed_m_s: 0.1,
            },
        ];
        let c = comoving_cone(&samples, &xs, &hs, r).unwrap();
        assert!((c.angle_deg - 60.0).abs() < 2.0, "{c:?}");
        assert!((c.apex_depth_m - r * t).abs() < 0.001, "{}", c.apex_depth_m);
        // A region as wide as the foot all the way down is no cone.
        let flat: Vec<f64> = hs
            .iter()
            .flat_map(|&h| {
                xs.iter()
                    .map(move |&x| if h < -0.005 && x.abs() < r { -0.2 } else { 0.0 })
            })
            .collect();
        let s = [MotionSample {
            v_up_m_s: &flat,
            foot_bottom_m: -0.005,
            foot_speed_m_s: 0.2,
        }];
        assert!(comoving_cone(&s, &xs, &hs, r).is_none_or(|c| c.angle_deg.is_nan()));
        // Walls that stay put while the whole region slows with depth (the axis from 0.95 to
        // 0.5 of the foot over 15 mm): no cone, whatever a fixed threshold would make of it.
        let slowing: Vec<f64> = hs
            .iter()
            .flat_map(|&h| {
                let d = -0.005 - h;
                let a = (0.95 - 0.45 * d / 0.015).max(0.0);
                xs.iter().map(move |&x| {
                    let inside = 0.5 - 0.5 * ((x.abs() - 0.8 * r) / 0.0015).tanh();
                    if d > 0.0 { -0.2 * a * inside } else { f64::NAN }
                })
            })
            .collect();
        let s = [MotionSample {
            v_up_m_s: &slowing,
            foot_bottom_m: -0.005,
            foot_speed_m_s: 0.2,
        }];
        let c = comoving_cone(&s, &xs, &hs, r);
        assert!(c.as_ref().is_none_or(|c| c.angle_deg.is_nan()), "{c:?}");
    }

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
