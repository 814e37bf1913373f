//! LAMMPS dumps (`dump custom ... id type x y z vx vy vz radius`), one file per frame, as
//! text or gzip-compressed text ([`DumpFormat`]), read as a stream (one line in memory at a
//! time besides the frame's atoms) and checked against the run that should have written
//! them: the step the file's name and header give, the box, every atom's count and fields,
//! and every atom's radius against the run's own data file (a dump of another run has other
//! grains). A file that is cut short, or of another run, is refused naming the file and what
//! is wrong.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use crate::bed::{FOOT, whole};
pub use crate::spec::DumpFormat;

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
    /// How the run's frames are written.
    pub format: DumpFormat,
}

/// The file of the frame at `step` in `dir`, written as `format`.
pub fn frame_path(dir: &Path, step: u64, format: DumpFormat) -> PathBuf {
    match format {
        DumpFormat::Text => dir.join(format!("frame.{step}.txt")),
        DumpFormat::Gzip => dir.join(format!("frame.{step}.txt.gz")),
    }
}

/// The lines of one dump file, read one at a time, each checked to be complete.
struct Lines {
    name: String,
    reader: Box<dyn BufRead>,
    line: String,
    no: usize,
}

impl Lines {
    /// The next line (without its newline) and its number, `None` at the end of the file.
    fn next(&mut self) -> Result<Option<(usize, &str)>, String> {
        self.line.clear();
        let n = self.reader.read_line(&mut self.line).map_err(|e| {
            format!(
                "{}: {e} after line {} (the file is cut short, or not a dump)",
                self.name, self.no
            )
        })?;
        if n == 0 {
            return Ok(None);
        }
        self.no += 1;
        if !self.line.ends_with('\n') {
            return Err(format!(
                "{}:{}: its last line is not complete (the file is cut short)",
                self.name, self.no
            ));
        }
        Ok(Some((self.no, self.line.trim_end_matches(['\n', '\r']))))
    }

    /// The next line, which must be there: `what` names it for the error.
    fn expect(&mut self, what: &str) -> Result<(usize, String), String> {
        let name = self.name.clone();
        match self.next()? {
            Some((no, l)) => Ok((no, l.to_string())),
            None => Err(format!(
                "{name}: ends before {what} (the file is cut short)"
            )),
        }
    }
}

/// Read the frame at `step` from `dir`, checked against `check`.
pub fn read_frame(dir: &Path, step: u64, check: &RunCheck) -> Result<Frame, String> {
    let path = frame_path(dir, step, check.format);
    let name = path.display().to_string();
    let file = std::fs::File::open(&path).map_err(|e| {
        format!("{name}: {e} (the run stopped before this frame, or this is not its directory)")
    })?;
    parse_frame(file, &name, step, check)
}

