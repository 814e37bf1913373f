//! What one LAMMPS run of the intrusion is: the grains, the bed, the contacts, the foot, the
//! camera's rate; and what follows from them (the time step, the step counts).
//!
//! The contacts are Hertz-Mindlin (`pair_style granular`: `hertz/material` with a
//! restitution-based damping, `tangential mindlin` with Coulomb friction). Their stiffness is
//! softened from a seed's (~1 GPa) to what keeps the overlaps small at the run's stresses:
//! the time step scales with `d sqrt(rho / E)`, so a softer grain is a cheaper run (see
//! [`LammpsSpec::rayleigh_time_s`] and `docs/dem.md`).

use serde::{Deserialize, Serialize};

fn every_frame() -> u64 {
    1
}

fn is_every_frame(n: &u64) -> bool {
    *n == 1
}

/// How LAMMPS writes the dumped frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum DumpFormat {
    /// Text (`dump custom`, `frame.STEP.txt`): the format of runs before compressed dumps.
    #[default]
    Text,
    /// Gzip-compressed text (`dump custom/gz`, `frame.STEP.txt.gz`, LAMMPS's COMPRESS
    /// package): about 40 % of the bytes, read back as a stream.
    Gzip,
}

impl DumpFormat {
    /// The word the command line takes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Text => "text",
            Self::Gzip => "gzip",
        }
    }
}

fn is_text(f: &DumpFormat) -> bool {
    *f == DumpFormat::Text
}

/// A preset scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's 76 mm foot in ~1 mm grains, a 0.30 m x 0.15 m bed (~15 million grains,
    /// Young's modulus 100 MPa): a cluster job.
    Paper,
    /// A 20 mm foot in ~2 mm grains, a 60 mm x 40 mm bed (~20,000 grains, 5 MPa): minutes on
    /// two cores.
    Small,
    /// The paper's regime at reduced scale: the small preset's 20 mm foot in 1.5 mm grains
    /// (6.7 per foot radius), a 50 mm x 35 mm bed poured to phi 0.57 (rolling friction),
    /// ~28,000 grains. With a jump's push-off scaled to this foot at the paper's Froude number
    /// (`--scale-from-foot 0.076`), the paper's depth over radius and Froude number.
    Regime,
}

impl Preset {
    /// The preset's name on the command line and in files (`paper`, `small`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Small => "small",
            Self::Regime => "regime",
        }
    }
}

