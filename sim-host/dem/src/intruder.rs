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

    /// Read a trajectory CSV: a time column `t_s` and either the foot height `x_f_m`
    /// (`jump --out`'s `trajectory.csv`: depth = -x_f) or `depth_m` (a tracked foot).
    /// `window` (from, to) in the file's seconds keeps part of it; time then starts at 0.
    pub fn from_csv(path: &Path, window: (Option<f64>, Option<f64>)) -> Result<Self, String> {
        let name = path.display().to_string();
        let mut rdr =
            csv::Reader::from_path(path).map_err(|e| format!("--trajectory {name}: {e}"))?;
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
        let (mut ts, mut ds) = (Vec::new(), Vec::new());
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
            if let Some(&prev) = ts.last()
                && t <= prev
            {
                return Err(format!(
                    "--trajectory {name} line {line}: time {t} s does not increase (previous {prev} s; allowed: strictly increasing)"
                ));
            }
            if window.0.is_some_and(|a| t < a) || window.1.is_some_and(|b| t > b) {
                continue;
            }
            ts.push(t);
            ds.push(d);
        }
        if ts.len() < 2 {
            return Err(format!(
                "--trajectory {name}: {} rows in the window (allowed: at least 2)",
                ts.len()
            ));
        }
        let t0 = ts[0];
        ts.iter_mut().for_each(|t| *t -= t0);
        Ok(Self::Table {
            t_s: ts,
            depth_m: ds,
            source: name,
        })
    }
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
