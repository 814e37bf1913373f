//! `dem bed` as one call: a bed prepared (settled under gravity or packed to an area
//! fraction) and its folder written: `bed.ckpt`, `grains.csv`, `load.csv`, `bed.toml`,
//! `bed.png`/`.svg`.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::bed::{BedMethod, BedReport, BedSpec, prepare};
use crate::error::DemError;
use crate::params::DemParams;
use crate::render::SideCamera;
use crate::request::{ModelRequest, with_threads};
use crate::world::World;
use sandjumper_output::{Progress, StagedDir, write_csv};

/// A bed to prepare.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct BedRequest {
    /// Grains and contacts.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub model: ModelRequest,
    /// Box width, m.
    #[cfg_attr(feature = "clap", arg(long = "width", value_name = "M", default_value = "0.23", value_parser = sandjumper_output::parse::parse_number))]
    pub width_m: f64,
    /// Bed height, m.
    #[cfg_attr(feature = "clap", arg(long = "height", value_name = "M", default_value = "0.08", value_parser = sandjumper_output::parse::parse_number))]
    pub height_m: f64,
    /// Pack to this area fraction with no gravity instead of settling under gravity.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PHI", value_parser = sandjumper_output::parse::parse_number))]
    pub pack: Option<f64>,
    /// Seed.
    #[cfg_attr(feature = "clap", arg(long, default_value = "1"))]
    pub seed: u64,
    /// Longest preparation, simulated s.
    #[cfg_attr(feature = "clap", arg(long = "max-time", value_name = "S", default_value = "2", value_parser = sandjumper_output::parse::parse_number))]
    pub max_time_s: f64,
    /// At rest once the kinetic energy per grain is below this share of m g d.
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", default_value = "1e-8", value_parser = sandjumper_output::parse::parse_number))]
    pub rest: f64,
    /// Threads (0: all cores).
    #[cfg_attr(feature = "clap", arg(long, default_value = "0"))]
    pub threads: usize,
    /// Pin each thread to a core of its own, among those this process may run on (as
    /// OpenMP's `OMP_PROC_BIND`): steadier, and about 2 % faster on two threads. Leave it
    /// off on a node shared with jobs that are not confined to cores of their own.
    #[cfg_attr(feature = "clap", arg(long))]
    pub pin_threads: bool,
    /// Output directory: bed.ckpt, grains.csv, load.csv, bed.toml, bed.png/.svg.
    #[cfg_attr(feature = "clap", arg(long, value_name = "DIR"))]
    pub out: PathBuf,
}

impl Default for BedRequest {
    fn default() -> Self {
        Self {
            model: ModelRequest::default(),
            width_m: 0.23,
            height_m: 0.08,
            pack: None,
            seed: 1,
            max_time_s: 2.0,
            rest: 1e-8,
            threads: 0,
            pin_threads: false,
            out: PathBuf::new(),
        }
    }
}

/// A prepared bed: its report and where its folder went.
#[derive(Clone, Debug, Serialize)]
pub struct BedOutcome {
    /// The bed as prepared.
    pub report: BedReport,
    /// Its folder.
    pub out: PathBuf,
}

impl fmt::Display for BedOutcome {
    /// The line `dem bed` prints.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rep = &self.report;
        write!(
            f,
            "dem bed: {} grains ({:.3e} kg), surface {:.4} m, area fraction {:.3}, {} after {:.3} s ({} steps), written to {}",
            rep.grains,
            rep.mass_kg,
            rep.surface_m,
            rep.area_fraction,
            if rep.settled {
                "at rest"
            } else {
                "NOT at rest"
            },
            rep.time_s,
            rep.steps,
            self.out.display()
        )
    }
}

impl BedRequest {
    /// The parameters and bed this request resolves to, checked (bad input: what and what
    /// is allowed).
    pub fn validate(&self) -> Result<(DemParams, BedSpec), DemError> {
        let p = self.model.resolve()?;
        let spec = BedSpec {
            width_m: self.width_m,
            height_m: self.height_m,
            method: match self.pack {
                Some(phi) => BedMethod::Pack { phi },
                None => BedMethod::Settle,
            },
            seed: self.seed,
            max_time_s: self.max_time_s,
            rest_agitation: self.rest,
        };
        spec.check(&p).map_err(DemError::Input)?;
        Ok((p, spec))
    }
}

/// What `bed.toml` holds.
#[derive(Serialize)]
struct BedRecord<'a> {
    params: &'a DemParams,
    spec: &'a BedSpec,
    report: &'a BedReport,
    bytes_per_grain: f64,
}

/// Prepare the bed `request` asks for on its threads and write its folder.
pub fn run(request: &BedRequest, progress: &dyn Progress) -> Result<BedOutcome, DemError> {
    with_threads(request.threads, request.pin_threads, || {
        run_here(request, progress)
    })
}