/// One run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LammpsSpec {
    /// The preset the run started from (options may have changed some values).
    pub preset: Preset,
    /// Foot diameter, m.
    pub foot_diameter_m: f64,
    /// Mean grain diameter, m.
    pub grain_diameter_m: f64,
    /// Diameters are uniform in `d (1 - s) .. d (1 + s)`; s, 1.
    pub grain_size_spread: f64,
    /// Grain density, kg/m^3 (a poppy seed's, about 1000).
    pub grain_density_kg_m3: f64,
    /// Bed width (square, periodic in x and y), m.
    pub bed_width_m: f64,
    /// Bed depth after settling (the grains are counted for it at the target packing), m.
    pub bed_depth_m: f64,
    /// Target packing fraction of the settled bed (sets the pouring friction); also the
    /// model's phi for eq. 6 and `F_p(z)`, 1.
    pub packing_fraction: f64,
    /// Young's modulus of the grains (softened), Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio, 1.
    pub poisson_ratio: f64,
    /// Normal restitution coefficient, 1.
    pub restitution: f64,
    /// Sliding friction coefficient (grains, floor and foot), 1.
    pub friction: f64,
    /// Gravity, m/s^2.
    pub gravity_m_s2: f64,
    /// Time step as a fraction of the Rayleigh time, 1.
    pub time_step_fraction: f64,
    /// Dump rate (the PIV camera's frame rate), frames/s.
    pub fps: f64,
    /// Foot force output rate (each value the mean over its window), 1/s.
    pub force_rate_hz: f64,
    /// Grains dumped: within this many foot radii of the foot's axis, 1.
    pub dump_radius_factor: f64,
    /// The settle stops once the grains' rms speed is below this, m/s.
    pub settled_rms_speed_m_s: f64,
    /// The settle stops after this long in any case, s.
    pub max_settle_s: f64,
    /// Time the settled bed relaxes against the foot, held still, before it moves (the
    /// contacts' tangential history does not survive the data file between the stages), s.
    pub relax_s: f64,
    /// Seed of the grains' sizes and start positions.
    pub seed: u64,
    /// Frames between dumps (the grains near the axis, written by LAMMPS): 1 every frame, N
    /// every Nth, 0 none. The column's momentum is LAMMPS's own at every frame whatever
    /// this is (`column.txt`); the cone is measured over the dumped frames.
    #[serde(default = "every_frame", skip_serializing_if = "is_every_frame")]
    pub dump_every_frames: u64,
    /// How the frames are written (a run recorded before this field: text).
    #[serde(default, skip_serializing_if = "is_text")]
    pub dump_format: DumpFormat,
    /// The paper's PIV geometry: a flat frictional sidewall at `y = 0` (the bed periodic in x
    /// only, a second wall at `y = width`) and a half-disc foot against it, its axis on the
    /// wall; the camera looks through the wall. The column's momentum and the foot's force
    /// are the half foot's, doubled (the full foot's by the wall's symmetry).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sidewall: bool,
    /// A deck check, not a run: every `run` of each stage stops after this many steps (the
    /// settle, the relaxation, the intrusion), so that a large preset's inputs can be run
    /// through LAMMPS in a cut-down box in seconds. None for a run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoke_steps: Option<u64>,
}

impl LammpsSpec {
    /// The preset's run.
    pub fn preset(p: Preset) -> Self {
        let common = Self {
            preset: p,
            foot_diameter_m: 0.076,
            grain_diameter_m: 0.001,
            grain_size_spread: 0.1,
            grain_density_kg_m3: 1000.0,
            bed_width_m: 0.30,
            bed_depth_m: 0.15,
            packing_fraction: 0.60,
            youngs_modulus_pa: 1e8,
            poisson_ratio: 0.3,
            restitution: 0.5,
            friction: 0.5,
            gravity_m_s2: 9.81,
            time_step_fraction: 0.15,
            fps: 500.0,
            force_rate_hz: 2000.0,
            dump_radius_factor: 2.0,
            settled_rms_speed_m_s: 0.002,
            max_settle_s: 1.0,
            relax_s: 0.01,
            seed: 1,
            dump_every_frames: 1,
            dump_format: DumpFormat::Gzip,
            sidewall: false,
            smoke_steps: None,
        };
        match p {
            Preset::Paper => common,
            Preset::Small => Self {
                foot_diameter_m: 0.020,
                grain_diameter_m: 0.002,
                bed_width_m: 0.060,
                bed_depth_m: 0.040,
                youngs_modulus_pa: 5e6,
                ..common
            },
            Preset::Regime => Self {
                foot_diameter_m: 0.020,
                grain_diameter_m: 0.0015,
                bed_width_m: 0.050,
                bed_depth_m: 0.035,
                packing_fraction: 0.57,
                youngs_modulus_pa: 5e6,
                ..common
            },
        }
    }

    /// The foot's axis in a bed `width_m` wide: the box's centre, or with a sidewall, the
    /// middle of the wall at `y = 0`, m.
    pub fn axis_m(&self, width_m: f64) -> (f64, f64) {
        if self.sidewall {
            (0.5 * width_m, 0.0)
        } else {
            (0.5 * width_m, 0.5 * width_m)
        }
    }

    /// What the half foot's measures are multiplied by to be the full foot's: 2 with a
    /// sidewall, else 1.
    pub fn symmetry_factor(&self) -> f64 {
        if self.sidewall { 2.0 } else { 1.0 }
    }

