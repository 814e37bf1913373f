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
    momentum_in(
        field,
        cal,
        dt_s,
        rho_phi_kg_m3,
        mask,
        Region {
            radius_m: f64::INFINITY,
            top_h_m: f64::INFINITY,
            bottom_h_m: f64::NEG_INFINITY,
        },
    )
}

/// The paper's control volume: the column under the foot, `r <= radius_m` from the axis and
/// below the height `top_h_m` (the foot's bottom, m, up positive from the surface), down to
/// the field's bottom. `P = rho phi Int_0^H Int_0^2pi Int_0^R v r dr dpsi dh`, each half-plane
/// an estimate as in [`grain_momentum`].
pub fn column_momentum(
    field: &VectorField,
    cal: &Calibration,
    dt_s: f64,
    rho_phi_kg_m3: f64,
    mask: Option<(&[bool], usize)>,
    radius_m: f64,
    top_h_m: f64,
) -> Momentum {
    column_momentum_to(
        field,
        cal,
        dt_s,
        rho_phi_kg_m3,
        mask,
        radius_m,
        (top_h_m, f64::NEG_INFINITY),
    )
}

/// [`column_momentum`] between the heights `(top_h_m, bottom_h_m)`, m (up positive): the
/// column cut at a depth `H` (e.g. the jammed cone's `R tan theta`), to see how much of `P`
/// lies deeper.
pub fn column_momentum_to(
    field: &VectorField,
    cal: &Calibration,
    dt_s: f64,
    rho_phi_kg_m3: f64,
    mask: Option<(&[bool], usize)>,
    radius_m: f64,
    (top_h_m, bottom_h_m): (f64, f64),
) -> Momentum {
    momentum_in(
        field,
        cal,
        dt_s,
        rho_phi_kg_m3,
        mask,
        Region {
            radius_m,
            top_h_m,
            bottom_h_m,
        },
    )
}

/// Where momentum is summed: pixels within `radius_m` of the axis and below `top_h_m`. A
/// bounded column weights each grain pixel by its own `r` and half-plane (its edge cuts cells,
/// and a cell-centre `r` would count the cut cells of one side at the radius beyond `R`); the
/// whole window keeps the cell-centre weighting it has always had.
#[derive(Clone, Copy)]
struct Region {
    radius_m: f64,
    top_h_m: f64,
    bottom_h_m: f64,
}

impl Region {
    fn bounded(&self) -> bool {
        self.radius_m.is_finite()
    }

    /// Whether pixel `(x, y)` lies within the column.
    fn holds(&self, cal: &Calibration, x: isize, y: isize) -> bool {
        let h = cal.h_m(y as f64);
        cal.x_m(x as f64).abs() <= self.radius_m && h <= self.top_h_m && h >= self.bottom_h_m
    }
}

