//! Quantities derived from a velocity field on a regular grid (PIV's vectors, or the DEM's
//! grains interpolated to a grid): velocity gradients, vorticity, and the paper's maximum
//! shear strain rate (its equation 2)
//!
//! `gamma_dot = sqrt(1/2 (du/dx - dv/dy)^2 + 1/2 (du/dy + dv/dx)^2)`.
//!
//! Tools disagree on this quantity (PIVlab changed its own after a bug report), so it is pinned
//! here by analytic cases: simple shear `u = G y` gives `G / sqrt(2)`, a rigid rotation 0, a
//! pure strain `u = E x, v = -E y` gives `sqrt(2) E`. Axes: `x` to the right, `h` (height) up,
//! `u` and `v` the velocity components along them, SI units.

/// A scalar or vector component on a regular grid: `nx` columns (x growing), `ny` rows
/// (row 0 at the top, height decreasing with the row), NaN where there is no value (masked).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Grid spacing, m (the same in x and h).
    pub spacing_m: f64,
    /// Values, row-major.
    pub values: Vec<f64>,
}

impl Grid {
    /// A grid of `nx x ny` values (row-major), NaN where missing.
    pub fn new(nx: usize, ny: usize, spacing_m: f64, values: Vec<f64>) -> Self {
        assert_eq!(values.len(), nx * ny, "grid values");
        Self {
            nx,
            ny,
            spacing_m,
            values,
        }
    }

    /// Value at column `i`, row `j`.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.values[j * self.nx + i]
    }

    /// d/dx at `(i, j)`: central difference, one-sided at an edge or next to a missing value,
    /// NaN if neither neighbour exists.
    pub fn d_dx(&self, i: usize, j: usize) -> f64 {
        let c = self.at(i, j);
        let left = (i > 0).then(|| self.at(i - 1, j)).filter(|v| v.is_finite());
        let right = (i + 1 < self.nx)
            .then(|| self.at(i + 1, j))
            .filter(|v| v.is_finite());
        difference(left, c, right, self.spacing_m)
    }

    /// d/dh at `(i, j)` (height up: row `j - 1` is higher).
    pub fn d_dh(&self, i: usize, j: usize) -> f64 {
        let c = self.at(i, j);
        let below = (j + 1 < self.ny)
            .then(|| self.at(i, j + 1))
            .filter(|v| v.is_finite());
        let above = (j > 0).then(|| self.at(i, j - 1)).filter(|v| v.is_finite());
        difference(below, c, above, self.spacing_m)
    }
}

fn difference(lo: Option<f64>, c: f64, hi: Option<f64>, h: f64) -> f64 {
    if !c.is_finite() {
        return f64::NAN;
    }
    match (lo, hi) {
        (Some(a), Some(b)) => (b - a) / (2.0 * h),
        (None, Some(b)) => (b - c) / h,
        (Some(a), None) => (c - a) / h,
        (None, None) => f64::NAN,
    }
}

/// The velocity gradient at one point, 1/s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gradient {
    /// du/dx.
    pub du_dx: f64,
    /// du/dh.
    pub du_dh: f64,
    /// dv/dx.
    pub dv_dx: f64,
    /// dv/dh.
    pub dv_dh: f64,
}

impl Gradient {
    /// Vorticity `dv/dx - du/dh`, 1/s (counter-clockwise positive, x right and h up).
    pub fn vorticity(&self) -> f64 {
        self.dv_dx - self.du_dh
    }

    /// The paper's maximum shear strain rate (equation 2), 1/s.
    pub fn max_shear_rate(&self) -> f64 {
        let a = self.du_dx - self.dv_dh;
        let b = self.du_dh + self.dv_dx;
        (0.5 * a * a + 0.5 * b * b).sqrt()
    }
}

/// Derived fields of a velocity field.
#[derive(Clone, Debug, PartialEq)]
pub struct Derived {
    /// Vorticity, 1/s.
    pub vorticity: Grid,
    /// Maximum shear strain rate (equation 2), 1/s.
    pub shear_rate: Grid,
}

/// Vorticity and shear rate of `(u, v)` (m/s, same grid), NaN where a component or both
/// neighbours along an axis are missing.
pub fn derive(u: &Grid, v: &Grid) -> Derived {
    let (nx, ny, h) = (u.nx, u.ny, u.spacing_m);
    let mut vort = Vec::with_capacity(nx * ny);
    let mut shear = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let g = Gradient {
                du_dx: u.d_dx(i, j),
                du_dh: u.d_dh(i, j),
                dv_dx: v.d_dx(i, j),
                dv_dh: v.d_dh(i, j),
            };
            vort.push(g.vorticity());
            shear.push(g.max_shear_rate());
        }
    }
    Derived {
        vorticity: Grid::new(nx, ny, h, vort),
        shear_rate: Grid::new(nx, ny, h, shear),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(f: impl Fn(f64, f64) -> (f64, f64)) -> (Grid, Grid) {
        let (nx, ny, h) = (7, 6, 0.01);
        let (mut u, mut v) = (Vec::new(), Vec::new());
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (i as f64 * h, -(j as f64) * h);
                let (a, b) = f(x, y);
                u.push(a);
                v.push(b);
            }
        }
        (Grid::new(nx, ny, h, u), Grid::new(nx, ny, h, v))
    }

    fn everywhere(g: &Grid, expected: f64) {
        for &x in &g.values {
            assert!((x - expected).abs() < 1e-9, "{x} vs {expected}");
        }
    }

    #[test]
    fn simple_shear_gives_g_over_sqrt_2_and_vorticity_minus_g() {
        let g = 3.0;
        let (u, v) = field(|_, y| (g * y, 0.0));
        let d = derive(&u, &v);
        everywhere(&d.shear_rate, g / 2f64.sqrt());
        everywhere(&d.vorticity, -g);
    }

    #[test]
    fn rigid_rotation_has_no_shear_and_twice_its_rate_of_vorticity() {
        let w = 2.0;
        let (u, v) = field(|x, y| (-w * y, w * x));
        let d = derive(&u, &v);
        everywhere(&d.shear_rate, 0.0);
        everywhere(&d.vorticity, 2.0 * w);
    }

    #[test]
    fn pure_strain_gives_what_the_formula_says() {
        // u = E x, v = -E h: du/dx - dv/dh = 2E, no cross terms: sqrt(1/2 (2E)^2) = sqrt(2) E.
        let e = 1.5;
        let (u, v) = field(|x, y| (e * x, -e * y));
        let d = derive(&u, &v);
        everywhere(&d.shear_rate, 2f64.sqrt() * e);
        everywhere(&d.vorticity, 0.0);
        // A uniform translation: nothing.
        let (u, v) = field(|_, _| (0.3, -0.2));
        let d = derive(&u, &v);
        everywhere(&d.shear_rate, 0.0);
    }

    #[test]
    fn missing_neighbours_fall_back_to_one_sided_differences() {
        let (mut u, v) = field(|_, y| (2.0 * y, 0.0));
        u.values[2 * 7 + 3] = f64::NAN;
        let d = derive(&u, &v);
        assert!(d.shear_rate.at(3, 2).is_nan());
        // Above and below the hole, the one-sided difference still sees the linear field.
        assert!((d.shear_rate.at(3, 1) - 2.0 / 2f64.sqrt()).abs() < 1e-9);
        assert!((d.shear_rate.at(3, 3) - 2.0 / 2f64.sqrt()).abs() < 1e-9);
    }
}
