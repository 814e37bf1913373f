//! The intruder: a flat row of intruder grains the width of the foot, moving on a prescribed
//! trajectory (constant speed, the simulator's foot `x_f(t)` from `jump --out`'s
//! `trajectory.csv`, or a tracked foot). Depth is measured down from the bed's surface; the
//! intruder's bottom is at `surface - depth(t)`.

use std::path::Path;

use serde::Serialize;

use super::grains::{Grains, INTRUDER};

/// A prescribed depth history.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Trajectory {
    /// From `start_depth_m` (negative: above the surface) down at `speed_m_s` until
    /// `end_depth_m`.
    Constant {
        /// m/s, down positive.
        speed_m_s: f64,
        /// m.
        start_depth_m: f64,
        /// m.
        end_depth_m: f64,
    },
    /// Depth at times (strictly increasing from 0), linear in between.
    Table {
        /// s.
        t_s: Vec<f64>,
        /// m (down positive).
        depth_m: Vec<f64>,
        /// Where it came from.
        source: String,
    },
}

impl Trajectory {
    /// The same motion for a foot `length_factor` times the size, at the same Froude number
    /// `v^2 / (g L)`: depths times `length_factor`, times times its square root (speeds too).
    /// A jump's push-off with the robot's 38 mm foot, scaled to a smaller foot, keeps the
    /// paper's depth over radius and its Froude number.
    pub fn froude_scaled(&self, length_factor: f64) -> Self {
        let (k, time) = (length_factor, length_factor.sqrt());
        match self {
            Self::Constant {
                speed_m_s,
                start_depth_m,
                end_depth_m,
            } => Self::Constant {
                speed_m_s: speed_m_s * time,
                start_depth_m: start_depth_m * k,
                end_depth_m: end_depth_m * k,
            },
            Self::Table {
                t_s,
                depth_m,
                source,
            } => Self::Table {
                t_s: t_s.iter().map(|t| t * time).collect(),
                depth_m: depth_m.iter().map(|d| d * k).collect(),
                source: format!("{source}, Froude-scaled by {k} in length"),
            },
        }
    }

    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        match self {
            Self::Constant {
                speed_m_s,
                start_depth_m,
                end_depth_m,
            } => (end_depth_m - start_depth_m) / speed_m_s,
            Self::Table { t_s, .. } => t_s.last().copied().unwrap_or(0.0),
        }
    }

    /// Depth at `t`, m.
    pub fn depth(&self, t: f64) -> f64 {
        match self {
            Self::Constant {
                speed_m_s,
                start_depth_m,
                ..
            } => start_depth_m + speed_m_s * t,
            Self::Table { t_s, depth_m, .. } => {
                let k = t_s.partition_point(|&x| x <= t);
                if k == 0 {
                    return depth_m[0];
                }
                if k >= t_s.len() {
                    return depth_m[depth_m.len() - 1];
                }
                let f = (t - t_s[k - 1]) / (t_s[k] - t_s[k - 1]);
                depth_m[k - 1] + f * (depth_m[k] - depth_m[k - 1])
            }
        }
    }

    /// Depth rate at `t`, m/s (down positive): the slope of the segment holding `t`.
    pub fn speed(&self, t: f64) -> f64 {
        match self {
            Self::Constant { speed_m_s, .. } => *speed_m_s,
            Self::Table { t_s, depth_m, .. } => {
                let k = t_s.partition_point(|&x| x <= t).clamp(1, t_s.len() - 1);
                (depth_m[k] - depth_m[k - 1]) / (t_s[k] - t_s[k - 1])
            }
        }
    }

    /// Fastest depth rate, m/s.
    pub fn max_speed(&self) -> f64 {
        match self {
            Self::Constant { speed_m_s, .. } => speed_m_s.abs(),
            Self::Table { t_s, depth_m, .. } => (1..t_s.len())
                .map(|k| ((depth_m[k] - depth_m[k - 1]) / (t_s[k] - t_s[k - 1])).abs())
                .fold(0.0, f64::max),
        }
    }

    /// Fastest intrusion, m/s: the largest down rate over the segments that end below the
    /// surface (a withdrawal, or the fall through the air before a landing, is not an
    /// intrusion); 0 when the intruder never goes down into the bed.
    pub fn max_intrusion_speed(&self) -> f64 {
        match self {
            Self::Constant { speed_m_s, .. } => speed_m_s.max(0.0),
            Self::Table { t_s, depth_m, .. } => (1..t_s.len())
                .filter(|&k| depth_m[k] > 0.0)
                .map(|k| (depth_m[k] - depth_m[k - 1]) / (t_s[k] - t_s[k - 1]))
                .fold(0.0, f64::max),
        }
    }

    /// Read a trajectory CSV: a time column `t_s` and either the foot height `x_f_m`
    /// (`jump --out`'s `trajectory.csv`: depth = -x_f) or `depth_m` (a tracked foot).
    /// `window` (from, to) in the file's seconds keeps part of it; time then starts at 0.
    pub fn from_csv(path: &Path, window: (Option<f64>, Option<f64>)) -> Result<Self, String> {
        let rows = read_rows(path)?;
        let keep: Vec<&Row> = rows
            .iter()
            .filter(|r| {
                !(window.0.is_some_and(|a| r.t_s < a) || window.1.is_some_and(|b| r.t_s > b))
            })
            .collect();
        Self::table(&keep, 0.0, path, "in the window")
    }

    /// The push-off episode of a jump's `trajectory.csv` (`jump --out`: `t_s`, `x_f_m` and
    /// `mode`): the foot's last intrusion before the jump's flight (the last `Aerial` run that
    /// follows an intrusion; a stutter's preliminary hop follows none), shifted so that its
    /// first intruding sample is at the bed's surface (depth 0, as the paper's DEM intrusions
    /// start: the foot at rest of the jump sits below the surface of an intact bed) and at
    /// time 0. The sample before it (at rest, or in the air before a landing) stays, at or
    /// above the surface.
    pub fn push_off_from_csv(path: &Path) -> Result<Self, String> {
        let rows = read_rows(path)?;
        let name = path.display();
        if rows.iter().any(|r| r.mode.is_none()) {
            return Err(format!(
                "--trajectory {name}: --episode needs a `mode` column (a `jump --out` trajectory.csv)"
            ));
        }
        let is = |r: &Row, m: &str| r.mode.as_deref() == Some(m);
        // The flight: the last run of Aerial rows with an intrusion before it.
        let mut best = (0, 0);
        let mut k = 0;
        let mut intruded = false;
        while k < rows.len() {
            if is(&rows[k], "Aerial") {
                let start = k;
                while k < rows.len() && is(&rows[k], "Aerial") {
                    k += 1;
                }
                if intruded {
                    best = (start, k);
                }
            } else {
                intruded |= is(&rows[k], "Intruding");
                k += 1;
            }
        }
        if best.1 == best.0 {
            return Err(format!(
                "--trajectory {name}: the jump never takes off after an intrusion (no `Aerial` rows after an `Intruding` one): no push-off to take"
            ));
        }
        // The last Intruding run before the flight (Static rows may lie between).
        let before = &rows[..best.0];
        let Some(end) = before.iter().rposition(|r| is(r, "Intruding")) else {
            return Err(format!(
                "--trajectory {name}: the foot does not intrude before its flight at {} s: no push-off to take",
                rows[best.0].t_s
            ));
        };
        let start = before[..=end]
            .iter()
            .rposition(|r| !is(r, "Intruding"))
            .map_or(0, |k| k + 1);
        // The episode from the sample before it to its end, its first intruding sample (the
        // start event: a touchdown or a restart) at the surface.
        let from = start.saturating_sub(1);
        let episode: Vec<&Row> = rows[from..=end].iter().collect();
        let surface = rows[start].depth_m;
        Self::table(&episode, surface, path, "in its push-off episode")
    }

    fn table(rows: &[&Row], depth_offset_m: f64, path: &Path, what: &str) -> Result<Self, String> {
        if rows.len() < 2 {
            return Err(format!(
                "--trajectory {}: {} rows {what} (allowed: at least 2)",
                path.display(),
                rows.len()
            ));
        }
        let t0 = rows[0].t_s;
        Ok(Self::Table {
            t_s: rows.iter().map(|r| r.t_s - t0).collect(),
            depth_m: rows.iter().map(|r| r.depth_m - depth_offset_m).collect(),
            source: path.display().to_string(),
        })
    }

    /// Refuse a trajectory whose intruder starts below the bed's surface, inside grains that
    /// were never displaced (its first force would be that of the overlap, not of the
    /// intrusion): the start must be at or above the surface (depth <= 0).
    pub fn check_starts_at_surface(&self) -> Result<(), String> {
        let d0 = self.depth(0.0);
        if d0 > 0.0 {
            let source = match self {
                Self::Table { source, .. } => format!("--trajectory {source}: "),
                Self::Constant { .. } => String::new(),
            };
            return Err(format!(
                "{source}the intruder starts {:.3} mm below the bed's surface (allowed: at or above it, depth <= 0; for a jump's trajectory.csv take its push-off with --episode push-off, which starts at the surface)",
                1e3 * d0
            ));
        }
        Ok(())
    }
}

