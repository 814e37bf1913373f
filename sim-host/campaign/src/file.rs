//! The campaign file (TOML): the grid, repeats, order, bed preparation, the simulated bed,
//! camera and analysis. Unknown keys, empty lists and values outside what is allowed are
//! refused with the file, the line and what is allowed.

use std::path::Path;

use serde::{Deserialize, Serialize};
use toml::Spanned;

/// A whole campaign file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignFile {
    /// Name (goes into the records).
    pub name: String,
    /// Seed of the order shuffle and of the simulated bed.
    #[serde(default)]
    pub seed: u64,
    /// Jumps per grid point.
    #[serde(default = "one")]
    pub repeats: Spanned<u32>,
    /// `as-written` or `shuffled` (with `seed`).
    #[serde(default)]
    pub order: Order,
    /// Ground model of the replay prediction (and of the simulated rig's sand).
    #[serde(default = "eq4")]
    pub model: String,
    /// The parameter space.
    pub grid: Grid,
    /// Bed preparation.
    pub bed: BedSettings,
    /// The simulated bed (used by `--link sil|pil`).
    #[serde(default)]
    pub simulated_bed: SimulatedBedSettings,
    /// Camera.
    #[serde(default)]
    pub camera: CameraSettings,
    /// What to analyse per jump.
    #[serde(default)]
    pub analysis: AnalysisSettings,
    /// What to do when a point's bed cannot be prepared.
    #[serde(default)]
    pub on_failed_preparation: FailurePolicy,
}

fn one() -> Spanned<u32> {
    Spanned::new(0..0, 1)
}

fn no_delays() -> Spanned<Vec<f64>> {
    Spanned::new(0..0, Vec::new())
}

fn eq4() -> String {
    "eq4".into()
}

/// Order of the points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// Kinds, then frequencies, then delays, then phis, then repeats, as written.
    #[default]
    AsWritten,
    /// Shuffled with the campaign's seed (guards against drift).
    Shuffled,
}

/// On a failed preparation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FailurePolicy {
    /// Record the failure and go on with the next point.
    #[default]
    Skip,
    /// Record it and stop the campaign (exit status 1; `resume` retries the point).
    Stop,
}

/// The parameter space.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// `single`, `stutter`, `delayed`.
    pub kinds: Spanned<Vec<String>>,
    /// Forcing frequencies, Hz.
    pub frequencies_hz: Spanned<Vec<f64>>,
    /// Delays of the delayed stutter, s (other kinds ignore them).
    #[serde(default = "no_delays")]
    pub delays_s: Spanned<Vec<f64>>,
    /// Target packing fractions.
    pub phis: Spanned<Vec<f64>>,
    /// Gain lowering during the delay (a factor on the position gain; none if absent).
    #[serde(default)]
    pub gain_lowering: Option<f32>,
}

/// Bed preparation (closed loop on the measured bed height).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BedSettings {
    /// Grain mass in the bed, kg.
    pub grain_mass_kg: f64,
    /// Grain material density, kg/m^3.
    pub grain_density_kg_m3: f64,
    /// Bed area, m^2.
    pub area_m2: f64,
    /// Accepted |phi - target|.
    pub tolerance: Spanned<f64>,
    /// Measure-compact rounds (and re-fluidizations) before the point fails.
    pub max_attempts: Spanned<u32>,
    /// Blower on, s.
    pub fluidize_s: f64,
    /// Blower voltage while fluidizing, V (0-10).
    pub blower_v: f64,
    /// Wait after fluidizing or compacting, s.
    pub settle_s: f64,
    /// Shaker seconds per compaction dose (at `shaker_duty`).
    pub dose_s: f64,
    /// Shaker duty, 0-1.
    pub shaker_duty: f64,
    /// Height readings averaged across the bed per measurement.
    pub height_readings: u32,
    /// The board's bed-height sensor (needed with `--port`).
    #[serde(default)]
    pub height_sensor: Option<HeightSensor>,
    /// Longest wait for the lift to reach a limit switch, s.
    #[serde(default = "lift_timeout")]
    pub lift_timeout_s: f64,
}

fn lift_timeout() -> f64 {
    60.0
}

/// The bed-height sensor's calibration: `height = height_at_zero_code_m + metres_per_code *
/// code` (a distance sensor looking down has a negative slope).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeightSensor {
    /// m per ADC code.
    pub metres_per_code: f64,
    /// Bed height at code 0, m.
    pub height_at_zero_code_m: f64,
}

/// The simulated bed's behaviour.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulatedBedSettings {
    /// Mean phi after fluidizing.
    pub fluidized_phi: f64,
    /// Scatter (standard deviation) of phi after fluidizing.
    pub fluidized_scatter: f64,
    /// Phi gained per e-fold of accumulated dose: `phi = phi0 + gain ln(1 + D / dose_scale_s)`.
    pub compaction_gain: f64,
    /// Dose scale, shaker-seconds at full duty.
    pub dose_scale_s: f64,
    /// Densest reachable phi.
    pub max_phi: f64,
    /// Noise of one height reading, m (standard deviation).
    pub height_noise_m: f64,
}

