//! Coarse graining: the grains' velocities onto a PIV-like grid, and from there through the
//! same code as PIV ([`sandjumper_flow`]): eq. 2's shear rate, vorticity, grain momentum and
//! added mass. The paper computed the DEM's momentum "identically to PIV"; here that holds by
//! construction: the grid becomes a [`VectorField`] in virtual pixels and goes through
//! [`grain_momentum`] and [`column_momentum_to`] ([`sample_momenta`]).
//!
//! Mass-weighted Gaussian coarse graining (Goldhirsch's): with `phi(r) = exp(-r^2 / 2w^2) /
//! (2 pi w^2)`, density `rho(r) = sum m_i phi(r - r_i)`, momentum density `p(r) = sum m_i v_i
//! phi(r - r_i)`, velocity `p / rho`. The kernel is cut at 3 w. Nodes where `rho` is below a
//! share of the bed's mean (outside the grains, inside the intruder) have no velocity (NaN).

use serde::Serialize;

use super::grains::FREE;
use super::world::World;
use sandjumper_flow::fields::Grid;
use sandjumper_flow::momentum::{Calibration, Momentum, column_momentum_to, grain_momentum};
use sandjumper_flow::piv::{VectorField, flag};

/// A grid over the bed: nodes every `spacing_m`, from `x0` to the right and from `top` down.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GridSpec {
    /// x of column 0, m.
    pub x0_m: f64,
    /// Height of row 0, m (rows go down).
    pub top_m: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Spacing, m.
    pub spacing_m: f64,
    /// Gaussian width `w`, m.
    pub width_m: f64,
    /// Nodes whose density is below this share of the bed's mean have no velocity.
    pub min_density_share: f64,
}

/// A coarse-grained field.
#[derive(Clone, Debug, PartialEq)]
pub struct CoarseField {
    /// Velocity along x, m/s.
    pub u: Grid,
    /// Velocity up, m/s.
    pub v: Grid,
    /// Mass density, kg/m^2 (per unit of the 2-D plane).
    pub density: Grid,
}

impl GridSpec {
    /// Position of node `(i, j)`, m.
    pub fn node(&self, i: usize, j: usize) -> (f64, f64) {
        (
            self.x0_m + i as f64 * self.spacing_m,
            self.top_m - j as f64 * self.spacing_m,
        )
    }
}

/// Coarse-grain the free grains of `w` (their full-step velocities) onto `spec`.
/// `bulk_density` (kg/m^2) is what `min_density_share` is a share of.
pub fn coarse_grain(w: &World, spec: &GridSpec, bulk_density: f64) -> CoarseField {
    let (nx, ny, h) = (spec.nx, spec.ny, spec.spacing_m);
    let mut rho = vec![0.0; nx * ny];
    let mut px = vec![0.0; nx * ny];
    let mut py = vec![0.0; nx * ny];
    let s2 = 2.0 * spec.width_m * spec.width_m;
    let norm = 1.0 / (core::f64::consts::PI * s2);
    let reach = 3.0 * spec.width_m;
    let g = &w.g;
    for i in 0..g.len() {
        if g.kind[i] != FREE {
            continue;
        }
        let m = 1.0 / g.inv_mass[i];
        let (x, y) = (g.x[i], g.y[i]);
        let (ux, uy) = (w.u.x[i], w.u.y[i]);
        let c0 = ((x - reach - spec.x0_m) / h).ceil().max(0.0) as usize;
        let c1 = (((x + reach - spec.x0_m) / h).floor() as isize).min(nx as isize - 1);
        let r0 = ((spec.top_m - (y + reach)) / h).ceil().max(0.0) as usize;
        let r1 = (((spec.top_m - (y - reach)) / h).floor() as isize).min(ny as isize - 1);
        if c1 < 0 || r1 < 0 {
            continue;
        }
        for r in r0..=r1 as usize {
            for c in c0..=c1 as usize {
                let (gx, gy) = spec.node(c, r);
                let d2 = (gx - x).powi(2) + (gy - y).powi(2);
                if d2 > reach * reach {
                    continue;
                }
                let wgt = m * norm * (-d2 / s2).exp();
                let k = r * nx + c;
                rho[k] += wgt;
                px[k] += wgt * ux;
                py[k] += wgt * uy;
            }
        }
    }
    let floor = spec.min_density_share * bulk_density;
    let u: Vec<f64> = (0..nx * ny)
        .map(|k| {
            if rho[k] > floor {
                px[k] / rho[k]
            } else {
                f64::NAN
            }
        })
        .collect();
    let v: Vec<f64> = (0..nx * ny)
        .map(|k| {
            if rho[k] > floor {
                py[k] / rho[k]
            } else {
                f64::NAN
            }
        })
        .collect();
    CoarseField {
        u: Grid::new(nx, ny, h, u),
        v: Grid::new(nx, ny, h, v),
        density: Grid::new(nx, ny, h, rho),
    }
}

