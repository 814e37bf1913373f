//! The comparison's rows: one per DEM run (from its typed summary), PIV's added mass (its
//! typed flow rows) against the DEM's, and the DEM's flow tables the figures draw.

use std::collections::HashMap;
use std::path::Path;

use serde::Serialize;

use crate::error::FiguresDemError;
use sandjumper_dem::outputs::Summary;
use sandjumper_flow::analysis::FlowRow;

/// One DEM run of the comparison (a row of `dem_runs.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Its folder under `runs/`.
    pub name: String,
    /// What it is.
    pub what: String,
    /// DEM added mass over eq. 6 (C scaled with R^2), median over the samples with the foot
    /// at >= 0.3 of its fastest, 1.
    pub added_mass_vs_eq6_median: f64,
    /// The headline: the same ratio's median over the samples where eq. 6's cone is forming
    /// (from a quarter of its complete value to its completion), 1 (NaN: none there).
    pub added_mass_vs_eq6_cone_forming_median: f64,
    /// Samples in that median.
    pub cone_forming_samples: usize,
    /// Peak momentum of the column under the foot, kg m/s.
    pub grain_momentum_under_foot_kg_m_s: f64,
    /// Peak force on the foot, N.
    pub max_force_n: f64,
    /// Depth reached, m.
    pub max_depth_m: f64,
    /// Angle of the shear bands' cone, degrees (NaN: no cone: a side does not narrow, or the
    /// sides differ by more than 10 degrees).
    pub shear_band_cone_deg: f64,
    /// The left side's angle, degrees (NaN: it does not narrow).
    pub shear_band_left_deg: f64,
    /// The right side's angle, degrees.
    pub shear_band_right_deg: f64,
    /// Depth below the foot where the fitted sides meet, m.
    pub shear_band_apex_m: f64,
    /// Rows (2 mm each) below the foot with clear bands.
    pub shear_band_rows: usize,
    /// Angle of the co-moving region's cone (down speed half the foot's), degrees (NaN:
    /// none, or the sides differ by more than 10 degrees).
    pub comoving_cone_deg: f64,
    /// Its left side's angle, degrees.
    pub comoving_left_deg: f64,
    /// Its right side's angle, degrees.
    pub comoving_right_deg: f64,
    /// Depth below the foot where its sides meet, m.
    pub comoving_apex_m: f64,
    /// Share of the column's momentum deeper than the 60 degree cone (median), 1.
    pub momentum_beyond_cone_depth_share: f64,
    /// Share of the column's momentum in the coarse-graining window's bottom tenth, 1.
    pub momentum_in_window_bottom_tenth_share: f64,
    /// The run's warning that its motion reaches the window's bottom, if it has one.
    pub window_depth_warning: Option<String>,
    /// Grains.
    pub grains: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl Row {
    /// The row of the intrusion `s`, called `name`, described by `what`, that took `wall_s`.
    pub fn of(s: &Summary, name: &str, what: &str, wall_s: f64) -> Self {
        let nan = f64::NAN;
        let cone = s.shear_band_cone.as_ref();
        let moving = s.comoving_cone.as_ref();
        Self {
            name: name.into(),
            what: what.into(),
            added_mass_vs_eq6_median: s.added_mass_vs_eq6_median,
            added_mass_vs_eq6_cone_forming_median: s.added_mass_vs_eq6_cone_forming_median,
            cone_forming_samples: s.cone_forming_samples,
            grain_momentum_under_foot_kg_m_s: s.grain_momentum_under_foot_kg_m_s,
            max_force_n: s.max_force_n,
            max_depth_m: s.max_depth_m,
            shear_band_cone_deg: cone.map_or(nan, |c| c.angle_deg),
            shear_band_left_deg: cone.map_or(nan, |c| c.left_deg),
            shear_band_right_deg: cone.map_or(nan, |c| c.right_deg),
            shear_band_apex_m: cone.map_or(nan, |c| c.apex_depth_m),
            shear_band_rows: cone.map_or(0, |c| c.rows.len()),
            comoving_cone_deg: moving.map_or(nan, |c| c.angle_deg),
            comoving_left_deg: moving.map_or(nan, |c| c.left_deg),
            comoving_right_deg: moving.map_or(nan, |c| c.right_deg),
            comoving_apex_m: moving.map_or(nan, |c| c.apex_depth_m),
            momentum_beyond_cone_depth_share: s.momentum_beyond_cone_depth_share,
            momentum_in_window_bottom_tenth_share: s.momentum_in_window_bottom_tenth_share,
            window_depth_warning: s.window_depth_warning.clone(),
            grains: s.grains as u64,
            wall_s,
        }
    }

    /// The line `figures dem` prints for this run.
    pub fn line(&self) -> String {
        format!(
            "  {:<13} DEM/eq. 6 {:.2} where its cone forms ({} samples; {:.2} over all), peak P under the foot {:.4} kg m/s, shear-band cone {}, co-moving cone {}",
            self.name,
            self.added_mass_vs_eq6_cone_forming_median,
            self.cone_forming_samples,
            self.added_mass_vs_eq6_median,
            self.grain_momentum_under_foot_kg_m_s,
            if self.shear_band_cone_deg.is_finite() {
                format!(
                    "{:.0} deg ({} rows)",
                    self.shear_band_cone_deg, self.shear_band_rows
                )
            } else {
                format!(
                    "none (bands do not narrow over {} rows)",
                    self.shear_band_rows
                )
            },
            if self.comoving_cone_deg.is_finite() {
                format!("{:.0} deg", self.comoving_cone_deg)
            } else if self.comoving_left_deg.is_finite() || self.comoving_right_deg.is_finite() {
                format!(
                    "none (sides {:.0} and {:.0} deg)",
                    self.comoving_left_deg, self.comoving_right_deg
                )
            } else {
                "none (the moving region does not narrow below the foot)".to_string()
            }
        )
    }
}

