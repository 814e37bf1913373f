//! Model parameters (docs/model.md sections 1 and 3): serde + TOML, presets per packing fraction,
//! overrides from a user's TOML file, validation.
//!
//! Every field is SI and carries its unit in its name. [`Params::preset`] fills the sand
//! section from docs/model.md's per-packing table (linear interpolation between rows); a user's
//! TOML file then overrides any field ([`Params::with_overrides_toml`]); [`Params::to_toml`]
//! writes the resolved set, which reads back to the same value.

use core::fmt;
use core::str::FromStr;
use serde::{Deserialize, Serialize};

/// The named ground models of docs/model.md section 3 (the names the CLI and presets use).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelName {
    /// Rigid floor at z = 0; perfectly plastic impact.
    Hard,
    /// `F_p = k1 z`, no re-intrusion, constant alpha.
    Eq1Linear,
    /// Two-resistance `F_p`, re-intrusion overshoot, constant alpha.
    Eq1,
    /// Cone `F_p`, re-intrusion overshoot, added mass (the paper's final model, the default).
    #[default]
    Eq4,
}

impl ModelName {
    /// Every model, in the order of docs/model.md's table.
    pub const ALL: [ModelName; 4] = [Self::Hard, Self::Eq1Linear, Self::Eq1, Self::Eq4];

    /// The name the CLI and files use.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Hard => "hard",
            Self::Eq1Linear => "eq1-linear",
            Self::Eq1 => "eq1",
            Self::Eq4 => "eq4",
        }
    }
}

impl fmt::Display for ModelName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for ModelName {
    type Err = ParamsError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| ParamsError {
                source: String::new(),
                key: Some("model".into()),
                line: None,
                message: format!("unknown model `{s}`"),
                allowed: "one of hard, eq1-linear, eq1, eq4".into(),
            })
    }
}

/// The three bodies and the spring (docs/model.md section 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotParams {
    /// m_m: linear motor + air-bearing carriage, kg.
    pub motor_mass_kg: f64,
    /// m_r: thrust rod, kg.
    pub rod_mass_kg: f64,
    /// m_f: flat disc foot, kg.
    pub foot_mass_kg: f64,
    /// k_s: spring between rod bottom and foot, N/m.
    pub spring_stiffness_n_m: f64,
    /// c_s: spring damping, N s/m.
    pub spring_damping_n_s_m: f64,
    /// L0: spring rest length, m. Only differences of heights are reported, so it only sets
    /// where the rod sits above the foot.
    pub spring_rest_length_m: f64,
    /// R: foot radius, m.
    pub foot_radius_m: f64,
    /// A: amplitude of the one-cycle sine trajectories, m.
    pub stroke_amplitude_m: f64,
    /// |p| limit of the actuator, m.
    pub stroke_limit_m: f64,
    /// g, m/s^2.
    pub gravity_m_s2: f64,
}

impl RobotParams {
    /// The robot of docs/model.md section 1 (the same at every packing fraction).
    pub const MODEL: Self = Self {
        motor_mass_kg: 1.125,
        rod_mass_kg: 0.125,
        foot_mass_kg: 0.030,
        spring_stiffness_n_m: 3300.0,
        spring_damping_n_s_m: 4.0,
        spring_rest_length_m: 0.1,
        foot_radius_m: 0.038,
        stroke_amplitude_m: 0.01875,
        stroke_limit_m: 0.025,
        gravity_m_s2: 9.81,
    };
}

/// The motor drive for force-driven runs: `F_m = clamp(K_f i, -F_peak, F_peak)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveParams {
    /// K_f: force constant, N/A (chosen).
    pub force_constant_n_a: f64,
    /// F_peak: largest force the motor gives, N (chosen).
    pub peak_force_n: f64,
    /// Time constant of the first-order current lag, s; 0 disables the lag (chosen).
    pub current_lag_s: f64,
}

