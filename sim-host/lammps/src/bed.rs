//! The bed: the grains' loose start, LAMMPS data files written and read, and the settled
//! bed's surface and packing fraction.
//!
//! The pour: grains of random diameter on a cubic lattice of spacing `1.2 d_max` with
//! random offsets (no two overlap) and small random velocities, above a floor at z = 0 in a
//! box periodic in x and y; LAMMPS lets them fall under gravity and settle ([`crate::script`]).

use std::fmt::Write as _;
use std::path::Path;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::spec::LammpsSpec;

/// LAMMPS atom type of a grain.
pub const GRAIN: u8 = 1;
/// LAMMPS atom type of a foot atom.
pub const FOOT: u8 = 2;

/// One atom of a LAMMPS data file (`atom_style sphere`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atom {
    /// LAMMPS atom id (from 1).
    pub id: u64,
    /// [`GRAIN`] or [`FOOT`].
    pub kind: u8,
    /// Diameter, m.
    pub diameter_m: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
    /// Position, m.
    pub x: [f64; 3],
    /// Velocity, m/s.
    pub v: [f64; 3],
}

impl Atom {
    /// Mass, kg.
    pub fn mass_kg(&self) -> f64 {
        self.density_kg_m3 * core::f64::consts::PI / 6.0 * self.diameter_m.powi(3)
    }
}

/// A box periodic in x and y, `[0, w) x [0, w)`, the floor at z = 0, up to `top_m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BedBox {
    /// Width (x and y), m.
    pub width_m: f64,
    /// Top of the box, m.
    pub top_m: f64,
}

/// The loose start of the pour: `spec.grain_count()` grains on a jittered lattice, the box
/// wide enough for a whole number of lattice cells (at least `spec.bed_width_m`).
pub fn loose_start(spec: &LammpsSpec) -> (BedBox, Vec<Atom>) {
    let mut rng = StdRng::seed_from_u64(spec.seed);
    let dmax = spec.max_grain_diameter_m();
    let spacing = 1.2 * dmax;
    let per_row = (spec.bed_width_m / spacing).ceil().max(1.0) as u64;
    let width = per_row as f64 * spacing;
    let n = spec.grain_count();
    let jitter = 0.5 * (spacing - dmax) * 0.95;
    let mut atoms = Vec::with_capacity(n as usize);
    let mut u = |a: f64| a * (2.0 * rng.random::<f64>() - 1.0);
    for k in 0..n {
        let layer = k / (per_row * per_row);
        let i = k % per_row;
        let j = (k / per_row) % per_row;
        let d = spec.grain_diameter_m * (1.0 + u(spec.grain_size_spread));
        let x = [
            (i as f64 + 0.5) * spacing + u(jitter),
            (j as f64 + 0.5) * spacing + u(jitter),
            (layer as f64 + 0.5) * spacing + u(jitter),
        ];
        let v = [u(0.05), u(0.05), u(0.05)];
        atoms.push(Atom {
            id: k + 1,
            kind: GRAIN,
            diameter_m: d,
            density_kg_m3: spec.grain_density_kg_m3,
            x,
            v,
        });
    }
    debug_assert_eq!(loose_box(spec).width_m, width);
    (loose_box(spec), atoms)
}

/// The box of [`loose_start`] (without its grains: a paper-sized bed's are ~1 GB).
pub fn loose_box(spec: &LammpsSpec) -> BedBox {
    let spacing = 1.2 * spec.max_grain_diameter_m();
    let per_row = (spec.bed_width_m / spacing).ceil().max(1.0) as u64;
    let layers = spec.grain_count().div_ceil(per_row * per_row);
    BedBox {
        width_m: per_row as f64 * spacing,
        top_m: (layers as f64 + 1.0) * spacing,
    }
}

/// The text of a LAMMPS data file (`atom_style sphere`, with velocities).
pub fn data_file(title: &str, bed: &BedBox, atoms: &[Atom]) -> String {
    let mut s = String::with_capacity(atoms.len() * 120 + 400);
    let _ = write!(
        s,
        "{title}\n\n{} atoms\n2 atom types\n\n0 {:e} xlo xhi\n0 {:e} ylo yhi\n0 {:e} zlo zhi\n\nAtoms # sphere\n\n",
        atoms.len(),
        bed.width_m,
        bed.width_m,
        bed.top_m
    );
    for a in atoms {
        let _ = writeln!(
            s,
            "{} {} {:e} {:e} {:e} {:e} {:e}",
            a.id, a.kind, a.diameter_m, a.density_kg_m3, a.x[0], a.x[1], a.x[2]
        );
    }
    s += "\nVelocities\n\n";
    for a in atoms {
        let _ = writeln!(s, "{} {:e} {:e} {:e} 0 0 0", a.id, a.v[0], a.v[1], a.v[2]);
    }
    s
}