fn momentum_in(
    field: &VectorField,
    cal: &Calibration,
    dt_s: f64,
    rho_phi_kg_m3: f64,
    mask: Option<(&[bool], usize)>,
    region: Region,
) -> Momentum {
    let cell = field.step_px as f64 * cal.m_per_px;
    let da = cell * cell;
    let half = 0.5 * field.step_px as f64;
    let (mut left, mut right, mut cells) = (0.0, 0.0, 0);
    let bounded = region.bounded();
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
            // Sum of |x| over the grain pixels of each half-plane, m (bounded columns).
            let (mut r_left, mut r_right) = (0.0, 0.0);
            for y in y0..y1 {
                for x in x0..x1 {
                    total += 1;
                    if (y as f64) < cal.origin_px.1 - 0.5 || (bounded && !region.holds(cal, x, y)) {
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
                        if bounded {
                            let xm = cal.x_m(x as f64);
                            if xm < 0.0 {
                                r_left -= xm;
                            } else {
                                r_right += xm;
                            }
                        }
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
            if bounded {
                let pixel_area = cal.m_per_px * cal.m_per_px;
                left += w * r_left * pixel_area;
                right += w * r_right * pixel_area;
            } else {
                let term = w * x.abs() * da * share;
                if x < 0.0 {
                    left += term;
                } else {
                    right += term;
                }
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

/// The model's added mass (the paper's eq. 6, preset at packing fraction `phi`) for a foot of
/// radius `r_m` (m) at depth `depth_m` (m), kg: the preset's `C` (the 38 mm foot's) scaled with
/// the foot's area, as the stiffnesses are. What the PIV added mass is drawn beside.
pub fn model_added_mass(phi: f64, r_m: f64, depth_m: f64) -> Result<f64, String> {
    use sandjumper_model::ground::{GroundLaw, Sand};
    use sandjumper_model::params::{ModelName, Params};
    let mut params = Params::preset(phi).map_err(|e| e.to_string())?;
    params.sand.added_mass_c_m2 *= (r_m / params.sand.reference_foot_radius_m).powi(2);
    params.robot.foot_radius_m = r_m;
    let law = GroundLaw::resolve(ModelName::Eq4, &params.model);
    Ok(Sand::new(&params, law).added_mass(depth_m))
}

/// Share of eq. 6's complete-cone added mass from which its cone counts as forming: below it
/// eq. 6 is small beside what a measured column carries from contact, and ratios to it
/// measure that offset, not the cone.
pub const CONE_FORMING_FROM_SHARE: f64 = 0.25;

/// The depths over which a measured added mass is compared with eq. 6 where its cone is
/// forming, for a foot of radius `r_m` at `phi`: from the depth where eq. 6 reaches
/// [`CONE_FORMING_FROM_SHARE`] of its complete-cone value to the depth where the cone is
/// complete (`R tan theta / mu`), m.
pub fn cone_forming_depths(phi: f64, r_m: f64) -> Result<(f64, f64), String> {
    use sandjumper_model::ground::{GroundLaw, Sand};
    use sandjumper_model::params::{ModelName, Params};
    let mut params = Params::preset(phi).map_err(|e| e.to_string())?;
    params.sand.added_mass_c_m2 *= (r_m / params.sand.reference_foot_radius_m).powi(2);
    params.robot.foot_radius_m = r_m;
    let sand = Sand::new(&params, GroundLaw::resolve(ModelName::Eq4, &params.model));
    let complete = sand.cone_depth_m();
    if !complete.is_finite() || complete <= 0.0 {
        return Err(format!(
            "eq. 6's cone does not complete at phi {phi} (a jamming front that does not grow)"
        ));
    }
    let target = CONE_FORMING_FROM_SHARE * sand.added_mass(complete);
    // m_a grows monotonically with depth: bisect for the depth where it reaches the share.
    let (mut lo, mut hi) = (0.0, complete);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if sand.added_mass(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((hi, complete))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform field moving down `v_px` px per frame on a grid every `step` px, `n` x `n`
    /// vectors, window `i` over pixels `step i .. step (i + 1)` (pixel centres at their
    /// indices, as in PIV).
    fn uniform(n: usize, step: usize, v_px: f64) -> VectorField {
        let centres: Vec<f64> = (0..n)
            .map(|i| 0.5 * (step as f64 - 1.0) + (step * i) as f64)
            .collect();
        VectorField {
            nx: n,
            ny: n,
            step_px: step,
            xs: centres.clone(),
            ys: centres,
            u: vec![0.0; n * n],
            v: vec![v_px; n * n],
            flag: vec![flag::VALID; n * n],
            peak_ratio: vec![2.0; n * n],
        }
    }

    #[test]
    fn the_column_under_the_foot_holds_pi_rho_phi_v_r2_h() {
        // 1 mm pixels, a 200 x 200 px field, the axis and the surface on pixel edges (the
        // axis between pixels 99 and 100, the surface above row 0), as the DEM's grid has them.
        let field = uniform(50, 4, 1.0);
        let cal = Calibration {
            m_per_px: 1e-3,
            origin_px: (99.5, -0.5),
        };
        let (dt, rho_phi) = (1e-3, 600.0);
        let v = 1e-3 / dt; // 1 m/s down
        let (r, foot_h) = (0.04, -0.05);
        let depth = 0.2 - 0.05; // from the foot's bottom to the field's bottom, m
        let col = column_momentum(&field, &cal, dt, rho_phi, None, r, foot_h);
        let exact = -std::f64::consts::PI * rho_phi * v * r * r * depth;
        let err = (col.momentum_kg_m_s - exact) / exact;
        assert!(
            err.abs() < 0.005,
            "{} vs {exact} ({err:+.3})",
            col.momentum_kg_m_s
        );
        // The two half-planes agree.
        assert!((col.left_kg_m_s - col.right_kg_m_s).abs() < 1e-9 * exact.abs());
        // The wide window holds more than the column.
        let wide = grain_momentum(&field, &cal, dt, rho_phi, None);
        assert!(wide.momentum_kg_m_s.abs() > 2.0 * col.momentum_kg_m_s.abs());
        // Cut at half its depth, the column holds half its momentum.
        let half = column_momentum_to(
            &field,
            &cal,
            dt,
            rho_phi,
            None,
            r,
            (foot_h, foot_h - 0.5 * depth),
        );
        let share = half.momentum_kg_m_s / col.momentum_kg_m_s;
        assert!((share - 0.5).abs() < 0.01, "{share}");
        // Nothing above the surface or beside a zero-width column.
        let none = column_momentum(&field, &cal, dt, rho_phi, None, 0.0, foot_h);
        assert!(none.momentum_kg_m_s.abs() < 1e-3 * exact.abs());
    }

    #[test]
    fn the_cone_forms_from_a_quarter_of_eq6_to_its_completion() {
        // The paper's foot: the cone completes at R tan 60 / 2 = 32.9 mm (docs/model.md).
        let r = 0.038;
        let (from, to) = cone_forming_depths(0.57, r).unwrap();
        assert!(
            (to - r * 60f64.to_radians().tan() / 2.0).abs() < 1e-9,
            "{to}"
        );
        let complete = model_added_mass(0.57, r, to).unwrap();
        let at_from = model_added_mass(0.57, r, from).unwrap();
        assert!((at_from / complete - CONE_FORMING_FROM_SHARE).abs() < 1e-9);
        assert!(from > 0.0 && from < 0.5 * to, "{from} {to}");
        // The depths scale with the foot (every length of eq. 6 does, C with R^2).
        let (from_small, to_small) = cone_forming_depths(0.57, 0.5 * r).unwrap();
        assert!((to_small - 0.5 * to).abs() < 1e-9 && (from_small - 0.5 * from).abs() < 1e-6);
    }
}