    /// The step a stage's `run` goes to: `step`, or [`Self::smoke_steps`] when a deck check
    /// stops sooner.
    pub fn capped_step(&self, step: u64) -> u64 {
        self.smoke_steps.map_or(step, |n| step.min(n))
    }

    /// Foot radius, m.
    pub fn foot_radius_m(&self) -> f64 {
        0.5 * self.foot_diameter_m
    }

    /// Smallest grain diameter, m.
    pub fn min_grain_diameter_m(&self) -> f64 {
        self.grain_diameter_m * (1.0 - self.grain_size_spread)
    }

    /// Largest grain diameter, m.
    pub fn max_grain_diameter_m(&self) -> f64 {
        self.grain_diameter_m * (1.0 + self.grain_size_spread)
    }

    /// Shear modulus `E / (2 (1 + nu))`, Pa.
    pub fn shear_modulus_pa(&self) -> f64 {
        self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Rayleigh time of the smallest grain, `pi r sqrt(rho / G) / (0.1631 nu + 0.8766)`, s:
    /// the time a surface wave takes across it, the usual bound on a Hertz-Mindlin step.
    pub fn rayleigh_time_s(&self) -> f64 {
        let r = 0.5 * self.min_grain_diameter_m();
        core::f64::consts::PI * r * (self.grain_density_kg_m3 / self.shear_modulus_pa()).sqrt()
            / (0.1631 * self.poisson_ratio + 0.8766)
    }

    /// The time step, s: [`Self::time_step_fraction`] of the Rayleigh time, rounded down to
    /// two significant digits.
    pub fn time_step_s(&self) -> f64 {
        let raw = self.time_step_fraction * self.rayleigh_time_s();
        let scale = 10f64.powf(raw.log10().floor() - 1.0);
        (raw / scale).floor() * scale
    }

    /// Steps per foot-force window (at least 1).
    pub fn force_every(&self) -> u64 {
        ((1.0 / (self.force_rate_hz * self.time_step_s())).round() as u64).max(1)
    }

    /// Steps between dumps: a whole number of force windows.
    pub fn dump_every(&self) -> u64 {
        let fe = self.force_every();
        ((1.0 / (self.fps * self.time_step_s() * fe as f64)).round() as u64).max(1) * fe
    }

    /// The frame rate the dumps have (the step grid rounds [`Self::fps`]), frames/s.
    pub fn actual_fps(&self) -> f64 {
        1.0 / (self.dump_every() as f64 * self.time_step_s())
    }

    /// The number of grains the bed holds at its target packing.
    pub fn grain_count(&self) -> u64 {
        // Mean of d^3 for d uniform in d0 (1 +- s): d0^3 (1 + s^2).
        let s = self.grain_size_spread;
        let mean_volume =
            core::f64::consts::PI / 6.0 * self.grain_diameter_m.powi(3) * (1.0 + s * s);
        (self.packing_fraction * self.bed_width_m * self.bed_width_m * self.bed_depth_m
            / mean_volume)
            .round() as u64
    }

    /// The friction the grains pour with: a lower one packs them denser. Interpolated in a
    /// table measured with this module's pour (frictional Hertz spheres from a jittered
    /// lattice, restitution 0.5, spread 0.1; `docs/dem.md`); errors outside it.
    pub fn pour_friction(&self) -> Result<f64, String> {
        pour_friction_for(self.packing_fraction)
    }

    /// The rolling friction the grains pour with, below what sliding friction alone reaches
    /// (0.583): resisting their rolling as well packs them looser, down to the paper's 0.57
    /// ([`POUR_ROLLING_TABLE`]). None above.
    pub fn pour_rolling_friction(&self) -> Option<f64> {
        pour_rolling_for(self.packing_fraction)
    }

    /// The rolling stiffness of [`Self::pour_rolling_friction`]'s contacts (LAMMPS's `rolling
    /// sds`): `E d / 4`, which keeps `k dt^2 / m` the same (~0.06) at every grain size and
    /// stiffness, N/m.
    pub fn rolling_stiffness_n_m(&self) -> f64 {
        0.25 * self.youngs_modulus_pa * self.grain_diameter_m
    }

    /// Check every value: what is wrong, and what is allowed.
    pub fn check(&self) -> Result<(), String> {
        let pos = |v: f64, what: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{what} is {v} (allowed: a positive number)"))
            }
        };
        pos(self.foot_diameter_m, "the foot diameter")?;
        pos(self.grain_diameter_m, "the grain diameter")?;
        pos(self.grain_density_kg_m3, "the grain density")?;
        pos(self.bed_width_m, "the bed width")?;
        pos(self.bed_depth_m, "the bed depth")?;
        pos(self.youngs_modulus_pa, "Young's modulus")?;
        pos(self.gravity_m_s2, "gravity")?;
        pos(self.fps, "the dump rate")?;
        pos(self.force_rate_hz, "the force rate")?;
        pos(self.settled_rms_speed_m_s, "the settled rms speed")?;
        pos(self.max_settle_s, "the longest settle")?;
        pos(self.relax_s, "the relaxation before the intrusion")?;
        if !(0.0..0.5).contains(&self.grain_size_spread) {
            return Err(format!(
                "the grain size spread is {} (allowed: 0 to below 0.5)",
                self.grain_size_spread
            ));
        }
        if !(0.0..0.5).contains(&self.poisson_ratio) {
            return Err(format!(
                "Poisson's ratio is {} (allowed: 0 to below 0.5)",
                self.poisson_ratio
            ));
        }
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return Err(format!(
                "the restitution coefficient is {} (allowed: above 0, up to 1)",
                self.restitution
            ));
        }
        if !(0.0..=10.0).contains(&self.friction) {
            return Err(format!(
                "the friction coefficient is {} (allowed: 0 to 10)",
                self.friction
            ));
        }
        if !(0.01..=0.5).contains(&self.time_step_fraction) {
            return Err(format!(
                "the time step fraction is {} of the Rayleigh time (allowed: 0.01 to 0.5)",
                self.time_step_fraction
            ));
        }
        if !(1.0..=4.0).contains(&self.dump_radius_factor) {
            return Err(format!(
                "the dump radius is {} foot radii (allowed: 1 to 4: the column is r <= R, its \
                 neighbours up to 2R)",
                self.dump_radius_factor
            ));
        }
        if self.foot_diameter_m < 4.0 * self.grain_diameter_m {
            return Err(format!(
                "the foot ({} mm) is less than 4 grain diameters ({} mm) across (allowed: at \
                 least 4, for a column under it)",
                1e3 * self.foot_diameter_m,
                1e3 * self.grain_diameter_m
            ));
        }
        if self.bed_width_m < 2.0 * self.dump_radius_factor * self.foot_radius_m() {
            return Err(format!(
                "the bed ({} mm across) is narrower than the dumped region ({} foot radii of \
                 {} mm each side; allowed: a bed at least that wide)",
                1e3 * self.bed_width_m,
                self.dump_radius_factor,
                1e3 * self.foot_radius_m()
            ));
        }
        if self.bed_depth_m < 5.0 * self.grain_diameter_m {
            return Err(format!(
                "the bed is {} mm deep (allowed: at least 5 grain diameters, {} mm)",
                1e3 * self.bed_depth_m,
                5e3 * self.grain_diameter_m
            ));
        }
        if self.dump_every_frames > 100_000 {
            return Err(format!(
                "dumps every {} frames (allowed: 0, none, to 100000)",
                self.dump_every_frames
            ));
        }
        if self.sidewall && self.dump_every_frames != 1 {
            return Err(format!(
                "the sidewall PIV needs every frame at the camera's rate; dumps every {} frames \
                 (allowed with --sidewall: 1)",
                self.dump_every_frames
            ));
        }
        if self.fps > self.force_rate_hz {
            return Err(format!(
                "the dump rate is {} frames/s, above the force rate {} Hz (allowed: up to the \
                 force rate: dumps fall on force windows)",
                self.fps, self.force_rate_hz
            ));
        }
        let n = self.grain_count();
        if n > MAX_GRAINS {
            return Err(format!(
                "the bed holds {n} grains (allowed: up to {MAX_GRAINS}: this tool builds the \
                 pour in memory; a wider, deeper bed or smaller grains need a pour of its own)"
            ));
        }
        self.pour_friction().map(|_| ())
    }

    /// Refuse a trajectory that reaches deeper than `max_depth_m` into this bed: the foot
    /// must stay at least 5 grain diameters above the floor.
    pub fn check_depth(&self, max_depth_m: f64) -> Result<(), String> {
        let allowed = self.bed_depth_m - 5.0 * self.grain_diameter_m;
        if max_depth_m > allowed {
            return Err(format!(
                "the foot goes {:.1} mm deep into a bed {:.1} mm deep (allowed: down to {:.1} \
                 mm, 5 grain diameters above the floor; give a deeper --bed-depth)",
                1e3 * max_depth_m,
                1e3 * self.bed_depth_m,
                1e3 * allowed
            ));
        }
        Ok(())
    }
}