/// Read a LAMMPS data file of `atom_style sphere` (as `write_data` writes it: `id type
/// diameter density x y z [ix iy iz]`, then `Velocities`): its box and atoms, positions
/// unwrapped into the box. Errors name the file and line.
pub fn read_data(path: &Path) -> Result<(BedBox, Vec<Atom>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse_data(&text, &path.display().to_string())
}

/// A count, an atom id or an atom type (`what`) of LAMMPS's files: integers there, read as
/// such (as f64, ids past 2^53 would merge, `1.5` would pass as atom 1 and a type of 300 as
/// 44); otherwise what `w` is not, and what is `allowed`. Shared with the dump reader.
pub(crate) fn whole<T: std::str::FromStr>(w: &str, what: &str, allowed: &str) -> Result<T, String> {
    w.parse()
        .map_err(|_| format!("`{w}` is not {what} (allowed: {allowed})"))
}

/// [`read_data`] of a data file's text; `name` names it in errors.
pub fn parse_data(text: &str, name: &str) -> Result<(BedBox, Vec<Atom>), String> {
    let mut width = None;
    let mut top = None;
    let mut count = None;
    let mut atoms: Vec<Atom> = Vec::new();
    let mut section = "";
    let mut index = std::collections::HashMap::new();
    for (no, raw) in text.lines().enumerate().skip(1) {
        let line = raw.split('#').next().unwrap_or("").trim();
        let at = || format!("{name}:{}", no + 1);
        if line.is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |s: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{}: `{s}` is not a finite number", at()))
        };
        let located = |e: String| format!("{}: {e}", at());
        if raw.trim_start().starts_with("Atoms") {
            section = "atoms";
            continue;
        }
        if raw.trim_start().starts_with("Velocities") {
            section = "velocities";
            continue;
        }
        if f[0].chars().next().is_some_and(char::is_alphabetic) {
            section = "other";
            continue;
        }
        match section {
            "" => {
                if f.len() == 2 && f[1] == "atoms" {
                    count = Some(
                        whole::<u64>(f[0], "an atom count", "a whole number").map_err(located)?,
                    );
                } else if f.len() == 4 && f[2] == "xlo" {
                    width = Some(num(f[1])? - num(f[0])?);
                } else if f.len() == 4 && f[2] == "zlo" {
                    top = Some(num(f[1])?);
                }
            }
            "atoms" => {
                if f.len() < 7 {
                    return Err(format!(
                        "{}: an atom line has {} fields (allowed: id type diameter density x y z)",
                        at(),
                        f.len()
                    ));
                }
                let id: u64 = whole(f[0], "an atom id", "a whole number").map_err(located)?;
                if index.insert(id, atoms.len()).is_some() {
                    return Err(format!("{}: atom {id} listed twice", at()));
                }
                atoms.push(Atom {
                    id,
                    kind: whole(f[1], "an atom type", "0 to 255").map_err(located)?,
                    diameter_m: num(f[2])?,
                    density_kg_m3: num(f[3])?,
                    x: [num(f[4])?, num(f[5])?, num(f[6])?],
                    v: [0.0; 3],
                });
            }
            "velocities" => {
                if f.len() < 4 {
                    return Err(format!("{}: a velocity line has {} fields", at(), f.len()));
                }
                let id: u64 = whole(f[0], "an atom id", "a whole number").map_err(located)?;
                if let Some(&k) = index.get(&id) {
                    atoms[k].v = [num(f[1])?, num(f[2])?, num(f[3])?];
                }
            }
            _ => {}
        }
    }
    let (Some(width), Some(top), Some(count)) = (width, top, count) else {
        return Err(format!(
            "{name}: not a LAMMPS data file (no atom count or box bounds)"
        ));
    };
    if width <= 0.0 {
        return Err(format!(
            "{name}: a box {width} m wide (allowed: xhi above xlo)"
        ));
    }
    if atoms.len() as u64 != count {
        return Err(format!(
            "{name}: {} atoms listed where its header says {count} (the file is cut short)",
            atoms.len()
        ));
    }
    for a in &mut atoms {
        for c in 0..2 {
            a.x[c] = a.x[c].rem_euclid(width);
        }
    }
    Ok((
        BedBox {
            width_m: width,
            top_m: top,
        },
        atoms,
    ))
}