fn run_here(a: &BedRequest, progress: &dyn Progress) -> Result<BedOutcome, DemError> {
    let (p, spec) = a.validate()?;
    let staged = StagedDir::create(&a.out)?;
    let n = spec.grain_count(&p);
    let dl = p.dimensionless(p.design_speed_m_s);
    progress.note(&format!(
        "dem bed: {n} grains, step {:.3e} s, contact time {:.3e} s, t_c v / d = {:.3e}, Froude v / sqrt(g d) = {:.2} at {} m/s",
        p.dt_s, dl.contact_time_s, dl.contact_time_speed_over_d, dl.froude, p.design_speed_m_s
    ));
    progress.start("bed preparation (share)", Some(1000));
    let mut at = 0u64;
    let (world, rep) = prepare(&p, &spec, |f| {
        let now = (f * 1000.0) as u64;
        progress.advance(now.saturating_sub(at));
        at = at.max(now);
        !progress.cancelled()
    })
    .map_err(|e| {
        if e == crate::bed::STOPPED {
            DemError::internal(e)
        } else {
            DemError::Input(e)
        }
    })?;
    progress.finish();
    crate::checkpoint::save(
        &staged.file("bed.ckpt"),
        &world,
        &serde_json::json!({ "bed": { "params": p, "spec": spec, "report": rep } }),
        &[],
    )
    .map_err(DemError::Internal)?;
    write_grains(&staged.file("grains.csv"), &world)?;
    write_load(&staged.file("load.csv"), &world, rep.surface_m)?;
    let rec = BedRecord {
        params: &p,
        spec: &spec,
        report: &rep,
        bytes_per_grain: world.bytes_per_grain(),
    };
    staged.write_text(
        "bed.toml",
        &toml::to_string(&rec).map_err(DemError::internal)?,
    )?;
    let cam = overview_camera(a.width_m, rep.surface_m);
    // A bed at rest: the colour scale only has to exist.
    let vmax = 0.1;
    crate::figure::save_snapshot(
        &world,
        &cam,
        vmax,
        &format!(
            "DEM bed: {} grains, area fraction {:.3}, hexatic order {:.2}",
            rep.grains,
            rep.area_fraction,
            crate::structure::hexatic_order(&world)
        ),
        &staged.file("bed.png"),
        &staged.file("bed.svg"),
    )?;
    let out = staged.commit()?;
    Ok(BedOutcome { report: rep, out })
}

/// The load across heights against the weight above (a bed at rest carries its weight).
fn write_load(path: &Path, world: &World, surface_m: f64) -> Result<(), DemError> {
    let heights: Vec<f64> = (1..20).map(|k| surface_m * k as f64 / 20.0).collect();
    let load = world.vertical_load_across(&heights);
    let g = world.cfg.gravity_m_s2;
    #[derive(Serialize)]
    struct LoadRow {
        height_m: f64,
        load_n: f64,
        weight_above_n: f64,
    }
    let rows: Vec<LoadRow> = heights
        .iter()
        .zip(&load)
        .map(|(&h, &l)| LoadRow {
            height_m: h,
            load_n: l,
            weight_above_n: (0..world.g.len())
                .filter(|&i| world.g.y[i] >= h)
                .map(|i| world.g.mass(i) * g)
                .sum(),
        })
        .collect();
    write_csv(path, &rows, &["height_m", "load_n", "weight_above_n"]).map_err(DemError::Internal)
}

fn overview_camera(width: f64, surface: f64) -> SideCamera {
    let m_per_px = (width.max(surface) / 1200.0).max(1e-6);
    SideCamera {
        m_per_px,
        left_m: 0.0,
        top_m: surface * 1.05,
        width_px: (width / m_per_px) as u32,
        height_px: (surface * 1.05 / m_per_px) as u32,
    }
}

fn write_grains(path: &Path, w: &World) -> Result<(), DemError> {
    #[derive(Serialize)]
    struct Row {
        id: u32,
        kind: u8,
        x_m: f64,
        y_m: f64,
        diameter_m: f64,
        vx_m_s: f64,
        vy_m_s: f64,
    }
    let g = &w.g;
    let mut rows: Vec<Row> = (0..g.len())
        .map(|i| Row {
            id: g.id[i],
            kind: g.kind[i],
            x_m: g.x[i],
            y_m: g.y[i],
            diameter_m: 2.0 * g.radius[i],
            vx_m_s: w.u.x[i],
            vy_m_s: w.u.y[i],
        })
        .collect();
    rows.sort_by_key(|r| r.id);
    write_csv(
        path,
        &rows,
        &["id", "kind", "x_m", "y_m", "diameter_m", "vx_m_s", "vy_m_s"],
    )
    .map_err(DemError::Internal)
}
