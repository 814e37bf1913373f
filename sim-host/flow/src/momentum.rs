//! Grain momentum and added mass from a velocity field (the paper's Fig. 6 analysis):
//! `P = rho phi Int Int Int v(r, h) r dr dpsi dh`, assuming azimuthal symmetry about the
//! foot's axis, and `m_a = P / v_foot`.
//!
//! Each half-plane of the side-wall view (left and right of the axis) is taken as the profile
//! of an axisymmetric flow: `P_side = 2 pi rho phi sum(v r dA)` over its cells below the
//! free surface, each weighted by its share of grain pixels (below the surface, outside the
//! mask), `r = |x|`, `dA` the cell's area. The two
//! sides are two estimates of the same momentum: reported apart (their difference says how
//! symmetric the flow is) and averaged for `P`. `v` is the vertical velocity, height up.

use serde::Serialize;

use super::piv::{VectorField, flag};

/// Pixels to metres and seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Calibration {
    /// Metres per pixel.
    pub m_per_px: f64,
    /// The foot's axis at the undisturbed surface, px (x, y): the origin of `x` and `h`.
    pub origin_px: (f64, f64),
}

impl Calibration {
    /// `x` of a pixel column, m (right positive).
    pub fn x_m(&self, x_px: f64) -> f64 {
        (x_px - self.origin_px.0) * self.m_per_px
    }

    /// Height of a pixel row, m (up positive, 0 at the surface).
    pub fn h_m(&self, y_px: f64) -> f64 {
        (self.origin_px.1 - y_px) * self.m_per_px
    }
}

/// The momentum of one field.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Momentum {
    /// From the left half-plane, kg m/s (height up).
    pub left_kg_m_s: f64,
    /// From the right half-plane, kg m/s.
    pub right_kg_m_s: f64,
    /// Their mean, kg m/s.
    pub momentum_kg_m_s: f64,
    /// Cells counted (both sides).
    pub cells: usize,
}

/// Grain momentum of `field` (displacements in px over `dt_s`), with bulk density
/// `rho_phi_kg_m3` (grain density times packing fraction). `mask` (`width` px per row, true:
/// not grains) weights each cell by its share of grain pixels below the surface, so a foot or
/// a mask edge that cuts a cell counts the grains in it once: a cell whose centre is masked
/// but which holds grains takes the mean velocity of its unmasked neighbours.
pub fn grain_momentum(
    field: &VectorField,
    cal: &Calibration,
    dt_s: f64,
    rho_phi_kg_m3: f64,
    mask: Option<(&[bool], usize)>,
) -> Momentum {
    let cell = field.step_px as f64 * cal.m_per_px;
    let da = cell * cell;
    let half = 0.5 * field.step_px as f64;
    let (mut left, mut right, mut cells) = (0.0, 0.0, 0);
    let usable = |k: usize| field.flag[k] != flag::MASKED && field.v[k].is_finite();
    for j in 0..field.ny {
        for i in 0..field.nx {
            let (xc, yc) = (field.xs[i], field.ys[j]);
            // Share of the cell that is grains: below the surface and not masked.
            let (x0, x1) = (
                (xc - half + 0.5).floor() as isize,
                (xc + half + 0.5).floor() as isize,
            );
            let (y0, y1) = (
                (yc - half + 0.5).floor() as isize,
                (yc + half + 0.5).floor() as isize,
            );
            let (mut grain, mut total) = (0usize, 0usize);
            for y in y0..y1 {
                for x in x0..x1 {
                    total += 1;
                    if (y as f64) < cal.origin_px.1 - 0.5 {
                        continue;
                    }
                    let masked = mask.is_some_and(|(m, w)| {
                        x >= 0
                            && y >= 0
                            && (x as usize) < w
                            && (y as usize) * w + (x as usize) < m.len()
                            && m[y as usize * w + x as usize]
                    });
                    if !masked {
                        grain += 1;
                    }
                }
            }
            if grain == 0 || total == 0 {
                continue;
            }
            let share = grain as f64 / total as f64;
            let k = j * field.nx + i;
            let v_px = if usable(k) {
                field.v[k]
            } else {
                match field.block_mean(k, usable) {
                    Some((_, v)) => v,
                    None => continue,
                }
            };
            let x = cal.x_m(xc);
            let w = -v_px * cal.m_per_px / dt_s;
            let term = w * x.abs() * da * share;
            if x < 0.0 {
                left += term;
            } else {
                right += term;
            }
            cells += 1;
        }
    }
    let k = 2.0 * core::f64::consts::PI * rho_phi_kg_m3;
    let (l, r) = (k * left, k * right);
    Momentum {
        left_kg_m_s: l,
        right_kg_m_s: r,
        momentum_kg_m_s: 0.5 * (l + r),
        cells,
    }
}

/// A foot outline per frame: polygon vertices in px.
pub type Polygon = Vec<(f64, f64)>;

/// Whether `(x, y)` lies inside `poly` (even-odd rule).
pub fn inside(poly: &[(f64, f64)], x: f64, y: f64) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (xi, yi) = poly[i];
        let (xj, yj) = poly[(i + n - 1) % n];
        if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
    }
    inside
}

/// The foot's depth below the surface from its outline: its lowest point, m.
pub fn foot_depth_m(poly: &[(f64, f64)], cal: &Calibration) -> f64 {
    let lowest = poly.iter().map(|p| p.1).fold(f64::MIN, f64::max);
    -cal.h_m(lowest)
}
