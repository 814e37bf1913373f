//! Measurement files for the fits: plain CSV with a header row, checked line by line.
//!
//! - intrusion curves: `depth_m,force_n` (slow intrusion at constant speed; depth increasing);
//! - added mass: `depth_m,added_mass_kg` (e.g. from PIV, `m_a = P / v_foot`);
//! - jumps: the columns of `sweep.csv`, `kind,phi,freq_hz,tau_s,jump_height_m` (plus
//!   `final_jump_height_m` when the final height is fitted); extra columns are ignored.
//!
//! Every problem is reported as a [`DataError`] naming the file, the 1-based line and what
//! is wrong: a missing column, a value that is not a finite number, a depth that does not
//! increase, too few points, a force curve that is zero everywhere.

use core::fmt;
use std::path::{Path, PathBuf};

use sandjumper_core::trajectory::JumpKind;

use sandjumper_model::trajectory::parse_kind;

/// A measurement file that cannot be used, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct DataError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line in the file, when the problem is on one line.
    pub line: Option<u64>,
    /// What is wrong, and what is allowed.
    pub problem: String,
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}: {}", self.path.display(), self.problem),
            None => write!(f, "{}: {}", self.path.display(), self.problem),
        }
    }
}

impl std::error::Error for DataError {}

impl DataError {
    fn new(path: &Path, line: Option<u64>, problem: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            line,
            problem: problem.into(),
        }
    }
}

/// The rows of a CSV file restricted to the requested columns, as text, with line numbers.
struct Table {
    /// (line, one value per requested column).
    rows: Vec<(u64, Vec<String>)>,
}

fn read_table(path: &Path, columns: &[&str]) -> Result<Table, DataError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| {
            DataError::new(
                path,
                None,
                format!("cannot read the file: {}", io_reason(&e)),
            )
        })?;
    let header = reader
        .headers()
        .map_err(|e| DataError::new(path, Some(1), format!("cannot read the header row: {e}")))?
        .clone();
    let index: Vec<usize> = columns
        .iter()
        .map(|want| {
            header.iter().position(|h| h == *want).ok_or_else(|| {
                DataError::new(
                    path,
                    Some(1),
                    format!(
                        "missing column `{want}` (header has: {}; required: {})",
                        header.iter().collect::<Vec<_>>().join(","),
                        columns.join(",")
                    ),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line());
            DataError::new(path, line, format!("malformed CSV row: {e}"))
        })?;
        let line = record.position().map_or(0, |p| p.line());
        if record.iter().all(str::is_empty) {
            continue;
        }
        let values = index
            .iter()
            .zip(columns)
            .map(|(&i, name)| {
                record.get(i).map(str::to_string).ok_or_else(|| {
                    DataError::new(
                        path,
                        Some(line),
                        format!("row has no value for column `{name}`"),
                    )
                })
            })
            .collect::<Result<_, _>>()?;
        rows.push((line, values));
    }
    Ok(Table { rows })
}

fn io_reason(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::Io(io) => io.to_string(),
        _ => e.to_string(),
    }
}

fn number(path: &Path, line: u64, column: &str, text: &str) -> Result<f64, DataError> {
    let value: f64 = text.parse().map_err(|_| {
        DataError::new(
            path,
            Some(line),
            format!("column `{column}`: `{text}` is not a number"),
        )
    })?;
    if !value.is_finite() {
        return Err(DataError::new(
            path,
            Some(line),
            format!("column `{column}`: `{text}` is not a finite number"),
        ));
    }
    Ok(value)
}

/// A measured curve `y(depth)` with strictly increasing depth (one intrusion stroke).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthCurve {
    /// Depth below the free surface, m (strictly increasing, >= 0).
    pub depth_m: Vec<f64>,
    /// The measured quantity at each depth (force in N, or added mass in kg).
    pub value: Vec<f64>,
    /// 1-based file line of each point.
    pub line: Vec<u64>,
}

impl DepthCurve {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.depth_m.len()
    }

    /// True if the curve has no points.
    pub fn is_empty(&self) -> bool {
        self.depth_m.is_empty()
    }
}

