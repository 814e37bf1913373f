//! LAMMPS text dumps (`dump custom ... id type x y z vx vy vz radius`), one file per frame,
//! read and checked against the run that should have written them: the step the file's
//! name and header give, the box, every atom's count and fields, and every atom's radius
//! against the run's own data file (a dump of another run has other grains). A file that
//! is cut short, or of another run, is refused naming the file and what is wrong.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::bed::FOOT;

/// One dumped atom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DumpAtom {
    /// LAMMPS id.
    pub id: u64,
    /// LAMMPS type ([`crate::bed::GRAIN`] or [`FOOT`]).
    pub kind: u8,
    /// Position, m.
    pub x: [f64; 3],
    /// Velocity, m/s.
    pub v: [f64; 3],
    /// Radius, m.
    pub radius_m: f64,
}

/// One frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Its step.
    pub step: u64,
    /// Its atoms.
    pub atoms: Vec<DumpAtom>,
}

impl Frame {
    /// The foot's spheres.
    pub fn foot(&self) -> impl Iterator<Item = &DumpAtom> {
        self.atoms.iter().filter(|a| a.kind == FOOT)
    }
}

/// What a frame of this run must be.
#[derive(Clone, Debug)]
pub struct RunCheck {
    /// Box width in x and y, m.
    pub width_m: f64,
    /// Radius of every atom of the run by id, m.
    pub radius_by_id: HashMap<u64, f64>,
}

/// The file of the frame at `step` in `dir`.
pub fn frame_path(dir: &Path, step: u64) -> PathBuf {
    dir.join(format!("frame.{step}.txt"))
}