/// The sand (docs/model.md section 3) at one packing fraction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SandParams {
    /// phi: packing fraction (dimensionless). Enters the added mass directly.
    pub packing_fraction: f64,
    /// phi_c: critical packing fraction (informational; the presets encode its effect).
    pub critical_packing_fraction: f64,
    /// k1: first (shallow) penetration stiffness for a foot of `reference_foot_radius_m`, N/m.
    pub k1_n_m: f64,
    /// k2: second (deep) penetration stiffness for a foot of `reference_foot_radius_m`, N/m.
    pub k2_n_m: f64,
    /// delta: depth where the two-resistance law changes slope, m.
    pub delta_m: f64,
    /// alpha: constant velocity-squared drag coefficient (eq1), kg/m.
    pub alpha_kg_m: f64,
    /// b: added-mass drag factor, `alpha(s) = b dm_a/ds` (eq4), dimensionless.
    pub added_mass_drag_b: f64,
    /// sigma_cone: stress gradient on the jammed cone's slanted face, N/m^3.
    pub sigma_cone_n_m3: f64,
    /// rho: grain density, kg/m^3.
    pub grain_density_kg_m3: f64,
    /// theta: shear-band angle from horizontal, degrees.
    pub shear_band_angle_deg: f64,
    /// mu: jamming-front growth rate, dimensionless.
    pub jamming_front_rate: f64,
    /// C: added-mass constant, m^2.
    pub added_mass_c_m2: f64,
    /// kappa / k1: re-intrusion overshoot stiffness as a multiple of k1, dimensionless.
    pub reintrusion_kappa_per_k1: f64,
    /// l_re: decay length of the re-intrusion overshoot, m.
    pub reintrusion_length_m: f64,
    /// Foot radius the stiffnesses k1, k2 and kappa were given for, m. Stiffnesses scale with
    /// foot area: the model uses `k1 (R / R_ref)^2` (docs/model.md: "Stiffnesses scale with foot area").
    pub reference_foot_radius_m: f64,
}

/// Penetration force law `F_p(z)` (override of the named model's choice).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PenetrationChoice {
    /// Use the named model's law.
    Model,
    /// `F_p = k1 z`.
    Linear,
    /// `k1 z` up to delta, `k2` beyond.
    TwoResistance,
    /// RFT on the jammed cone (paper Fig. 5).
    Cone,
}

/// Re-intrusion overshoot on/off (override of the named model's choice).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReintrusionChoice {
    /// Use the named model's choice.
    Model,
    /// Overshoot once the foot has been airborne.
    On,
    /// Never an overshoot.
    Off,
}

/// Velocity-dependent part of the ground force (override of the named model's choice).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DragChoice {
    /// Use the named model's choice.
    Model,
    /// `alpha v^2` with constant alpha.
    ConstantAlpha,
    /// eq4: added mass `m_a(s)`, `alpha(s) = b dm_a/ds`, solved implicitly.
    AddedMass,
}

/// Where the re-intrusion overshoot of an episode is anchored. docs/model.md anchors it at "that
/// episode's own z_start", where an episode starts at each touchdown and each time a static
/// foot starts moving down again.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReintrusionAnchor {
    /// Literal docs/model.md: every episode (touchdown or restart of a static foot) re-anchors the
    /// overshoot at its own z_start. A static foot therefore restarts only once its load
    /// exceeds `F_p(z) + kappa z` (the capacity of the episode it would start).
    Episode,
    /// Only a touchdown re-anchors the overshoot; a static foot that starts moving again keeps
    /// the anchor of the touchdown (its holding capacity is continuous). The added-mass episode
    /// depth s still restarts at every episode.
    Touchdown,
}

/// Which preset alpha eq1 and eq1-linear use (docs/model.md section 3, "alpha for eq1").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Eq1AlphaChoice {
    /// The paper's procedure: alpha fitted per packing fraction to eq4's single-jump heights
    /// over 4-20 Hz ([`EQ1_ALPHA_FITTED_KG_M`]; `sandjumper figures` refits it and a test
    /// checks the table against that fit).
    Fitted,
    /// docs/model.md's alpha column, the fit's starting values.
    Starting,
}