/// One row of a trajectory file.
struct Row {
    t_s: f64,
    depth_m: f64,
    mode: Option<String>,
}

/// The rows of a trajectory CSV (time strictly increasing).
fn read_rows(path: &Path) -> Result<Vec<Row>, String> {
    let name = path.display().to_string();
    let mut rdr = csv::Reader::from_path(path).map_err(|e| format!("--trajectory {name}: {e}"))?;
    let headers = rdr
        .headers()
        .map_err(|e| format!("--trajectory {name}: {e}"))?
        .clone();
    let col = |n: &str| headers.iter().position(|h| h.trim() == n);
    let t_col = col("t_s").ok_or_else(|| {
        format!(
            "--trajectory {name}: no `t_s` column (columns: {}; allowed: t_s with x_f_m or depth_m)",
            headers.iter().collect::<Vec<_>>().join(",")
        )
    })?;
    let (d_col, sign) = match (col("depth_m"), col("x_f_m")) {
        (Some(c), _) => (c, 1.0),
        (None, Some(c)) => (c, -1.0),
        (None, None) => {
            return Err(format!(
                "--trajectory {name}: no `x_f_m` or `depth_m` column (columns: {})",
                headers.iter().collect::<Vec<_>>().join(",")
            ));
        }
    };
    let mode_col = col("mode");
    let mut rows: Vec<Row> = Vec::new();
    for (k, rec) in rdr.records().enumerate() {
        let line = k + 2;
        let rec = rec.map_err(|e| format!("--trajectory {name} line {line}: {e}"))?;
        let num = |c: usize, what: &str| -> Result<f64, String> {
            let s = rec.get(c).unwrap_or("").trim();
            sandjumper_output::parse::parse_number(s).map_err(|_| {
                format!("--trajectory {name} line {line}: {what} `{s}` is not a number")
            })
        };
        let t = num(t_col, "t_s")?;
        let d = sign * num(d_col, "depth")?;
        if let Some(prev) = rows.last().map(|r| r.t_s)
            && t <= prev
        {
            return Err(format!(
                "--trajectory {name} line {line}: time {t} s does not increase (previous {prev} s; allowed: strictly increasing)"
            ));
        }
        rows.push(Row {
            t_s: t,
            depth_m: d,
            mode: mode_col
                .and_then(|c| rec.get(c))
                .map(|m| m.trim().to_string()),
        });
    }
    Ok(rows)
}

