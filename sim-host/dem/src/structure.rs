//! What the grains' arrangement and flow look like: crystallisation (the hexatic order
//! parameter) and the shape of the jammed region under the intruder (its side angle, 60
//! degrees for the triangles of a monodisperse crystal).

use serde::Serialize;

use super::grains::FREE;
use super::world::World;

/// Mean hexatic order `|psi_6|` of the free grains with at least two contacts: per grain
/// `|mean over contacts of exp(6 i theta)|`, 1 for a perfect triangular lattice, about 0.4
/// and below for a disordered packing. Contacts: centres closer than 1.1 times the sum of
/// radii (grains at rest in a packing barely overlap).
pub fn hexatic_order(w: &World) -> f64 {
    let g = &w.g;
    let n = g.len().min(w.nl.start.len().saturating_sub(1));
    // Per grain: sum of exp(6 i theta) over its contacts, and their count. The bond seen
    // from the partner points the other way, theta + pi, and 6 pi is a whole turn: the
    // same term for both grains.
    let mut acc = vec![(0.0f64, 0.0f64, 0usize); n];
    for i in 0..n {
        if g.kind[i] != FREE {
            continue;
        }
        for e in w.nl.start[i] as usize..w.nl.start[i + 1] as usize {
            let j = w.nl.j[e] as usize;
            if g.kind[j] != FREE {
                continue;
            }
            let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
            let reach = 1.1 * (g.radius[i] + g.radius[j]);
            if dx * dx + dy * dy < reach * reach {
                let th = 6.0 * dy.atan2(dx);
                let (s, c) = th.sin_cos();
                for k in [i, j] {
                    acc[k].0 += c;
                    acc[k].1 += s;
                    acc[k].2 += 1;
                }
            }
        }
    }
    let (mut sum, mut count) = (0.0, 0usize);
    for &(re, im, c) in &acc {
        if c >= 2 {
            sum += re.hypot(im) / c as f64;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { sum / count as f64 }
}

/// The jammed region under the intruder, from the grains moving down with it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JammedRegion {
    /// Angle of its sides from the horizontal, degrees (NaN: too few rows to fit).
    pub side_angle_deg: f64,
    /// Half-width per depth below the intruder: `(depth below the foot, half-width)`, m.
    pub profile: Vec<(f64, f64)>,
    /// Its height below the foot (deepest row with co-moving grains), m.
    pub height_m: f64,
}

/// Grains moving down at more than `share` of the intruder's speed, below its bottom
/// `bottom_m` and within its half-width of the axis `x_axis_m`, binned in rows one grain
/// diameter `d_m` high: each row's half-width (the farthest such grain's edge from the axis,
/// counting only rows that continue the region from the foot down), and a straight-line
/// fit of half-width against depth for the side angle.
pub fn jammed_region(
    w: &World,
    x_axis_m: f64,
    half_width_m: f64,
    bottom_m: f64,
    speed_m_s: f64,
    share: f64,
    d_m: f64,
) -> JammedRegion {
    let g = &w.g;
    let rows = ((2.0 * half_width_m / d_m) as usize).max(2) + 2;
    let mut half = vec![0.0f64; rows];
    for i in 0..g.len() {
        if g.kind[i] != FREE || g.y[i] > bottom_m {
            continue;
        }
        let dx = (g.x[i] - x_axis_m).abs();
        if dx > half_width_m {
            continue;
        }
        if -w.u.y[i] < share * speed_m_s {
            continue;
        }
        let r = ((bottom_m - g.y[i]) / d_m) as usize;
        if r < rows {
            half[r] = half[r].max(dx + g.radius[i]);
        }
    }
    let mut profile = Vec::new();
    for (r, &h) in half.iter().enumerate() {
        if h <= 0.0 {
            break;
        }
        profile.push(((r as f64 + 0.5) * d_m, h.min(half_width_m)));
    }
    let height_m = profile.last().map_or(0.0, |p| p.0);
    // Fit over the rows whose half-width shrinks (skip the first row, which is the foot's).
    let pts: Vec<(f64, f64)> = profile.iter().skip(1).copied().collect();
    let side_angle_deg = if pts.len() >= 3 {
        let n = pts.len() as f64;
        let (mx, my) = (
            pts.iter().map(|p| p.0).sum::<f64>() / n,
            pts.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let slope = sxy / sxx; // d(half-width)/d(depth), negative
        (1.0 / -slope).atan().to_degrees()
    } else {
        f64::NAN
    };
    JammedRegion {
        side_angle_deg,
        profile,
        height_m,
    }
}