/// Virtual pixels per grid spacing when a field is handed to the PIV code.
pub const PX_PER_NODE: usize = 16;

/// The field as a PIV vector field in virtual pixels (`PX_PER_NODE` per node; the image's
/// top-left corner at `(x0 - spacing/2, top + spacing/2)`), displacements over `dt_s`; nodes
/// without velocity are masked. Returns it with its calibration, the axis at `x_axis_m` and
/// the undisturbed surface at `surface_m`.
pub fn as_vector_field(
    f: &CoarseField,
    spec: &GridSpec,
    dt_s: f64,
    x_axis_m: f64,
    surface_m: f64,
) -> (VectorField, Calibration) {
    let m_per_px = spec.spacing_m / PX_PER_NODE as f64;
    let left = spec.x0_m - 0.5 * spec.spacing_m;
    let top = spec.top_m + 0.5 * spec.spacing_m;
    let half = 0.5 * PX_PER_NODE as f64;
    let xs = (0..spec.nx)
        .map(|i| half + (i * PX_PER_NODE) as f64)
        .collect();
    let ys = (0..spec.ny)
        .map(|j| half + (j * PX_PER_NODE) as f64)
        .collect();
    let n = spec.nx * spec.ny;
    let mut u = vec![f64::NAN; n];
    let mut v = vec![f64::NAN; n];
    let mut fl = vec![flag::MASKED; n];
    for k in 0..n {
        let (a, b) = (f.u.values[k], f.v.values[k]);
        if a.is_finite() && b.is_finite() {
            u[k] = a * dt_s / m_per_px;
            v[k] = -b * dt_s / m_per_px;
            fl[k] = flag::VALID;
        }
    }
    let field = VectorField {
        nx: spec.nx,
        ny: spec.ny,
        step_px: PX_PER_NODE,
        xs,
        ys,
        u,
        v,
        flag: fl,
        peak_ratio: vec![f64::NAN; n],
    };
    let cal = Calibration {
        m_per_px,
        origin_px: ((x_axis_m - left) / m_per_px, (top - surface_m) / m_per_px),
    };
    (field, cal)
}

/// The momenta of one sample, computed by the PIV code on the coarse-grained field (down is
/// negative: height up, as the flow code has it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleMomenta {
    /// The wide window: every grain below the surface on each side of the axis, the
    /// intruder's own region masked like the foot in a PIV frame (a diagnostic).
    pub window: Momentum,
    /// The paper's control volume: the column under the intruder, `r <= R` from the axis and
    /// below its bottom, down to the window's bottom ([`column_momentum_to`]).
    pub under_foot: Momentum,
    /// The same column cut at the jammed cone's depth ([`cone_depth_m`]) under the intruder.
    pub under_foot_to_cone: Momentum,
    /// The columns of radius `2R` and `3R` below the foot (the wide window's split into bands
    /// around the paper's column).
    pub under_foot_2r: Momentum,
    /// Radius `3R`.
    pub under_foot_3r: Momentum,
    /// The column under the foot down to a tenth of its depth above the window's bottom: the
    /// rest is the column's momentum in the window's bottom tenth (motion there means `P`
    /// depends on how deep the window reaches).
    pub under_foot_above_bottom_tenth: Momentum,
}