/// The frame at `step` from `bytes` (the file's bytes as written, text or gzip as
/// `check.format` says), checked against `check`; `name` names the source in errors. What
/// [`read_frame`] reads a file with, and what the fuzzer drives.
pub fn parse_frame(
    bytes: impl Read + 'static,
    name: &str,
    step: u64,
    check: &RunCheck,
) -> Result<Frame, String> {
    let raw: Box<dyn Read> = match check.format {
        DumpFormat::Text => Box::new(bytes),
        DumpFormat::Gzip => Box::new(flate2::read::MultiGzDecoder::new(BufReader::new(bytes))),
    };
    let name = name.to_string();
    let mut lines = Lines {
        name: name.clone(),
        reader: Box::new(BufReader::with_capacity(1 << 16, raw)),
        line: String::new(),
        no: 0,
    };
    let expect_item = |(no, l): (usize, String), item: &str| {
        if l.starts_with(item) {
            Ok(())
        } else {
            Err(format!(
                "{name}:{no}: `{l}` where a LAMMPS dump has `{item}` (not a dump of this run)"
            ))
        }
    };
    expect_item(lines.expect("its TIMESTEP")?, "ITEM: TIMESTEP")?;
    let (no, l) = lines.expect("its step")?;
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
    expect_item(
        lines.expect("its NUMBER OF ATOMS")?,
        "ITEM: NUMBER OF ATOMS",
    )?;
    let (no, l) = lines.expect("its atom count")?;
    let count: usize = l
        .trim()
        .parse()
        .map_err(|_| format!("{name}:{no}: `{l}` is not an atom count"))?;
    if count > check.radius_by_id.len() {
        return Err(format!(
            "{name}:{no}: {count} atoms where this run has {} (a dump of another run)",
            check.radius_by_id.len()
        ));
    }
    expect_item(lines.expect("its BOX BOUNDS")?, "ITEM: BOX BOUNDS")?;
    for axis in 0..3 {
        let (no, l) = lines.expect("its box bounds")?;
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
    let (no, l) = lines.expect("its ATOMS header")?;
    let want = "ITEM: ATOMS id type x y z vx vy vz radius";
    if l.trim() != want {
        return Err(format!(
            "{name}:{no}: `{l}` (allowed: `{want}`, as this run dumps them)"
        ));
    }
    let mut atoms = Vec::with_capacity(count);
    for k in 0..count {
        let Some((no, l)) = lines.next()? else {
            return Err(format!(
                "{name}: {k} atom lines where its header counts {count} (the file is cut short)"
            ));
        };
        // `id type` are integers ([`whole`]), the rest numbers.
        let located = |e: String| format!("{name}:{no}: {e}");
        let mut id = 0u64;
        let mut kind = 0u8;
        let mut f = [0.0f64; 9];
        let mut n = 0;
        for w in l.split_whitespace() {
            match n {
                0 => id = whole(w, "an atom id", "a whole number").map_err(located)?,
                1 => kind = whole(w, "an atom type", "0 to 255").map_err(located)?,
                9 => {
                    n += 1;
                    break;
                }
                _ => {
                    f[n] = w
                        .parse()
                        .map_err(|_| format!("{name}:{no}: `{w}` is not a number"))?
                }
            }
            n += 1;
        }
        if n != 9 {
            return Err(format!(
                "{name}:{no}: an atom line with {n} fields (allowed: 9; the file is cut short \
                 or not of this run)"
            ));
        }
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
            kind,
            x: [f[2], f[3], f[4]],
            v: [f[5], f[6], f[7]],
            radius_m: f[8],
        });
    }
    while let Some((no, l)) = lines.next()? {
        if !l.trim().is_empty() {
            return Err(format!(
                "{name}:{no}: `{l}` after the {count} atoms its header counts (not one frame of \
                 this run)"
            ));
        }
    }
    Ok(Frame { step, atoms })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check() -> RunCheck {
        RunCheck {
            width_m: 0.06,
            radius_by_id: [(1, 0.001), (2, 0.0009), (3, 0.001)].into_iter().collect(),
            format: DumpFormat::Text,
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
        std::fs::write(
            frame_path(dir.path(), 40, DumpFormat::Text),
            frame_text(40, 0.0009, 2),
        )
        .unwrap();
        let f = read_frame(dir.path(), 40, &check()).unwrap();
        assert_eq!(f.atoms.len(), 2);
        assert_eq!(f.foot().count(), 1);
        assert_eq!(f.atoms[1].v, [0.0, 0.0, -0.2]);
    }

    #[test]
    fn cut_short_or_foreign_frames_are_refused_saying_why() {
        let dir = tempfile::tempdir().unwrap();
        let p = frame_path(dir.path(), 40, DumpFormat::Text);
        let cases: [(String, &str); 8] = [
            (frame_text(40, 0.0009, 3), "cut short"),
            (frame_text(40, 0.0009, 9), "another run"),
            (frame_text(40, 0.0012, 2), "another run"),
            (frame_text(80, 0.0009, 2), "step 80"),
            (
                frame_text(40, 0.0009, 2).replace("0 0.06\n0 0.06", "0 0.07\n0 0.07"),
                "box",
            ),
            (frame_text(40, 0.0009, 2)[..150].to_string(), "frame.40.txt"),
            (
                frame_text(40, 0.0009, 2).replace("\n2 2 0.01", "\n2.0 2 0.01"),
                "`2.0` is not an atom id",
            ),
            (
                frame_text(40, 0.0009, 2).replace("\n2 2 0.01", "\n2 256 0.01"),
                "`256` is not an atom type",
            ),
        ];
        for (text, why) in cases {
            std::fs::write(&p, &text).unwrap();
            let e = read_frame(dir.path(), 40, &check()).unwrap_err();
            assert!(e.contains(why) && e.contains("frame.40.txt"), "{why}: {e}");
        }
        let e = read_frame(dir.path(), 80, &check()).unwrap_err();
        assert!(e.contains("frame.80.txt") && e.contains("stopped"), "{e}");
    }

    fn gzip(text: &str) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(text.as_bytes()).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn a_gzip_frame_reads_as_its_text_and_a_cut_one_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let gz = RunCheck {
            format: DumpFormat::Gzip,
            ..check()
        };
        let text = frame_text(40, 0.0009, 2);
        std::fs::write(frame_path(dir.path(), 40, DumpFormat::Text), &text).unwrap();
        let p = frame_path(dir.path(), 40, DumpFormat::Gzip);
        assert!(p.ends_with("frame.40.txt.gz"));
        let bytes = gzip(&text);
        std::fs::write(&p, &bytes).unwrap();
        assert_eq!(
            read_frame(dir.path(), 40, &gz).unwrap(),
            read_frame(dir.path(), 40, &check()).unwrap()
        );
        // A stream cut anywhere, or text where gzip is expected, is refused naming the file.
        for cut in [bytes.len() - 4, bytes.len() / 2, 12] {
            std::fs::write(&p, &bytes[..cut]).unwrap();
            let e = read_frame(dir.path(), 40, &gz).unwrap_err();
            assert!(
                e.contains("frame.40.txt.gz") && e.contains("cut short"),
                "{cut}: {e}"
            );
        }
        std::fs::write(&p, &text).unwrap();
        let e = read_frame(dir.path(), 40, &gz).unwrap_err();
        assert!(e.contains("frame.40.txt.gz"), "{e}");
    }
}