/// eq1's alpha fitted to eq4's single jumps at the preset rows 0.57..=0.62, kg/m
/// (`sandjumper figures`, full grid: `eq1_alpha_fit.csv`).
pub const EQ1_ALPHA_FITTED_KG_M: [f64; 6] = [90.6, 109.4, 141.5, 171.7, 281.6, 468.6];

/// Overrides of the named model's ingredients (docs/model.md: "plus overrides").
/// Ignored by the `hard` model (no sand).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelOverrides {
    /// `F_p` law: model | linear | two-resistance | cone.
    pub penetration: PenetrationChoice,
    /// Re-intrusion overshoot: model | on | off.
    pub reintrusion: ReintrusionChoice,
    /// Drag: model | constant-alpha | added-mass.
    pub drag: DragChoice,
    /// Overshoot anchor: episode (docs/model.md, literal) | touchdown.
    pub reintrusion_anchor: ReintrusionAnchor,
    /// The preset alpha of eq1 and eq1-linear: fitted (to eq4's single jumps, the paper's
    /// procedure) | starting (docs/model.md's column). Setting it in a params file replaces the
    /// preset's `sand.alpha_kg_m` unless the file sets that too.
    pub eq1_alpha: Eq1AlphaChoice,
}

impl Default for ModelOverrides {
    fn default() -> Self {
        Self {
            penetration: PenetrationChoice::Model,
            reintrusion: ReintrusionChoice::Model,
            drag: DragChoice::Model,
            reintrusion_anchor: ReintrusionAnchor::Episode,
            eq1_alpha: Eq1AlphaChoice::Fitted,
        }
    }
}

/// All parameters of a simulation: robot, drive, sand, model overrides.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The robot (docs/model.md section 1).
    pub robot: RobotParams,
    /// The motor drive (force-driven runs).
    pub drive: DriveParams,
    /// The sand (docs/model.md section 3).
    pub sand: SandParams,
    /// Overrides of the named models' ingredients.
    pub model: ModelOverrides,
}

/// An error in parameters: what was wrong, where (source, key, line), what is allowed.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamsError {
    /// Where the parameters came from (a file name, or "preset").
    pub source: String,
    /// Dotted key, e.g. `robot.foot_mass_kg`, when the error concerns one key.
    pub key: Option<String>,
    /// 1-based line in the source text, when known.
    pub line: Option<usize>,
    /// What was wrong.
    pub message: String,
    /// What is allowed.
    pub allowed: String,
}

impl fmt::Display for ParamsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.source.is_empty() {
            write!(f, "{}", self.source)?;
            if let Some(line) = self.line {
                write!(f, ":{line}")?;
            }
            write!(f, ": ")?;
        } else if let Some(line) = self.line {
            write!(f, "line {line}: ")?;
        }
        if let Some(key) = &self.key {
            write!(f, "key `{key}`: ")?;
        }
        write!(f, "{}", self.message)?;
        if !self.allowed.is_empty() {
            write!(f, " (allowed: {})", self.allowed)?;
        }
        Ok(())
    }
}

impl std::error::Error for ParamsError {}

/// One row of docs/model.md's per-packing table (7.6 cm foot).
struct PresetRow {
    phi: f64,
    k1_kn_m: f64,
    k2_kn_m: f64,
    delta_cm: f64,
    /// docs/model.md's alpha column: the starting values of the fit.
    alpha_kg_m: f64,
    b: f64,
    sigma_cone_mn_m3: f64,
}

const fn row(
    phi: f64,
    k1_kn_m: f64,
    k2_kn_m: f64,
    delta_cm: f64,
    alpha_kg_m: f64,
    b: f64,
    sigma_cone_mn_m3: f64,
) -> PresetRow {
    PresetRow {
        phi,
        k1_kn_m,
        k2_kn_m,
        delta_cm,
        alpha_kg_m,
        b,
        sigma_cone_mn_m3,
    }
}