/// What the settled bed is.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settled {
    /// Height of the surface under the foot (the median over cells one grain wide of the
    /// highest grain top, within the foot's radius of the axis), m.
    pub surface_m: f64,
    /// Packing fraction of the bulk (grain volume of the centres between 3 mean diameters
    /// above the floor and 3 below the surface, and 3 from a sidewall, over that slab's
    /// volume), 1.
    pub packing_fraction: f64,
    /// Grains in the bed.
    pub grains: u64,
}

/// Measure the settled bed of `atoms` in `bed`, the foot's axis where the spec puts it
/// ([`LammpsSpec::axis_m`]).
pub fn settled(spec: &LammpsSpec, bed: &BedBox, atoms: &[Atom]) -> Result<Settled, String> {
    let d = spec.grain_diameter_m;
    let c = spec.axis_m(bed.width_m);
    let r = spec.foot_radius_m();
    let cells = ((2.0 * r) / d).ceil() as usize;
    let mut top = vec![f64::NEG_INFINITY; cells * cells];
    let mut n = 0u64;
    for a in atoms.iter().filter(|a| a.kind == GRAIN) {
        n += 1;
        let (dx, dy) = (a.x[0] - c.0, a.x[1] - c.1);
        if dx * dx + dy * dy > r * r {
            continue;
        }
        let i = (((dx + r) / d) as usize).min(cells - 1);
        let j = (((dy + r) / d) as usize).min(cells - 1);
        let k = i * cells + j;
        top[k] = top[k].max(a.x[2] + 0.5 * a.diameter_m);
    }
    let mut tops: Vec<f64> = top.into_iter().filter(|t| t.is_finite()).collect();
    if tops.is_empty() {
        return Err("the settled bed has no grain under the foot".into());
    }
    tops.sort_by(f64::total_cmp);
    let surface = tops[tops.len() / 2];
    let (lo, hi) = (3.0 * d, surface - 3.0 * d);
    if hi <= lo {
        return Err(format!(
            "the settled bed is {:.1} mm deep: too shallow to measure its packing (allowed: more \
             than 6 grain diameters)",
            1e3 * surface
        ));
    }
    // Against sidewalls, the bulk is also 3 mean diameters away from each wall (a wall
    // loosens the grains beside it).
    let (y_lo, y_hi) = if spec.sidewall {
        (3.0 * d, bed.width_m - 3.0 * d)
    } else {
        (f64::NEG_INFINITY, f64::INFINITY)
    };
    let volume: f64 = atoms
        .iter()
        .filter(|a| a.kind == GRAIN && a.x[2] >= lo && a.x[2] < hi)
        .filter(|a| a.x[1] >= y_lo && a.x[1] < y_hi)
        .map(|a| core::f64::consts::PI / 6.0 * a.diameter_m.powi(3))
        .sum();
    let depth_y = if spec.sidewall {
        y_hi - y_lo
    } else {
        bed.width_m
    };
    Ok(Settled {
        surface_m: surface,
        packing_fraction: volume / (bed.width_m * depth_y * (hi - lo)),
        grains: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{LammpsSpec, Preset};

    const TWO_ATOMS: &str = "title\n\n2 atoms\n0 0.04 xlo xhi\n0 0.04 ylo yhi\n0 0.03 zlo zhi\n\nAtoms # sphere\n\n1 1 0.002 1000 0.01 0.01 0.01\n2 1 0.002 1000 0.02 0.02 0.01\n";

    /// A data file is read whole or refused naming the line: an atom listed twice (its
    /// first line lost), a coordinate that is not finite, a box of no width.
    #[test]
    fn a_data_file_with_a_twice_listed_atom_or_nan_or_no_box_is_refused() {
        let (bed, atoms) = parse_data(TWO_ATOMS, "t.data").unwrap();
        assert_eq!((bed.width_m, atoms.len()), (0.04, 2));
        let twice = TWO_ATOMS.replace("\n2 1 0.002", "\n1 1 0.002");
        let e = parse_data(&twice, "t.data").unwrap_err();
        assert!(e.contains("t.data:11: atom 1 listed twice"), "{e}");
        let nan = TWO_ATOMS.replace("0.02 0.02 0.01", "nan 0.02 0.01");
        let e = parse_data(&nan, "t.data").unwrap_err();
        assert!(e.contains("`nan` is not a finite number"), "{e}");
        let flat = TWO_ATOMS.replace("0 0.04 xlo xhi", "0.04 0.04 xlo xhi");
        let e = parse_data(&flat, "t.data").unwrap_err();
        assert!(e.contains("a box 0 m wide"), "{e}");
    }

    /// Counts, ids and types are whole numbers: ids either side of 2^53 stay two atoms (as
    /// f64 they were one), and `1.5` is not atom 1.
    #[test]
    fn atom_ids_types_and_counts_are_whole_numbers() {
        let big = TWO_ATOMS
            .replace("\n1 1 0.002", "\n9007199254740992 1 0.002")
            .replace("\n2 1 0.002", "\n9007199254740993 1 0.002");
        let (_, atoms) = parse_data(&big, "t.data").unwrap();
        assert_eq!(atoms[1].id, 9007199254740993);
        for (from, to, why) in [
            (
                "\n2 1 0.002",
                "\n1.5 1 0.002",
                "t.data:11: `1.5` is not an atom id",
            ),
            (
                "\n2 1 0.002",
                "\n2 300 0.002",
                "t.data:11: `300` is not an atom type",
            ),
            (
                "2 atoms",
                "2.0 atoms",
                "t.data:3: `2.0` is not an atom count",
            ),
        ] {
            let e = parse_data(&TWO_ATOMS.replace(from, to), "t.data").unwrap_err();
            assert!(e.contains(why), "{why}: {e}");
        }
    }

    #[test]
    fn the_loose_start_has_no_overlap_and_round_trips_through_a_data_file() {
        let spec = LammpsSpec {
            bed_width_m: 0.02,
            bed_depth_m: 0.012,
            ..LammpsSpec::preset(Preset::Small)
        };
        let (bed, atoms) = loose_start(&spec);
        assert_eq!(atoms.len() as u64, spec.grain_count());
        // Neighbours on the lattice never touch.
        for a in &atoms {
            for b in &atoms {
                if a.id < b.id {
                    let d2: f64 = (0..3).map(|c| (a.x[c] - b.x[c]).powi(2)).sum();
                    let touch = 0.5 * (a.diameter_m + b.diameter_m);
                    assert!(d2.sqrt() > touch, "{} {}", a.id, b.id);
                }
            }
            assert!(a.x[2] - 0.5 * a.diameter_m > 0.0 && a.x[2] < bed.top_m);
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bed.data");
        std::fs::write(&p, data_file("test", &bed, &atoms)).unwrap();
        let (bed2, back) = read_data(&p).unwrap();
        assert_eq!(bed2, bed);
        assert_eq!(back, atoms);
    }

    #[test]
    fn a_cut_data_file_is_refused_naming_it() {
        let spec = LammpsSpec {
            bed_width_m: 0.02,
            bed_depth_m: 0.012,
            ..LammpsSpec::preset(Preset::Small)
        };
        let (bed, atoms) = loose_start(&spec);
        let text = data_file("test", &bed, &atoms);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cut.data");
        // Cut at a line's end halfway through the atoms.
        let half = text[..text.find("Velocities").unwrap() / 2]
            .rfind('\n')
            .unwrap();
        std::fs::write(&p, &text[..half]).unwrap();
        let e = read_data(&p).unwrap_err();
        assert!(e.contains("cut.data") && e.contains("cut short"), "{e}");
    }

    #[test]
    fn a_simple_cubic_bed_has_its_packing_and_surface() {
        // Grains of 2 mm on a 2 mm cubic lattice: phi = pi/6, surface at the top layer's top.
        let spec = LammpsSpec::preset(Preset::Small);
        let d = 0.002;
        let w = 0.06;
        let mut atoms = Vec::new();
        for k in 0..20 {
            for i in 0..30 {
                for j in 0..30 {
                    atoms.push(Atom {
                        id: atoms.len() as u64 + 1,
                        kind: GRAIN,
                        diameter_m: d,
                        density_kg_m3: 1000.0,
                        x: [
                            (i as f64 + 0.5) * d,
                            (j as f64 + 0.5) * d,
                            (k as f64 + 0.5) * d,
                        ],
                        v: [0.0; 3],
                    });
                }
            }
        }
        let bed = BedBox {
            width_m: w,
            top_m: 0.05,
        };
        let s = settled(&spec, &bed, &atoms).unwrap();
        assert!((s.surface_m - 0.040).abs() < 1e-12, "{}", s.surface_m);
        // The slab holds whole layers only approximately: within one layer's share.
        assert!(
            (s.packing_fraction - core::f64::consts::PI / 6.0).abs() < 0.04,
            "{}",
            s.packing_fraction
        );
        assert_eq!(s.grains, 18_000);
    }
}