impl Default for SimulatedBedSettings {
    fn default() -> Self {
        Self {
            fluidized_phi: 0.57,
            fluidized_scatter: 0.002,
            compaction_gain: 0.02,
            dose_scale_s: 2.0,
            max_phi: 0.625,
            height_noise_m: 0.5e-3,
        }
    }
}

/// Camera.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSettings {
    /// Frame rate, frames/s (the paper's rod camera: 200).
    pub fps: u32,
    /// On a board: the folder the lab's camera software writes a jump's frames into (named
    /// by camera frame number, `frame_NNNNNN.png` as `track` reads them); the campaign moves
    /// them into the point's folder after each jump.
    pub capture_dir: Option<std::path::PathBuf>,
    /// On a board: the camera's scale, m/px.
    pub m_per_px: f64,
    /// On a board: the exposure, s.
    pub exposure_s: f64,
    /// On a board: how long to wait for the frames after a jump, s.
    pub capture_timeout_s: f64,
}

impl Default for CameraSettings {
    fn default() -> Self {
        Self {
            fps: 200,
            capture_dir: None,
            m_per_px: 1.2e-4,
            exposure_s: 1e-3,
            capture_timeout_s: 10.0,
        }
    }
}

/// What to analyse.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnalysisSettings {
    /// Track the rod in the frames for the measured jump height.
    pub track: bool,
    /// Replay the encoder log in the simulator for the predicted jump height.
    pub replay: bool,
}

impl Default for AnalysisSettings {
    fn default() -> Self {
        Self {
            track: true,
            replay: true,
        }
    }
}

/// Line (1-based) of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

impl CampaignFile {
    /// What a campaign on a board (`--port`) needs beyond a simulated one.
    pub fn check_for_board(&self, name: &str) -> Result<(), String> {
        if self.bed.height_sensor.is_none() {
            return Err(format!(
                "{name}: a campaign on a board needs [bed.height_sensor] (metres_per_code, height_at_zero_code_m) to turn the sensor's code into a bed height"
            ));
        }
        if self.analysis.track && self.camera.capture_dir.is_none() {
            return Err(format!(
                "{name}: analysis.track with --port needs camera.capture_dir, the folder the lab's camera software writes each jump's frames into (allowed: set it, or track = false)"
            ));
        }
        let c = &self.camera;
        let ok = c.m_per_px.is_finite()
            && c.m_per_px > 0.0
            && c.exposure_s.is_finite()
            && c.exposure_s >= 0.0
            && c.capture_timeout_s.is_finite()
            && c.capture_timeout_s > 0.0;
        if !ok {
            return Err(format!(
                "{name}: camera: m_per_px {}, exposure_s {}, capture_timeout_s {} (allowed: positive; exposure may be 0)",
                c.m_per_px, c.exposure_s, c.capture_timeout_s
            ));
        }
        Ok(())
    }

