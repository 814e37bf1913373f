//! What a fit hands back: the fitted values with their standard errors, how well they fit,
//! and the three ways of showing it (readable summary, JSON, a `--params` TOML file).

use core::fmt::Write as _;

use serde::Serialize;

use sandjumper_model::params::Params;

/// Two-sided 95 % normal quantile used for the printed confidence intervals.
pub const Z95: f64 = 1.959_963_985;

/// One fitted parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedValue {
    /// Packing fraction the value belongs to (`None` where it does not apply).
    pub phi: Option<f64>,
    /// Name after the paper: `k1`, `k2`, `delta`, `kappa`, `l_re`, `mu`, `C`, `alpha`, `b`.
    pub param: &'static str,
    /// Best-fit value, SI units ([`FittedValue::unit`]).
    pub value: f64,
    /// Standard error, same units.
    pub stderr: f64,
    /// Unit, e.g. `N/m`.
    pub unit: &'static str,
}

impl FittedValue {
    /// Parameter `index` of a least-squares fit.
    pub fn from_fit(
        fit: &super::least_squares::LeastSquaresFit,
        index: usize,
        phi: Option<f64>,
        param: &'static str,
        unit: &'static str,
    ) -> Self {
        Self {
            phi,
            param,
            value: fit.values[index],
            stderr: fit.stderr[index],
            unit,
        }
    }

    /// 95 % confidence interval `value ± 1.96 stderr` (normal approximation).
    pub fn confidence_95(&self) -> (f64, f64) {
        (
            self.value - Z95 * self.stderr,
            self.value + Z95 * self.stderr,
        )
    }
}

/// A parameter override to write to the `--params` TOML: `[table] key = value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// Dotted key in [`Params`]' TOML, e.g. `sand.k1_n_m`.
    pub key: &'static str,
    /// Value in the unit of that key.
    pub value: f64,
}

impl Override {
    /// `key = value`.
    pub fn new(key: &'static str, value: f64) -> Self {
        Self { key, value }
    }
}

/// The result of one `sandjumper fit ...` run.
#[derive(Clone, Debug, PartialEq)]
pub struct FitReport {
    /// One line saying what was fitted to what, e.g. "two-resistance law, 120 points".
    pub title: String,
    /// Fitted values, in a stable order.
    pub fits: Vec<FittedValue>,
    /// RMS of the residuals (model - data) over all points used.
    pub residual_rms: f64,
    /// Unit of the residuals (N, kg, m).
    pub residual_unit: &'static str,
    /// Points used in the fit.
    pub points_used: usize,
    /// Points read but left out (with the rule in [`FitReport::notes`]).
    pub points_excluded: usize,
    /// Extra lines for the summary: exclusion rules, scalings, caveats.
    pub notes: Vec<String>,
    /// `--params` overrides, grouped by packing fraction (`None`: one file for any phi).
    pub overrides: Vec<(Option<f64>, Vec<Override>)>,
}

#[derive(Serialize)]
struct JsonFit {
    phi: Option<f64>,
    param: &'static str,
    value: f64,
    stderr: f64,
}

#[derive(Serialize)]
struct JsonReport {
    fits: Vec<JsonFit>,
    residual_rms: f64,
}

impl FitReport {
    /// `{"fits": [{"phi", "param", "value", "stderr"}, ...], "residual_rms": ...}`.
    pub fn to_json(&self) -> String {
        let report = JsonReport {
            fits: self
                .fits
                .iter()
                .map(|f| JsonFit {
                    phi: f.phi,
                    param: f.param,
                    value: f.value,
                    stderr: f.stderr,
                })
                .collect(),
            residual_rms: self.residual_rms,
        };
        serde_json::to_string(&report).expect("plain numbers and names")
    }

    /// A readable summary: each value with its standard error and 95 % interval.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "{}", self.title);
        let _ = writeln!(
            s,
            "  {} points used{}",
            self.points_used,
            if self.points_excluded > 0 {
                format!(", {} excluded", self.points_excluded)
            } else {
                String::new()
            }
        );
        for f in &self.fits {
            let (lo, hi) = f.confidence_95();
            let phi = f.phi.map_or(String::new(), |p| format!("phi = {p:.4}  "));
            let _ = writeln!(
                s,
                "  {phi}{:<6} = {:>12} ± {:<11} {:<7} (95% CI {} .. {})",
                f.param,
                sig(f.value),
                sig(f.stderr),
                f.unit,
                sig(lo),
                sig(hi)
            );
        }
        let _ = writeln!(
            s,
            "  residual RMS = {} {}",
            sig(self.residual_rms),
            self.residual_unit
        );
        for note in &self.notes {
            let _ = writeln!(s, "  note: {note}");
        }
        s
    }

    /// The `--params` TOML for the overrides of packing fraction `phi` (a group of
    /// [`FitReport::overrides`]): `[sand]` keys that `jump`, `sweep`, `hil` and `replay`
    /// accept on top of any preset.
    pub fn params_toml(&self, phi: Option<f64>) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# sandjumper fit: {}", self.title);
        if let Some(phi) = phi {
            let _ = writeln!(
                s,
                "# fitted at packing fraction phi = {phi}; use with --phi {phi}"
            );
        }
        let _ = writeln!(
            s,
            "# residual RMS = {} {}",
            sig(self.residual_rms),
            self.residual_unit
        );
        let mut table = toml::Table::new();
        for (group_phi, overrides) in &self.overrides {
            if *group_phi != phi {
                continue;
            }
            for o in overrides {
                let (section, key) = o.key.split_once('.').expect("dotted key");
                table
                    .entry(section)
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                    .as_table_mut()
                    .expect("section table")
                    .insert(key.to_string(), toml::Value::Float(o.value));
            }
        }
        s.push_str(&toml::to_string(&table).expect("plain numbers"));
        s
    }

    /// Check every override file against [`Params::with_overrides_toml`] on `base`.
    pub fn check_overrides(&self, base: &Params) -> Result<(), String> {
        for (phi, _) in &self.overrides {
            base.clone()
                .with_overrides_toml(&self.params_toml(*phi), "fitted parameters")
                .map_err(|e| format!("the fitted values are not valid parameters: {e}"))?;
        }
        Ok(())
    }
}

/// Four significant digits, plain or scientific as fits the magnitude.
pub fn sig(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{x:.3e}")
    } else {
        let digits = if a == 0.0 {
            3
        } else {
            (3 - a.log10().floor() as i32).max(0) as usize
        };
        format!("{x:.digits$}")
    }
}