/// The preset rows `i` and `i + 1` around `phi` (within the presets) and the weight of row
/// `i + 1` in the linear interpolation.
fn preset_interval(phi: f64) -> (usize, f64) {
    let i = PRESETS
        .windows(2)
        .position(|w| phi <= w[1].phi)
        .unwrap_or(PRESETS.len() - 2);
    (
        i,
        (phi - PRESETS[i].phi) / (PRESETS[i + 1].phi - PRESETS[i].phi),
    )
}

/// docs/model.md section 3, per-packing presets.
const PRESETS: [PresetRow; 6] = [
    row(0.57, 1.6, 1.1, 1.5, 50.0, 17.0, 0.12),
    row(0.58, 2.0, 1.3, 1.5, 60.0, 20.0, 0.15),
    row(0.59, 2.5, 1.6, 1.4, 75.0, 25.0, 0.18),
    row(0.60, 3.2, 1.9, 1.3, 90.0, 30.0, 0.21),
    row(0.61, 6.0, 2.2, 1.1, 150.0, 50.0, 0.24),
    row(0.62, 10.0, 2.5, 1.0, 250.0, 80.0, 0.27),
];

/// Smallest packing fraction with a preset.
pub const PRESET_PHI_MIN: f64 = 0.57;
/// Largest packing fraction with a preset.
pub const PRESET_PHI_MAX: f64 = 0.62;

impl Default for Params {
    /// The preset at phi = 0.57 (the CLI's default).
    fn default() -> Self {
        Self::preset(PRESET_PHI_MIN).expect("0.57 is a preset row")
    }
}

impl Params {
    /// Parameters for packing fraction `phi` (docs/model.md tables; sand values linearly
    /// interpolated between rows). Errors if `phi` is outside 0.57..=0.62 or not finite.
    pub fn preset(phi: f64) -> Result<Params, ParamsError> {
        // Tolerate rounding of range endpoints such as 0.57 + 5 * 0.01.
        const SLACK: f64 = 1e-9;
        if !phi.is_finite() || !(PRESET_PHI_MIN - SLACK..=PRESET_PHI_MAX + SLACK).contains(&phi) {
            return Err(ParamsError {
                source: "preset".into(),
                key: Some("sand.packing_fraction".into()),
                line: None,
                message: format!("no preset for packing fraction phi = {phi}"),
                allowed: format!(
                    "{PRESET_PHI_MIN} <= phi <= {PRESET_PHI_MAX}, or a params file giving the sand values"
                ),
            });
        }
        let phi = phi.clamp(PRESET_PHI_MIN, PRESET_PHI_MAX);
        let (i, w) = preset_interval(phi);
        let (a, b) = (&PRESETS[i], &PRESETS[i + 1]);
        let lerp = |x: f64, y: f64| x + (y - x) * w;
        let alpha_fitted = lerp(EQ1_ALPHA_FITTED_KG_M[i], EQ1_ALPHA_FITTED_KG_M[i + 1]);
        Ok(Params {
            robot: RobotParams::MODEL,
            drive: DriveParams {
                force_constant_n_a: 10.0,
                peak_force_n: 300.0,
                current_lag_s: 2e-4,
            },
            sand: SandParams {
                packing_fraction: phi,
                critical_packing_fraction: 0.60,
                k1_n_m: 1e3 * lerp(a.k1_kn_m, b.k1_kn_m),
                k2_n_m: 1e3 * lerp(a.k2_kn_m, b.k2_kn_m),
                delta_m: 1e-2 * lerp(a.delta_cm, b.delta_cm),
                alpha_kg_m: alpha_fitted,
                added_mass_drag_b: lerp(a.b, b.b),
                sigma_cone_n_m3: 1e6 * lerp(a.sigma_cone_mn_m3, b.sigma_cone_mn_m3),
                grain_density_kg_m3: 1000.0,
                shear_band_angle_deg: 60.0,
                jamming_front_rate: 2.0,
                added_mass_c_m2: 8e-4,
                reintrusion_kappa_per_k1: 1.0,
                reintrusion_length_m: 0.005,
                reference_foot_radius_m: 0.038,
            },
            model: ModelOverrides::default(),
        })
    }