    /// Read and check `path`.
    pub fn read(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read the campaign file {}: {e}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parse and check `text` (from `name`).
    pub fn parse(text: &str, name: &str) -> Result<Self, String> {
        let f: Self = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start));
            format!(
                "{name}{}: {}",
                line.map(|l| format!(":{l}")).unwrap_or_default(),
                e.message()
            )
        })?;
        f.check(text, name)?;
        Ok(f)
    }

    fn check(&self, text: &str, name: &str) -> Result<(), String> {
        let at = |span: std::ops::Range<usize>, msg: String| {
            if span.is_empty() && span.start == 0 {
                format!("{name}: {msg}")
            } else {
                format!("{name}:{}: {msg}", line_of(text, span.start))
            }
        };
        let g = &self.grid;
        for (list_name, span, empty) in [
            ("grid.kinds", g.kinds.span(), g.kinds.get_ref().is_empty()),
            (
                "grid.frequencies_hz",
                g.frequencies_hz.span(),
                g.frequencies_hz.get_ref().is_empty(),
            ),
            ("grid.phis", g.phis.span(), g.phis.get_ref().is_empty()),
        ] {
            if empty {
                return Err(at(
                    span,
                    format!("{list_name} is empty (allowed: at least one value)"),
                ));
            }
        }
        for k in g.kinds.get_ref() {
            if sandjumper_model::trajectory::parse_kind(k).is_none() {
                return Err(at(
                    g.kinds.span(),
                    format!("grid.kinds: unknown kind `{k}` (allowed: single, stutter, delayed)"),
                ));
            }
        }
        if g.kinds.get_ref().iter().any(|k| k == "delayed") && g.delays_s.get_ref().is_empty() {
            return Err(at(
                g.kinds.span(),
                "grid.kinds has `delayed` but grid.delays_s is empty (allowed: at least one delay in s)".into(),
            ));
        }
        for &f in g.frequencies_hz.get_ref() {
            if !(f.is_finite() && f > 0.0 && f <= 50.0) {
                return Err(at(
                    g.frequencies_hz.span(),
                    format!("grid.frequencies_hz: {f} Hz (allowed: above 0, up to 50 Hz)"),
                ));
            }
        }
        for &d in g.delays_s.get_ref() {
            if !(d.is_finite() && (0.0..=5.0).contains(&d)) {
                return Err(at(
                    g.delays_s.span(),
                    format!("grid.delays_s: {d} s (allowed: 0 to 5 s)"),
                ));
            }
        }
        let sb = &self.simulated_bed;
        let (lo, hi) = (
            sandjumper_model::params::PRESET_PHI_MIN,
            sandjumper_model::params::PRESET_PHI_MAX.min(sb.max_phi),
        );
        for &p in g.phis.get_ref() {
            if !(p.is_finite() && p >= lo && p <= hi) {
                return Err(at(
                    g.phis.span(),
                    format!(
                        "grid.phis: {p} is outside what the bed can reach and the presets cover (allowed: {lo} to {hi})"
                    ),
                ));
            }
        }
        if let Some(gl) = g.gain_lowering
            && !(gl.is_finite() && gl > 0.0 && gl <= 1.0)
        {
            return Err(format!(
                "{name}: grid.gain_lowering {gl} (allowed: above 0, up to 1)"
            ));
        }
        if *self.repeats.get_ref() == 0 {
            return Err(at(
                self.repeats.span(),
                "repeats is 0 (allowed: 1 or more)".into(),
            ));
        }
        let b = &self.bed;
        let tol = *b.tolerance.get_ref();
        if !(tol.is_finite() && tol > 0.0) {
            return Err(at(
                b.tolerance.span(),
                format!("bed.tolerance {tol} (allowed: a positive phi difference)"),
            ));
        }
        if *b.max_attempts.get_ref() == 0 {
            return Err(at(
                b.max_attempts.span(),
                "bed.max_attempts is 0 (allowed: 1 or more)".into(),
            ));
        }
        for (key, v, ok) in [
            ("bed.grain_mass_kg", b.grain_mass_kg, b.grain_mass_kg > 0.0),
            (
                "bed.grain_density_kg_m3",
                b.grain_density_kg_m3,
                b.grain_density_kg_m3 > 0.0,
            ),
            ("bed.area_m2", b.area_m2, b.area_m2 > 0.0),
            ("bed.fluidize_s", b.fluidize_s, b.fluidize_s > 0.0),
            ("bed.settle_s", b.settle_s, b.settle_s >= 0.0),
            ("bed.dose_s", b.dose_s, b.dose_s > 0.0),
            (
                "bed.blower_v",
                b.blower_v,
                (0.0..=10.0).contains(&b.blower_v),
            ),
            (
                "bed.shaker_duty",
                b.shaker_duty,
                b.shaker_duty > 0.0 && b.shaker_duty <= 1.0,
            ),
        ] {
            if !(v.is_finite() && ok) {
                return Err(format!(
                    "{name}: {key} = {v} (allowed: positive; blower_v 0-10 V, shaker_duty above 0 up to 1)"
                ));
            }
        }
        if !(b.lift_timeout_s.is_finite() && b.lift_timeout_s > 0.0) {
            return Err(format!(
                "{name}: bed.lift_timeout_s = {} (allowed: positive)",
                b.lift_timeout_s
            ));
        }
        if let Some(h) = b.height_sensor
            && !(h.metres_per_code.is_finite()
                && h.metres_per_code != 0.0
                && h.height_at_zero_code_m.is_finite())
        {
            return Err(format!(
                "{name}: bed.height_sensor: metres_per_code {} and height_at_zero_code_m {} (allowed: a non-zero slope and a finite offset)",
                h.metres_per_code, h.height_at_zero_code_m
            ));
        }
        if b.height_readings == 0 {
            return Err(format!(
                "{name}: bed.height_readings is 0 (allowed: 1 or more)"
            ));
        }
        if !(sb.fluidized_phi > 0.3 && sb.fluidized_phi < sb.max_phi && sb.max_phi < 0.9) {
            return Err(format!(
                "{name}: simulated_bed: fluidized_phi {} and max_phi {} (allowed: 0.3 < fluidized_phi < max_phi < 0.9)",
                sb.fluidized_phi, sb.max_phi
            ));
        }
        if self.model.parse::<sandjumper_model::ModelName>().is_err() {
            return Err(format!(
                "{name}: model `{}` (allowed: hard, eq1-linear, eq1, eq4)",
                self.model
            ));
        }
        if self.camera.fps == 0 && self.analysis.track {
            return Err(format!(
                "{name}: camera.fps is 0 but analysis.track is on (allowed: a frame rate, or track = false)"
            ));
        }
        Ok(())
    }
}