/// The intruder's geometry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IntruderSpec {
    /// Width, m (the foot's 7.6 cm, or scaled).
    pub width_m: f64,
    /// Centre x, m.
    pub x_centre_m: f64,
    /// Diameter of its grains, m.
    pub grain_d_m: f64,
}

impl IntruderSpec {
    /// Left and right edges, m.
    pub fn edges(&self) -> (f64, f64) {
        (
            self.x_centre_m - 0.5 * self.width_m,
            self.x_centre_m + 0.5 * self.width_m,
        )
    }

    /// Add the row (centres half a grain apart, outer edges at the foot's edges) with its
    /// bottom at `bottom_m`; returns how many grains.
    pub fn add_to(&self, g: &mut Grains, bottom_m: f64, density_kg_m3: f64) -> usize {
        let d = self.grain_d_m;
        let span = self.width_m - d;
        let n = ((span / (0.5 * d)).ceil() as usize).max(1) + 1;
        let (left, _) = self.edges();
        for k in 0..n {
            let x = left + 0.5 * d + span * k as f64 / (n - 1) as f64;
            g.push(x, bottom_m + 0.5 * d, d, density_kg_m3, INTRUDER);
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A jump's trajectory.csv in miniature: rest below the surface, a preliminary hop, a
    /// short landing intrusion, rest, the push-off intrusion, the flight, the landing.
    fn jump_csv(dir: &Path) -> std::path::PathBuf {
        let rows: &[(f64, f64, &str)] = &[
            (0.000, -0.0085, "Static"),
            (0.001, -0.0086, "Intruding"),
            (0.002, -0.0080, "Aerial"),
            (0.003, -0.0082, "Intruding"),
            (0.004, -0.0090, "Static"),
            (0.005, -0.0095, "Intruding"),
            (0.006, -0.0105, "Intruding"),
            (0.007, -0.0110, "Intruding"),
            (0.008, -0.0100, "Aerial"),
            (0.009, 0.0300, "Aerial"),
            (0.010, 0.0100, "Aerial"),
            (0.011, -0.0120, "Intruding"),
        ];
        let mut text = String::from("t_s,x_f_m,mode\n");
        for (t, x, m) in rows {
            text += &format!("{t},{x},{m}\n");
        }
        let path = dir.join("trajectory.csv");
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn the_push_off_episode_is_the_last_intrusion_before_the_flight_from_the_surface() {
        let dir = tempfile::tempdir().unwrap();
        let path = jump_csv(dir.path());
        let Trajectory::Table { t_s, depth_m, .. } = Trajectory::push_off_from_csv(&path).unwrap()
        else {
            panic!("a table");
        };
        // From the sample before the episode (at rest, 9.0 mm) to its last intruding sample,
        // the first intruding one (9.5 mm) at the surface.
        assert_eq!(t_s.len(), 4);
        assert!((t_s[3] - 0.003).abs() < 1e-12, "{t_s:?}");
        let want = [-0.0005, 0.0, 0.0010, 0.0015];
        for (d, w) in depth_m.iter().zip(want) {
            assert!((d - w).abs() < 1e-12, "{depth_m:?}");
        }
        let whole = Trajectory::from_csv(&path, (None, None)).unwrap();
        assert!(
            Trajectory::push_off_from_csv(&path)
                .unwrap()
                .check_starts_at_surface()
                .is_ok()
        );
        let refused = whole.check_starts_at_surface().unwrap_err();
        assert!(
            refused.contains("8.500 mm below the bed's surface"),
            "{refused}"
        );
        assert!(refused.contains("--episode push-off"), "{refused}");
    }

    #[test]
    fn an_episode_needs_modes_and_a_flight() {
        let dir = tempfile::tempdir().unwrap();
        let no_mode = dir.path().join("a.csv");
        std::fs::write(&no_mode, "t_s,depth_m\n0,0\n0.001,0.001\n").unwrap();
        let e = Trajectory::push_off_from_csv(&no_mode).unwrap_err();
        assert!(e.contains("`mode` column"), "{e}");
        let grounded = dir.path().join("b.csv");
        std::fs::write(
            &grounded,
            "t_s,x_f_m,mode\n0,0,Static\n0.001,-0.001,Intruding\n",
        )
        .unwrap();
        let e = Trajectory::push_off_from_csv(&grounded).unwrap_err();
        assert!(e.contains("never takes off after an intrusion"), "{e}");
        // A stutter whose preliminary hop (no intrusion before it) is longer than its flight.
        let hop = dir.path().join("c.csv");
        std::fs::write(
            &hop,
            "t_s,x_f_m,mode\n0,-0.008,Static\n1,-0.005,Aerial\n2,0.01,Aerial\n3,0.01,Aerial\n\
             4,0.001,Aerial\n5,0,Intruding\n6,-0.002,Intruding\n7,-0.003,Aerial\n8,0.02,Aerial\n",
        )
        .unwrap();
        let Trajectory::Table { t_s, depth_m, .. } = Trajectory::push_off_from_csv(&hop).unwrap()
        else {
            panic!("a table");
        };
        // The landing's touchdown sample is the surface; the air sample before it stays above.
        assert_eq!(t_s, [0.0, 1.0, 2.0]);
        assert_eq!(depth_m, [-0.001, 0.0, 0.002]);
        // Its fastest intrusion is in the bed, not the fall before the touchdown.
        let landing = Trajectory::Table {
            t_s: vec![0.0, 1.0, 2.0, 3.0],
            depth_m: vec![-0.01, 0.0, 0.002, -0.005],
            source: String::new(),
        };
        assert_eq!(landing.max_speed(), 0.01);
        assert_eq!(landing.max_intrusion_speed(), 0.002);
        // A hop and a landing, no take-off after it.
        let no_jump = dir.path().join("d.csv");
        std::fs::write(
            &no_jump,
            "t_s,x_f_m,mode\n0,-0.008,Static\n1,0.01,Aerial\n2,0,Intruding\n3,-0.002,Static\n",
        )
        .unwrap();
        let e = Trajectory::push_off_from_csv(&no_jump).unwrap_err();
        assert!(e.contains("never takes off after an intrusion"), "{e}");
        let constant = Trajectory::Constant {
            speed_m_s: 0.3,
            start_depth_m: -0.0005,
            end_depth_m: 0.01,
        };
        assert!(constant.check_starts_at_surface().is_ok());
    }

    #[test]
    fn a_froude_scaled_motion_keeps_depth_over_size_and_the_froude_number() {
        let t = Trajectory::Table {
            t_s: vec![0.0, 0.01, 0.03],
            depth_m: vec![0.0, 0.004, 0.012],
            source: "jump".into(),
        };
        let k = 0.25;
        let s = t.froude_scaled(k);
        // Depth over size kept at every scaled time.
        for (time, depth) in [(0.0, 0.0), (0.01, 0.004), (0.02, 0.008), (0.03, 0.012)] {
            assert!((s.depth(time * k.sqrt()) - k * depth).abs() < 1e-15);
        }
        // v^2 / (g L): the speed scales with the square root of the size.
        let (v0, v1) = (t.speed(0.005), s.speed(0.005 * k.sqrt()));
        assert!((v1 * v1 / k - v0 * v0).abs() < 1e-12 * v0 * v0, "{v0} {v1}");
        let c = Trajectory::Constant {
            speed_m_s: 0.4,
            start_depth_m: 0.0,
            end_depth_m: 0.02,
        }
        .froude_scaled(k);
        assert_eq!(
            c,
            Trajectory::Constant {
                speed_m_s: 0.2,
                start_depth_m: 0.0,
                end_depth_m: 0.005
            }
        );
    }
}