/// Read `depth_m,<value_column>` from `path`: at least `min_points` rows, depth >= 0 and
/// strictly increasing, values finite and not all zero.
pub fn read_depth_curve(
    path: &Path,
    value_column: &str,
    min_points: usize,
) -> Result<DepthCurve, DataError> {
    let table = read_table(path, &["depth_m", value_column])?;
    let mut curve = DepthCurve {
        depth_m: Vec::new(),
        value: Vec::new(),
        line: Vec::new(),
    };
    for (line, v) in &table.rows {
        let depth = number(path, *line, "depth_m", &v[0])?;
        let value = number(path, *line, value_column, &v[1])?;
        if depth < 0.0 {
            return Err(DataError::new(
                path,
                Some(*line),
                format!(
                    "depth_m = {depth} is negative (allowed: depth below the free surface, >= 0)"
                ),
            ));
        }
        if let Some(&previous) = curve.depth_m.last()
            && depth <= previous
        {
            return Err(DataError::new(
                path,
                Some(*line),
                format!(
                    "depth_m = {depth} does not increase (previous row {previous}); \
                         allowed: one intrusion stroke with strictly increasing depth"
                ),
            ));
        }
        curve.depth_m.push(depth);
        curve.value.push(value);
        curve.line.push(*line);
    }
    if curve.len() < min_points {
        return Err(DataError::new(
            path,
            None,
            format!(
                "{} data rows; at least {min_points} are needed for this fit",
                curve.len()
            ),
        ));
    }
    if curve.value.iter().all(|v| *v == 0.0) {
        return Err(DataError::new(
            path,
            None,
            format!("`{value_column}` is zero on every row"),
        ));
    }
    Ok(curve)
}

/// Which measured height a jump fit compares with the simulator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeightColumn {
    /// `jump_height_m`: the highest point of the whole run (the paper's camera measure).
    Jump,
    /// `final_jump_height_m`: the highest point after the push-off half begins.
    Final,
}

impl HeightColumn {
    /// The CSV column name.
    pub fn column(self) -> &'static str {
        match self {
            Self::Jump => "jump_height_m",
            Self::Final => "final_jump_height_m",
        }
    }
}

/// One measured jump (a row of `sweep.csv` or a lab's equivalent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JumpMeasurement {
    /// Trajectory.
    pub kind: JumpKind,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay of a delayed stutter, s (0 otherwise).
    pub tau_s: f64,
    /// Measured height, m.
    pub height_m: f64,
    /// 1-based file line.
    pub line: u64,
}

/// Read jump measurements; every row must have a known kind, 0 < phi < 1, freq > 0,
/// tau >= 0 and a height >= 0.
pub fn read_jumps(path: &Path, height: HeightColumn) -> Result<Vec<JumpMeasurement>, DataError> {
    let columns = ["kind", "phi", "freq_hz", "tau_s", height.column()];
    let table = read_table(path, &columns)?;
    let mut jumps = Vec::with_capacity(table.rows.len());
    for (line, v) in &table.rows {
        let line = *line;
        let kind = parse_kind(&v[0]).ok_or_else(|| {
            DataError::new(
                path,
                Some(line),
                format!(
                    "column `kind`: unknown jump kind `{}` (allowed: single, stutter, delayed)",
                    v[0]
                ),
            )
        })?;
        let phi = number(path, line, "phi", &v[1])?;
        let freq_hz = number(path, line, "freq_hz", &v[2])?;
        let tau_s = number(path, line, "tau_s", &v[3])?;
        let height_m = number(path, line, columns[4], &v[4])?;
        let check = |ok: bool, what: String| {
            if ok {
                Ok(())
            } else {
                Err(DataError::new(path, Some(line), what))
            }
        };
        check(
            phi > 0.0 && phi < 1.0,
            format!("phi = {phi} (allowed: 0 < phi < 1)"),
        )?;
        check(freq_hz > 0.0, format!("freq_hz = {freq_hz} (allowed: > 0)"))?;
        check(tau_s >= 0.0, format!("tau_s = {tau_s} (allowed: >= 0)"))?;
        check(
            height_m >= 0.0,
            format!("{} = {height_m} (allowed: >= 0)", columns[4]),
        )?;
        jumps.push(JumpMeasurement {
            kind,
            phi,
            freq_hz,
            tau_s,
            height_m,
            line,
        });
    }
    if jumps.is_empty() {
        return Err(DataError::new(path, None, "no data rows"));
    }
    Ok(jumps)
}