/// The columns of `dem_runs.csv`.
pub const ROW_HEADER: &[&str] = &[
    "name",
    "what",
    "added_mass_vs_eq6_median",
    "added_mass_vs_eq6_cone_forming_median",
    "cone_forming_samples",
    "grain_momentum_under_foot_kg_m_s",
    "max_force_n",
    "max_depth_m",
    "shear_band_cone_deg",
    "shear_band_left_deg",
    "shear_band_right_deg",
    "shear_band_apex_m",
    "shear_band_rows",
    "comoving_cone_deg",
    "comoving_left_deg",
    "comoving_right_deg",
    "comoving_apex_m",
    "momentum_beyond_cone_depth_share",
    "momentum_in_window_bottom_tenth_share",
    "window_depth_warning",
    "grains",
    "wall_s",
];

/// A CSV's rows as maps of column to number (text columns and empty cells: NaN).
pub type Table = Vec<HashMap<String, f64>>;

/// A row's value of `key` (NaN when the column is missing).
pub fn val(row: &HashMap<String, f64>, key: &str) -> f64 {
    row.get(key).copied().unwrap_or(f64::NAN)
}

/// Read a CSV file into a [`Table`].
pub fn read_table(path: &Path) -> Result<Table, FiguresDemError> {
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
    let head: Vec<String> = r
        .headers()
        .map_err(FiguresDemError::internal)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
        rows.push(
            head.iter()
                .zip(rec.iter())
                .map(|(h, v)| (h.clone(), v.parse::<f64>().unwrap_or(f64::NAN)))
                .collect(),
        );
    }
    Ok(rows)
}

/// PIV's added mass on the DEM's frames against the DEM's own at the pairs' times.
#[derive(Clone, Debug, Serialize)]
pub struct PivComparison {
    /// The pairs compared.
    pub points: Vec<PivPoint>,
    /// Median of PIV over DEM added mass, 1 (NaN: no pairs).
    pub ratio_median: f64,
}

/// One PIV pair against the DEM (a row of `piv_vs_dem.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct PivPoint {
    /// The pair's time, s.
    pub t_s: f64,
    /// The DEM foot's depth then, m.
    pub depth_m: f64,
    /// The DEM's added mass then, kg.
    pub dem_added_mass_kg: f64,
    /// PIV's, kg.
    pub piv_added_mass_kg: f64,
}

/// Compare the flow table of a DEM run (the `flow.csv` in `dem`) with PIV's on its frames
/// (`piv`, PIV's outcome's rows).
pub fn compare_piv(dem: &Path, piv: &[FlowRow]) -> Result<PivComparison, FiguresDemError> {
    let d = read_table(&dem.join("flow.csv"))?;
    let at = |t: f64, key: &str| {
        // Linear between the DEM's samples around t (a PIV pair sits between two frames).
        d.windows(2)
            .find(|w| val(&w[0], "t_s") <= t && t <= val(&w[1], "t_s"))
            .map_or(f64::NAN, |w| {
                let f = (t - val(&w[0], "t_s")) / (val(&w[1], "t_s") - val(&w[0], "t_s"));
                val(&w[0], key) + f * (val(&w[1], key) - val(&w[0], key))
            })
    };
    let points: Vec<PivPoint> = piv
        .iter()
        .filter(|r| r.added_mass_kg.is_finite())
        .map(|r| PivPoint {
            t_s: r.t_s,
            depth_m: at(r.t_s, "depth_m"),
            dem_added_mass_kg: at(r.t_s, "added_mass_kg"),
            piv_added_mass_kg: r.added_mass_kg,
        })
        .filter(|q| q.dem_added_mass_kg.is_finite())
        .collect();
    let ratio_median = sandjumper_dem::outputs::median(
        points
            .iter()
            .map(|q| q.piv_added_mass_kg / q.dem_added_mass_kg)
            .collect(),
    );
    Ok(PivComparison {
        points,
        ratio_median,
    })
}