    /// The preset alpha of eq1 at `phi` for `choice`, kg/m (interpolated like the other sand
    /// values), or `None` outside the presets.
    pub fn preset_eq1_alpha(phi: f64, choice: Eq1AlphaChoice) -> Option<f64> {
        let mut p = Params::preset(phi).ok()?;
        if choice == Eq1AlphaChoice::Starting {
            let (i, w) = preset_interval(p.sand.packing_fraction);
            let (a, b) = (&PRESETS[i], &PRESETS[i + 1]);
            p.sand.alpha_kg_m = a.alpha_kg_m + (b.alpha_kg_m - a.alpha_kg_m) * w;
        }
        Some(p.sand.alpha_kg_m)
    }

    /// Override any field from a user's TOML text (tables `[robot]`, `[drive]`, `[sand]`,
    /// `[model]`, keys as written by [`Params::to_toml`]). Unknown keys, wrong types, bad
    /// values and TOML syntax errors are reported with `source`, the key and its line. The
    /// result is validated.
    pub fn with_overrides_toml(self, toml_text: &str, source: &str) -> Result<Params, ParamsError> {
        let lines = LineIndex::new(toml_text);
        let err = |key: Option<String>,
                   span: Option<core::ops::Range<usize>>,
                   message: String,
                   allowed: String| {
            ParamsError {
                source: source.to_string(),
                key,
                line: span.map(|s| lines.line_of(s.start)),
                message,
                allowed,
            }
        };
        let syntax = |e: toml::de::Error| {
            err(
                None,
                e.span(),
                format!("not valid TOML: {}", e.message().trim()),
                "TOML syntax".into(),
            )
        };
        let user: toml::Table = toml::from_str(toml_text).map_err(syntax)?;
        let spans = toml::de::DeTable::parse(toml_text).map_err(syntax)?;
        let key_span = |path: &[&str]| key_span(spans.get_ref(), path);
        let mut merged = toml::Table::try_from(&self).map_err(|e| {
            err(
                None,
                None,
                format!("cannot serialise parameters: {e}"),
                String::new(),
            )
        })?;
        let mut leaves: Vec<Vec<String>> = Vec::new();
        merge(&mut merged, &user, &mut Vec::new(), &mut leaves).map_err(|m| {
            let path: Vec<&str> = m.path.iter().map(String::as_str).collect();
            err(
                Some(m.path.join(".")),
                key_span(&path),
                m.message,
                m.allowed,
            )
        })?;
        let params: Params = merged.clone().try_into().map_err(|e: toml::de::Error| {
            // Attribute the failure to the first user key that alone makes it fail.
            let culprit = leaves.iter().find(|path| {
                let mut probe = toml::Table::try_from(&self).expect("serialisable");
                let mut one = toml::Table::new();
                set_path(
                    &mut one,
                    path,
                    get_path(&merged, path).expect("merged leaf").clone(),
                );
                merge(&mut probe, &one, &mut Vec::new(), &mut Vec::new()).is_ok()
                    && probe.try_into::<Params>().is_err()
            });
            match culprit {
                Some(path) => {
                    let p: Vec<&str> = path.iter().map(String::as_str).collect();
                    err(
                        Some(path.join(".")),
                        key_span(&p),
                        format!("invalid value: {}", e.message().trim()),
                        String::new(),
                    )
                }
                None => err(
                    None,
                    None,
                    format!("invalid parameters: {}", e.message().trim()),
                    String::new(),
                ),
            }
        })?;
        let mut params = params;
        // `[model] eq1_alpha` picks the preset alpha at this packing fraction, unless the file
        // gives `sand.alpha_kg_m` itself.
        let sets = |table: &str, key: &str| {
            user.get(table)
                .and_then(|t| t.as_table())
                .is_some_and(|t| t.contains_key(key))
        };
        if sets("model", "eq1_alpha") && !sets("sand", "alpha_kg_m") {
            let phi = params.sand.packing_fraction;
            params.sand.alpha_kg_m = Params::preset_eq1_alpha(phi, params.model.eq1_alpha)
                .ok_or_else(|| {
                    err(
                        Some("model.eq1_alpha".into()),
                        key_span(&["model", "eq1_alpha"]),
                        format!("no preset alpha at packing fraction {phi}"),
                        format!(
                            "phi within the presets ({PRESET_PHI_MIN}..={PRESET_PHI_MAX}), or \
                             sand.alpha_kg_m in the same file"
                        ),
                    )
                })?;
        }
        params.validate().map_err(|mut e| {
            e.source = source.to_string();
            if let Some(key) = &e.key {
                let path: Vec<&str> = key.split('.').collect();
                e.line = key_span(&path).map(|s| lines.line_of(s.start));
            }
            e
        })?;
        Ok(params)
    }