/// The most grains a run may have (the pour is built in memory: ~80 bytes a grain).
pub const MAX_GRAINS: u64 = 50_000_000;

/// Settled packing fraction against pouring friction, measured with this module's pour
/// (see [`LammpsSpec::pour_friction`]; `--preset small`, seed 1, LAMMPS 22 Jul 2025):
/// (phi, friction), phi decreasing. Frictional spheres settle no looser than about 0.583
/// this way (friction 2 gains 0.004 over friction 1).
pub const POUR_TABLE: [(f64, f64); 4] = [(0.625, 0.1), (0.594, 0.5), (0.587, 1.0), (0.583, 2.0)];

/// Settled packing fraction against rolling friction when pouring with sliding friction 2
/// (the loosest of [`POUR_TABLE`]; LAMMPS's `rolling sds`, stiffness
/// [`LammpsSpec::rolling_stiffness_n_m`], no rolling damping): (phi, rolling friction), phi
/// decreasing from where sliding friction alone stops. Measured with the small preset's
/// grains in a 40 x 40 x 30 mm bed, seed 1, 1 rank (2026-11-29): rolling friction 0.02 settles
/// 0.573, 0.05 0.569, 0.1 0.557 (0.3 0.531, 0.6 0.515).
pub const POUR_ROLLING_TABLE: [(f64, f64); 4] =
    [(0.583, 0.0), (0.573, 0.02), (0.569, 0.05), (0.557, 0.1)];