/// Read the frame at `step` from `dir`, checked against `check`.
pub fn read_frame(dir: &Path, step: u64, check: &RunCheck) -> Result<Frame, String> {
    let path = frame_path(dir, step);
    let name = path.display().to_string();
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!("{name}: {e} (the run stopped before this frame, or this is not its directory)")
    })?;
    if !text.ends_with('\n') {
        return Err(format!(
            "{name}: its last line is not complete (the file is cut short)"
        ));
    }
    let mut lines = text.lines().enumerate();
    let mut next = |what: &str| {
        lines
            .next()
            .map(|(no, l)| (no + 1, l))
            .ok_or_else(|| format!("{name}: ends before {what} (the file is cut short)"))
    };
    let expect_item = |(no, l): (usize, &str), item: &str| {
        if l.starts_with(item) {
            Ok(())
        } else {
            Err(format!(
                "{name}:{no}: `{l}` where a LAMMPS dump has `{item}` (not a dump of this run)"
            ))
        }
    };
    expect_item(next("its TIMESTEP")?, "ITEM: TIMESTEP")?;
    let (no, l) = next("its step")?;
    let got: u64 = l
        .trim()
        .parse()
        .map_err(|_| format!("{name}:{no}: `{l}` is not a step"))?;
    if got != step {
        return Err(format!(
            "{name}:{no}: the frame is of step {got}, where this run dumps step {step} into it \
             (a dump of another run)"
        ));
    }
    expect_item(next("its NUMBER OF ATOMS")?, "ITEM: NUMBER OF ATOMS")?;
    let (no, l) = next("its atom count")?;
    let count: usize = l
        .trim()
        .parse()
        .map_err(|_| format!("{name}:{no}: `{l}` is not an atom count"))?;
    expect_item(next("its BOX BOUNDS")?, "ITEM: BOX BOUNDS")?;
    for axis in 0..3 {
        let (no, l) = next("its box bounds")?;
        let b: Vec<f64> = l
            .split_whitespace()
            .filter_map(|w| w.parse::<f64>().ok())
            .collect();
        if b.len() < 2 {
            return Err(format!("{name}:{no}: `{l}` is not a box bound"));
        }
        let ok = if axis < 2 {
            b[0].abs() < 1e-9 && (b[1] - check.width_m).abs() <= 1e-9 * check.width_m
        } else {
            b[0].abs() < 1e-9
        };
        if !ok {
            return Err(format!(
                "{name}:{no}: box bounds `{l}` where this run's box is 0 to {:e} m across and \
                 its floor at 0 (a dump of another run)",
                check.width_m
            ));
        }
    }
    let (no, l) = next("its ATOMS header")?;
    let want = "ITEM: ATOMS id type x y z vx vy vz radius";
    if l.trim() != want {
        return Err(format!(
            "{name}:{no}: `{l}` (allowed: `{want}`, as this run dumps them)"
        ));
    }
    let listed = text.lines().count().saturating_sub(9);
    if listed < count {
        return Err(format!(
            "{name}: {listed} atom lines where its header counts {count} (the file is cut short)"
        ));
    }
    let mut atoms = Vec::with_capacity(count);
    for k in 0..count {
        let (no, l) = next(&format!("atom {} of {count}", k + 1))?;
        let mut f = [0.0f64; 9];
        let mut n = 0;
        for w in l.split_whitespace() {
            if n == 9 {
                n += 1;
                break;
            }
            f[n] = w
                .parse()
                .map_err(|_| format!("{name}:{no}: `{w}` is not a number"))?;
            n += 1;
        }
        if n != 9 {
            return Err(format!(
                "{name}:{no}: an atom line with {n} fields (allowed: 9; the file is cut short \
                 or not of this run)"
            ));
        }
        let id = f[0] as u64;
        let Some(&r) = check.radius_by_id.get(&id) else {
            return Err(format!(
                "{name}:{no}: atom {id} is not in this run (a dump of another run)"
            ));
        };
        if f[8].is_nan() || (f[8] - r).abs() > 1e-6 * r {
            return Err(format!(
                "{name}:{no}: atom {id} has radius {:e} m where this run's has {r:e} m (a dump \
                 of another run)",
                f[8]
            ));
        }
        atoms.push(DumpAtom {
            id,
            kind: f[1] as u8,
            x: [f[2], f[3], f[4]],
            v: [f[5], f[6], f[7]],
            radius_m: f[8],
        });
    }
    if let Some((no, l)) = lines.find(|(_, l)| !l.trim().is_empty()) {
        return Err(format!(
            "{name}:{}: `{l}` after the {count} atoms its header counts (not one frame of this \
             run)",
            no + 1
        ));
    }
    Ok(Frame { step, atoms })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check() -> RunCheck {
        RunCheck {
            width_m: 0.06,
            radius_by_id: [(1, 0.001), (2, 0.0009)].into_iter().collect(),
        }
    }

    fn frame_text(step: u64, r2: f64, atoms: usize) -> String {
        let mut s = format!(
            "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{atoms}\nITEM: BOX BOUNDS pp pp fm\n0 0.06\n0 0.06\n0 0.05\nITEM: ATOMS id type x y z vx vy vz radius\n"
        );
        s += "1 1 0.01 0.02 0.03 0 0 -0.1 0.001\n";
        s += &format!("2 2 0.01 0.02 0.04 0 0 -0.2 {r2}\n");
        s
    }

    #[test]
    fn a_frame_of_this_run_is_read() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(frame_path(dir.path(), 40), frame_text(40, 0.0009, 2)).unwrap();
        let f = read_frame(dir.path(), 40, &check()).unwrap();
        assert_eq!(f.atoms.len(), 2);
        assert_eq!(f.foot().count(), 1);
        assert_eq!(f.atoms[1].v, [0.0, 0.0, -0.2]);
    }

    #[test]
    fn cut_short_or_foreign_frames_are_refused_saying_why() {
        let dir = tempfile::tempdir().unwrap();
        let p = frame_path(dir.path(), 40);
        let cases: [(String, &str); 5] = [
            (frame_text(40, 0.0009, 3), "cut short"),
            (frame_text(40, 0.0012, 2), "another run"),
            (frame_text(80, 0.0009, 2), "step 80"),
            (
                frame_text(40, 0.0009, 2).replace("0 0.06\n0 0.06", "0 0.07\n0 0.07"),
                "box",
            ),
            (frame_text(40, 0.0009, 2)[..150].to_string(), "frame.40.txt"),
        ];
        for (text, why) in cases {
            std::fs::write(&p, &text).unwrap();
            let e = read_frame(dir.path(), 40, &check()).unwrap_err();
            assert!(e.contains(why) && e.contains("frame.40.txt"), "{why}: {e}");
        }
        let e = read_frame(dir.path(), 80, &check()).unwrap_err();
        assert!(e.contains("frame.80.txt") && e.contains("stopped"), "{e}");
    }
}