    /// Check every value against its physical range: masses, stiffnesses, lengths positive;
    /// damping and drag non-negative; packing fraction in (0, 1); angles in (0, 90) degrees.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let r = &self.robot;
        let d = &self.drive;
        let s = &self.sand;
        let positive: [(&str, f64); 17] = [
            ("robot.motor_mass_kg", r.motor_mass_kg),
            ("robot.rod_mass_kg", r.rod_mass_kg),
            ("robot.foot_mass_kg", r.foot_mass_kg),
            ("robot.spring_stiffness_n_m", r.spring_stiffness_n_m),
            ("robot.spring_rest_length_m", r.spring_rest_length_m),
            ("robot.foot_radius_m", r.foot_radius_m),
            ("robot.stroke_amplitude_m", r.stroke_amplitude_m),
            ("robot.stroke_limit_m", r.stroke_limit_m),
            ("robot.gravity_m_s2", r.gravity_m_s2),
            ("drive.force_constant_n_a", d.force_constant_n_a),
            ("drive.peak_force_n", d.peak_force_n),
            ("sand.k1_n_m", s.k1_n_m),
            ("sand.k2_n_m", s.k2_n_m),
            ("sand.delta_m", s.delta_m),
            ("sand.grain_density_kg_m3", s.grain_density_kg_m3),
            ("sand.reintrusion_length_m", s.reintrusion_length_m),
            ("sand.reference_foot_radius_m", s.reference_foot_radius_m),
        ];
        let non_negative: [(&str, f64); 8] = [
            ("robot.spring_damping_n_s_m", r.spring_damping_n_s_m),
            ("drive.current_lag_s", d.current_lag_s),
            ("sand.alpha_kg_m", s.alpha_kg_m),
            ("sand.added_mass_drag_b", s.added_mass_drag_b),
            ("sand.sigma_cone_n_m3", s.sigma_cone_n_m3),
            ("sand.jamming_front_rate", s.jamming_front_rate),
            ("sand.added_mass_c_m2", s.added_mass_c_m2),
            ("sand.reintrusion_kappa_per_k1", s.reintrusion_kappa_per_k1),
        ];
        let bad = |key: &str, value: f64, allowed: &str| ParamsError {
            source: String::new(),
            key: Some(key.to_string()),
            line: None,
            message: format!("value {value} is out of range"),
            allowed: allowed.to_string(),
        };
        for (key, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(key, v, "a finite number > 0"));
            }
        }
        for (key, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(key, v, "a finite number >= 0"));
            }
        }
        for (key, v) in [
            ("sand.packing_fraction", s.packing_fraction),
            (
                "sand.critical_packing_fraction",
                s.critical_packing_fraction,
            ),
        ] {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(bad(key, v, "0 < phi < 1"));
            }
        }
        if !(s.shear_band_angle_deg > 0.0 && s.shear_band_angle_deg < 90.0) {
            return Err(bad(
                "sand.shear_band_angle_deg",
                s.shear_band_angle_deg,
                "0 < theta < 90 degrees",
            ));
        }
        if r.stroke_amplitude_m > r.stroke_limit_m {
            return Err(bad(
                "robot.stroke_amplitude_m",
                r.stroke_amplitude_m,
                &format!(
                    "at most the stroke limit robot.stroke_limit_m = {}",
                    r.stroke_limit_m
                ),
            ));
        }
        Ok(())
    }

    /// The resolved parameters as TOML; `Params::preset(x)?.with_overrides_toml(&p.to_toml(), ..)`
    /// gives back `p`.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("parameters are plain numbers and names")
    }

    /// Total mass of motor and rod, `M = m_m + m_r`, kg.
    pub fn motor_rod_mass_kg(&self) -> f64 {
        self.robot.motor_mass_kg + self.robot.rod_mass_kg
    }
}