/// The rolling friction to pour with for a target packing fraction below
/// [`POUR_TABLE`]'s loosest (None above it, or below the rolling table's loosest).
pub fn pour_rolling_for(phi: f64) -> Option<f64> {
    interpolate(&POUR_ROLLING_TABLE, phi).filter(|mu| *mu > 0.0)
}

/// `table`'s second column at `phi` (first column decreasing), linearly; None outside it.
fn interpolate(table: &[(f64, f64)], phi: f64) -> Option<f64> {
    table.windows(2).find_map(|w| {
        let ((p0, m0), (p1, m1)) = (w[0], w[1]);
        (phi <= p0 && phi >= p1).then(|| m0 + (phi - p0) / (p1 - p0) * (m1 - m0))
    })
}

/// The pouring friction for a target packing fraction (see [`POUR_TABLE`]; below its
/// loosest, its loosest friction with rolling friction, [`POUR_ROLLING_TABLE`]).
pub fn pour_friction_for(phi: f64) -> Result<f64, String> {
    let rolling_lo = POUR_ROLLING_TABLE[POUR_ROLLING_TABLE.len() - 1].0;
    if pour_rolling_for(phi).is_some() || (phi >= rolling_lo && phi < POUR_TABLE[3].0) {
        return Ok(POUR_TABLE[POUR_TABLE.len() - 1].1);
    }
    let (hi, lo) = (POUR_TABLE[0].0, rolling_lo);
    if !(lo..=hi).contains(&phi) {
        return Err(format!(
            "the target packing fraction is {phi} (allowed: {lo} to {hi}, what pouring \
             frictional spheres gives, with rolling friction below 0.583)"
        ));
    }
    Ok(interpolate(&POUR_TABLE, phi).unwrap_or(POUR_TABLE[POUR_TABLE.len() - 1].1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_step_follows_the_rayleigh_time_of_the_smallest_grain() {
        let s = LammpsSpec::preset(Preset::Small);
        // r = 0.9 mm, G = 5e6 / 2.6, rho 1000: pi r sqrt(rho/G) / 0.9255.
        let g: f64 = 5e6 / 2.6;
        let expected = core::f64::consts::PI * 0.9e-3 * (1000.0 / g).sqrt() / 0.92553;
        assert!((s.rayleigh_time_s() / expected - 1.0).abs() < 1e-4);
        let dt = s.time_step_s();
        assert!(dt <= 0.15 * expected && dt > 0.14 * expected, "{dt}");
        // Four times stiffer: half the step.
        let stiff = LammpsSpec {
            youngs_modulus_pa: 2e7,
            ..s.clone()
        };
        assert!((stiff.rayleigh_time_s() / s.rayleigh_time_s() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn dumps_fall_on_force_windows_at_the_camera_rate() {
        for p in [Preset::Small, Preset::Paper] {
            let s = LammpsSpec::preset(p);
            assert_eq!(s.dump_every() % s.force_every(), 0);
            assert!(
                (s.actual_fps() / s.fps - 1.0).abs() < 0.05,
                "{}",
                s.actual_fps()
            );
            s.check().unwrap();
        }
    }

    #[test]
    fn the_grain_count_fills_the_bed_at_its_packing() {
        let s = LammpsSpec::preset(Preset::Small);
        let n = s.grain_count() as f64;
        let v = core::f64::consts::PI / 6.0 * 0.002f64.powi(3) * 1.01;
        assert!((n * v / (0.06 * 0.06 * 0.04) - 0.60).abs() < 1e-3);
        let paper = LammpsSpec::preset(Preset::Paper).grain_count();
        assert!(paper > 10_000_000 && paper < 20_000_000, "{paper}");
    }

    #[test]
    fn bad_values_are_refused_naming_what_is_allowed() {
        let s = LammpsSpec::preset(Preset::Small);
        let e = LammpsSpec {
            packing_fraction: 0.7,
            ..s.clone()
        }
        .check()
        .unwrap_err();
        assert!(e.contains("0.7") && e.contains("allowed"), "{e}");
        let e = LammpsSpec {
            foot_diameter_m: 0.004,
            ..s.clone()
        }
        .check()
        .unwrap_err();
        assert!(e.contains("4 grain diameters"), "{e}");
        let e = LammpsSpec {
            friction: f64::NAN,
            ..s
        }
        .check()
        .unwrap_err();
        assert!(e.contains("friction"), "{e}");
    }

    #[test]
    fn the_pour_friction_interpolates_its_table() {
        assert!((pour_friction_for(0.594).unwrap() - 0.5).abs() < 1e-12);
        assert!((pour_friction_for(0.590).unwrap() - (0.5 + 4.0 / 7.0 * 0.5)).abs() < 1e-12);
        assert!(pour_friction_for(0.63).is_err());
        // Below sliding friction's loosest: its friction, with rolling friction.
        let loosest = POUR_TABLE[POUR_TABLE.len() - 1];
        assert_eq!(pour_friction_for(0.58).unwrap(), loosest.1);
        let (p0, p1) = (POUR_ROLLING_TABLE[1], POUR_ROLLING_TABLE[2]);
        let mid = pour_rolling_for(0.5 * (p0.0 + p1.0)).unwrap();
        assert!((mid - 0.5 * (p0.1 + p1.1)).abs() < 1e-12, "{mid}");
        assert_eq!(pour_rolling_for(0.60), None);
        assert!(pour_friction_for(0.5).is_err());
    }
}
