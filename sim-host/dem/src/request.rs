//! What `bed` and `intrude` requests share: the grains and contacts ([`ModelRequest`]) and
//! the worker threads a run steps on ([`with_threads`]).

use serde::{Deserialize, Serialize};

use crate::error::DemError;
use crate::grains::SizeDistribution;
use crate::params::{Choice, DemParams, Model};
use crate::world::Integrator;

/// The grains' sizes as a request names them: two sizes large over small
/// [`ModelRequest::ratio`], or a uniform spread [`ModelRequest::spread`] about the mean.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Sizes {
    /// One size.
    Mono,
    /// Two sizes, 50:50.
    Bi,
    /// Uniform spread.
    Poly,
}

/// Grains and contacts of a bed or an intrusion, as the command line's model options give
/// them; [`ModelRequest::resolve`] turns them into [`DemParams`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ModelRequest {
    /// Model: `paper` (Supplementary I) or `full` (gravity, walls, friction, Verlet).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "paper"))]
    pub model: Model,
    /// Grain sizes: mono, bi (50:50, ratio 1.4) or poly.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "bi"))]
    pub sizes: Sizes,
    /// Large over small diameter (bi).
    #[cfg_attr(feature = "clap", arg(long, value_name = "R", default_value = "1.4", value_parser = sandjumper_output::parse::parse_positive))]
    pub ratio: f64,
    /// Spread of diameters about the mean (poly), share.
    #[cfg_attr(feature = "clap", arg(long, value_name = "S", default_value = "0.2", value_parser = sandjumper_output::parse::parse_number))]
    pub spread: f64,
    /// Small grain diameter, m.
    #[cfg_attr(feature = "clap", arg(long = "diameter", value_name = "M", default_value = "1e-3", value_parser = sandjumper_output::parse::parse_number))]
    pub diameter_m: f64,
    /// Grain density, kg/m^3.
    #[cfg_attr(feature = "clap", arg(long = "density", value_name = "KG_M3", default_value = "1000", value_parser = sandjumper_output::parse::parse_number))]
    pub density_kg_m3: f64,
    /// Intrusion speed the stiffness is chosen for, m/s.
    #[cfg_attr(feature = "clap", arg(long = "design-speed", value_name = "M_PER_S", default_value = "0.5", value_parser = sandjumper_output::parse::parse_number))]
    pub design_speed_m_s: f64,
    /// Largest overlap at that speed, share of a diameter.
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", default_value = "0.01", value_parser = sandjumper_output::parse::parse_number))]
    pub overlap: f64,
    /// Normal stiffness instead, N/m.
    #[cfg_attr(feature = "clap", arg(long = "kn", value_name = "N_PER_M", value_parser = sandjumper_output::parse::parse_number))]
    pub kn_n_per_m: Option<f64>,
    /// Coefficient of restitution (paper: of two small grains, with one dashpot for all
    /// pairs; full: of every pair).
    #[cfg_attr(feature = "clap", arg(long, value_name = "E", default_value = "0.5", value_parser = sandjumper_output::parse::parse_number))]
    pub restitution: f64,
    /// Dashpot instead, N s/m (the same for every pair).
    #[cfg_attr(feature = "clap", arg(long = "damping", value_name = "N_S_PER_M", value_parser = sandjumper_output::parse::parse_number))]
    pub damping_n_s_per_m: Option<f64>,
    /// Friction coefficient (full model).
    #[cfg_attr(feature = "clap", arg(long, value_name = "MU", default_value = "0.5", value_parser = sandjumper_output::parse::parse_number))]
    pub mu: f64,
    /// Per-grain drag rate, 1/s (paper default 20, full 0).
    #[cfg_attr(feature = "clap", arg(long = "drag", value_name = "PER_S", value_parser = sandjumper_output::parse::parse_number))]
    pub drag_per_s: Option<f64>,
    /// Integrator (paper: forward Euler, full: velocity Verlet).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub integrator: Option<Integrator>,
    /// Steps per shortest contact time.
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value = "50", value_parser = sandjumper_output::parse::parse_number))]
    pub steps_per_contact: f64,
    /// Time step instead, s.
    #[cfg_attr(feature = "clap", arg(long = "dt", value_name = "S", value_parser = sandjumper_output::parse::parse_number))]
    pub dt_s: Option<f64>,
    /// Allow a step above t_c / 10.
    #[cfg_attr(feature = "clap", arg(long))]
    pub force_step: bool,
    /// Walls in the paper model (the full model always has them).
    #[cfg_attr(feature = "clap", arg(long))]
    pub walls: bool,
}

impl Default for ModelRequest {
    fn default() -> Self {
        Self {
            model: Model::Paper,
            sizes: Sizes::Bi,
            ratio: 1.4,
            spread: 0.2,
            diameter_m: 1e-3,
            density_kg_m3: 1000.0,
            design_speed_m_s: 0.5,
            overlap: 0.01,
            kn_n_per_m: None,
            restitution: 0.5,
            damping_n_s_per_m: None,
            mu: 0.5,
            drag_per_s: None,
            integrator: None,
            steps_per_contact: 50.0,
            dt_s: None,
            force_step: false,
            walls: false,
        }
    }
}

impl ModelRequest {
    /// The parameters these choices resolve to (bad input: what and what is allowed).
    pub fn resolve(&self) -> Result<DemParams, DemError> {
        let mut c = Choice::new(self.model);
        c.sizes = match self.sizes {
            Sizes::Mono => SizeDistribution::Mono,
            Sizes::Bi => SizeDistribution::Bi {
                ratio: self.ratio,
                small_share: 0.5,
            },
            Sizes::Poly => SizeDistribution::Poly {
                spread: self.spread,
            },
        };
        c.diameter_m = self.diameter_m;
        c.density_kg_m3 = self.density_kg_m3;
        c.speed_m_s = self.design_speed_m_s;
        c.overlap = self.overlap;
        c.kn_n_per_m = self.kn_n_per_m;
        c.restitution = self.restitution;
        c.damping_n_s_per_m = self.damping_n_s_per_m;
        c.mu = self.mu;
        c.drag_per_s = self.drag_per_s;
        c.integrator = self.integrator;
        c.steps_per_contact = self.steps_per_contact;
        c.dt_s = self.dt_s;
        c.walls = self.walls;
        c.resolve(self.force_step).map_err(DemError::Input)
    }
}

/// Run `f` on a pool of `n` threads (0: as many as rayon's default, all cores), each pinned
/// to a core of its own when `pin` (refused when this process may run on fewer cores).
pub fn with_threads<T: Send>(
    n: usize,
    pin: bool,
    f: impl FnOnce() -> Result<T, DemError> + Send,
) -> Result<T, DemError> {
    let cores = if pin {
        core_affinity::get_core_ids().unwrap_or_default()
    } else {
        Vec::new()
    };
    let n = if n == 0 {
        rayon::current_num_threads()
    } else {
        n
    };
    if pin && cores.len() < n {
        return Err(DemError::input(format!(
            "--pin-threads: {n} threads need {n} cores, and this process may run on {} \
             (use --threads {} or fewer, or drop --pin-threads)",
            cores.len(),
            cores.len().max(1)
        )));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .start_handler(move |k| {
            if let Some(&core) = cores.get(k) {
                core_affinity::set_for_current(core);
            }
        })
        .build()
        .map_err(|e| DemError::internal(format!("cannot start {n} threads: {e}")))?;
    pool.install(f)
}