/// A failed merge: the key path, what was wrong and what is allowed.
struct MergeError {
    path: Vec<String>,
    message: String,
    allowed: String,
}

/// Overwrite `base` with `user`, key by key, checking every key exists and keeps its type.
/// Integers are accepted where a float is expected. `leaves` collects the paths set.
fn merge(
    base: &mut toml::Table,
    user: &toml::Table,
    path: &mut Vec<String>,
    leaves: &mut Vec<Vec<String>>,
) -> Result<(), MergeError> {
    for (key, value) in user {
        path.push(key.clone());
        let here = || path.clone();
        let Some(slot) = base.get_mut(key) else {
            let known: Vec<&str> = base.keys().map(String::as_str).collect();
            return Err(MergeError {
                path: here(),
                message: "unknown key".into(),
                allowed: format!("one of {}", known.join(", ")),
            });
        };
        match (slot, value) {
            (toml::Value::Table(b), toml::Value::Table(u)) => merge(b, u, path, leaves)?,
            (toml::Value::Table(_), _) => {
                return Err(MergeError {
                    path: here(),
                    message: format!("expected a table, found a {}", value.type_str()),
                    allowed: format!("[{}] with its keys", path.join(".")),
                });
            }
            (slot @ toml::Value::Float(_), toml::Value::Integer(i)) => {
                *slot = toml::Value::Float(*i as f64);
                leaves.push(here());
            }
            (slot, value) if slot.same_type(value) => {
                *slot = value.clone();
                leaves.push(here());
            }
            (slot, value) => {
                return Err(MergeError {
                    path: here(),
                    message: format!(
                        "expected a {}, found a {}",
                        slot.type_str(),
                        value.type_str()
                    ),
                    allowed: match slot {
                        toml::Value::Float(_) => "a number".into(),
                        toml::Value::String(_) => "a quoted name".into(),
                        other => format!("a {}", other.type_str()),
                    },
                });
            }
        }
        path.pop();
    }
    Ok(())
}

fn get_path<'a>(table: &'a toml::Table, path: &[String]) -> Option<&'a toml::Value> {
    let (last, parents) = path.split_last()?;
    let mut t = table;
    for p in parents {
        t = t.get(p)?.as_table()?;
    }
    t.get(last)
}

fn set_path(table: &mut toml::Table, path: &[String], value: toml::Value) {
    let (last, parents) = path.split_last().expect("non-empty path");
    let mut t = table;
    for p in parents {
        t = t
            .entry(p.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .expect("table on the path");
    }
    t.insert(last.clone(), value);
}

/// Byte span of the key `path` in the spanned parse of the user's text.
fn key_span(table: &toml::de::DeTable<'_>, path: &[&str]) -> Option<core::ops::Range<usize>> {
    let (first, rest) = path.split_first()?;
    let (key, value) = table.iter().find(|(k, _)| k.get_ref().as_ref() == *first)?;
    if rest.is_empty() {
        return Some(key.span());
    }
    match value.get_ref() {
        toml::de::DeValue::Table(t) => key_span(t, rest).or_else(|| Some(key.span())),
        _ => Some(key.span()),
    }
}

/// Byte offset to 1-based line number.
struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Self { starts }
    }

    fn line_of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset)
    }
}
