//! The flat disc foot as LAMMPS sees it: LAMMPS has no finite-disc wall, so the foot is a
//! rigid layer of spheres (diameter `d_f`, the smallest grain's) on a triangular lattice of
//! spacing `d_f / 2`, centres within `R - d_f / 2` of the axis, so its rim is at `R`; its
//! bottom (`d_f / 2` below the centres) has hollows 9 % of `d_f` deep between three spheres. No grain fits between its
//! spheres; their pairs are excluded from the contacts, and `fix move` carries the layer on
//! the prescribed trajectory.

use crate::bed::{Atom, FOOT};

/// The foot's spheres, centred on (`cx`, `cy`), bottom at `bottom_m`, ids from `first_id`.
pub fn foot_atoms(
    radius_m: f64,
    sphere_diameter_m: f64,
    centre: (f64, f64),
    bottom_m: f64,
    density_kg_m3: f64,
    first_id: u64,
) -> Vec<Atom> {
    let s = 0.5 * sphere_diameter_m;
    let reach = radius_m - 0.5 * sphere_diameter_m;
    let rows = (reach / (s * 0.75f64.sqrt())).ceil() as i64;
    let cols = (reach / s).ceil() as i64 + 1;
    let z = bottom_m + 0.5 * sphere_diameter_m;
    let mut atoms = Vec::new();
    for row in -rows..=rows {
        let y = row as f64 * s * 0.75f64.sqrt();
        let shift = if row.rem_euclid(2) == 1 { 0.5 * s } else { 0.0 };
        for col in -cols..=cols {
            let x = col as f64 * s + shift;
            if x * x + y * y <= reach * reach + 1e-18 {
                atoms.push(Atom {
                    id: first_id + atoms.len() as u64,
                    kind: FOOT,
                    diameter_m: sphere_diameter_m,
                    density_kg_m3,
                    x: [centre.0 + x, centre.1 + y, z],
                    v: [0.0; 3],
                });
            }
        }
    }
    atoms
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_foot_is_a_flat_disc_of_its_radius_with_no_gap_a_grain_fits() {
        let (r, d) = (0.010, 0.0018);
        let f = foot_atoms(r, d, (0.03, 0.03), 0.04, 1000.0, 101);
        assert_eq!(f[0].id, 101);
        let rim = f
            .iter()
            .map(|a| ((a.x[0] - 0.03).powi(2) + (a.x[1] - 0.03).powi(2)).sqrt() + 0.5 * d)
            .fold(0.0, f64::max);
        assert!(rim <= r + 1e-12 && rim > r - 0.5 * d, "{rim}");
        assert!(f.iter().all(|a| (a.x[2] - 0.5 * d - 0.04).abs() < 1e-15));
        // Area per sphere: the triangular lattice's cell (sqrt(3)/2 s^2) over the disc.
        let cell = 0.75f64.sqrt() * (0.5 * d).powi(2);
        let expected = core::f64::consts::PI * (r - 0.5 * d).powi(2) / cell;
        assert!((f.len() as f64 / expected - 1.0).abs() < 0.1, "{}", f.len());
        // Every sphere has a neighbour at the lattice spacing (none is left alone).
        for a in &f {
            let near = f.iter().any(|b| {
                b.id != a.id
                    && ((a.x[0] - b.x[0]).powi(2) + (a.x[1] - b.x[1]).powi(2)).sqrt() < 0.51 * d
            });
            assert!(near);
        }
    }
}