/// The momenta of the coarse-grained field `f` (`rho_phi`: grain density times the bed's
/// packing fraction, kg/m^3) about the axis `x_axis_m`, with the intruder at `foot` (left,
/// right, bottom, m).
pub fn sample_momenta(
    f: &CoarseField,
    spec: &GridSpec,
    x_axis_m: f64,
    surface_m: f64,
    rho_phi_kg_m3: f64,
    foot: (f64, f64, f64),
) -> SampleMomenta {
    let dt = 1.0e-3;
    let (field, cal) = as_vector_field(f, spec, dt, x_axis_m, surface_m);
    let w = spec.nx * PX_PER_NODE;
    let h = spec.ny * PX_PER_NODE;
    let left = spec.x0_m - 0.5 * spec.spacing_m;
    let top = spec.top_m + 0.5 * spec.spacing_m;
    let mut mask = vec![false; w * h];
    for y in 0..h {
        let ym = top - (y as f64 + 0.5) * cal.m_per_px;
        if ym < foot.2 {
            continue;
        }
        for x in 0..w {
            let xm = left + (x as f64 + 0.5) * cal.m_per_px;
            if xm >= foot.0 && xm <= foot.1 {
                mask[y * w + x] = true;
            }
        }
    }
    let window = grain_momentum(&field, &cal, dt, rho_phi_kg_m3, Some((&mask, w)));
    // The flow code puts a pixel's centre at its index; this grid's pixel `k` spans
    // [k, k + 1): the column shifts the origin by half a pixel so each pixel's `r` is its
    // centre's (the window keeps the weighting it has always had).
    let centred = Calibration {
        origin_px: (cal.origin_px.0 - 0.5, cal.origin_px.1 - 0.5),
        ..cal
    };
    let radius_m = 0.5 * (foot.1 - foot.0);
    let foot_h = foot.2 - surface_m;
    let column = |radius_m: f64, bottom_h_m: f64| {
        column_momentum_to(
            &field,
            &centred,
            dt,
            rho_phi_kg_m3,
            None,
            radius_m,
            (foot_h, bottom_h_m),
        )
    };
    SampleMomenta {
        window,
        under_foot: column(radius_m, f64::NEG_INFINITY),
        under_foot_to_cone: column(radius_m, foot_h - cone_depth_m(radius_m)),
        under_foot_2r: column(2.0 * radius_m, f64::NEG_INFINITY),
        under_foot_3r: column(3.0 * radius_m, f64::NEG_INFINITY),
        under_foot_above_bottom_tenth: {
            let bottom_h = spec.top_m - (spec.ny as f64 - 0.5) * spec.spacing_m - surface_m;
            column(radius_m, bottom_h + 0.1 * (foot_h - bottom_h))
        },
    }
}

/// The jammed cone's depth under a foot of radius `r_m` with sides at the paper's 60 degrees,
/// `R tan 60`, m: how deep the column must reach to hold the cone.
pub fn cone_depth_m(r_m: f64) -> f64 {
    r_m * 60f64.to_radians().tan()
}

#[cfg(test)]
mod momenta_tests {
    use super::*;

    /// Every grain below the surface moving down at 1 m/s: the columns' momenta go as the
    /// square of their radius (`Int_0^R v r dr`), so the bands `R..2R` and `2R..3R` hold 3 and
    /// 5 times the column's; a tenth of the column's depth holds a tenth of its momentum.
    #[test]
    fn bands_and_the_bottom_tenth_of_a_uniform_downflow() {
        let spec = GridSpec {
            x0_m: -0.05,
            top_m: 0.0,
            nx: 101,
            ny: 61,
            spacing_m: 0.001,
            width_m: 0.001,
            min_density_share: 0.1,
        };
        let n = spec.nx * spec.ny;
        let field = CoarseField {
            u: Grid::new(spec.nx, spec.ny, spec.spacing_m, vec![0.0; n]),
            v: Grid::new(spec.nx, spec.ny, spec.spacing_m, vec![-1.0; n]),
            density: Grid::new(spec.nx, spec.ny, spec.spacing_m, vec![1.0; n]),
        };
        // A 10 mm foot (R = 5 mm) with its bottom 10 mm below the surface at 0.
        let m = sample_momenta(&field, &spec, 0.0, 0.0, 1000.0, (-0.005, 0.005, -0.010));
        let col = m.under_foot.momentum_kg_m_s;
        let band1 = m.under_foot_2r.momentum_kg_m_s - col;
        let band2 = m.under_foot_3r.momentum_kg_m_s - m.under_foot_2r.momentum_kg_m_s;
        assert!(col < 0.0, "down is negative height-up: {col}");
        assert!(
            (band1 / col - 3.0).abs() < 0.05,
            "R..2R holds {} x the column",
            band1 / col
        );
        assert!(
            (band2 / col - 5.0).abs() < 0.05,
            "2R..3R holds {} x the column",
            band2 / col
        );
        let bottom = 1.0 - m.under_foot_above_bottom_tenth.momentum_kg_m_s / col;
        assert!(
            (bottom - 0.1).abs() < 0.02,
            "the bottom tenth holds {bottom} of the column"
        );
    }
}
