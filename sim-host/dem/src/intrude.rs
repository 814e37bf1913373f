//! An intrusion run: the intruder driven along its trajectory into a bed, with the force of
//! the grains on it recorded, the flow sampled at the camera's frame rate (coarse-grained
//! fields through the PIV code, side-wall frames, speed snapshots), and checkpoints so a
//! stopped run resumes to the same bits.
//!
//! Sampling and checkpoints happen at fixed step numbers, and a checkpoint rebuilds the
//! neighbour list before it is written (a resumed run rebuilds it from the same state), so a
//! run resumed from any checkpoint repeats the uninterrupted run exactly.

use serde::{Deserialize, Serialize};

use super::coarse::{CoarseField, GridSpec, coarse_grain, sample_momenta};
use super::intruder::{IntruderSpec, Trajectory};
use super::params::DemParams;
use super::render::SideCamera;
use super::world::World;
use sandjumper_flow::fields::derive;

/// How to run and sample an intrusion (with the trajectory, what a checkpoint stores).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct IntrudeSpec {
    /// The run's parameters.
    pub params: DemParams,
    /// The intruder.
    pub foot_width_m: f64,
    /// Trajectory as a table (constant speed is tabulated at its two ends).
    pub t_s: Vec<f64>,
    /// Depth at `t_s`, m.
    pub depth_m: Vec<f64>,
    /// Where the trajectory came from.
    pub trajectory: String,
    /// Samples (fields, frames, snapshots) per second.
    pub fps: f64,
    /// Force rows per second (each the mean over its interval).
    pub force_rate_hz: f64,
    /// Coarse-graining grid spacing, m.
    pub grid_spacing_m: f64,
    /// Coarse-graining Gaussian width, m.
    pub cg_width_m: f64,
    /// Side-wall camera scale, m/px.
    pub m_per_px: f64,
    /// Render side-wall frames.
    pub frames: bool,
    /// Bulk packing fraction for momentum (`rho phi`), as in `piv --phi`.
    pub phi_bulk: f64,
    /// Steps between checkpoints (0: none).
    pub checkpoint_every: u64,
    /// Seed of the grains' grey levels.
    pub seed: u64,
    /// Bed surface, m.
    pub surface_m: f64,
    /// Bed box: left and right, m.
    pub bed_x_m: (f64, f64),
    /// The added mass `P / v_foot` is taken only while the foot moves down at least this
    /// share of its fastest speed (the paper excluded the samples where `v_foot -> 0`).
    #[serde(default = "default_min_speed_ratio")]
    pub min_speed_ratio: f64,
}

/// A number that JSON wrote as `null` (serde writes NaN so) is NaN again.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// The paper's exclusion of slow samples: `v_foot >= 0.3 v_max`.
pub const DEFAULT_MIN_SPEED_RATIO: f64 = 0.3;

fn default_min_speed_ratio() -> f64 {
    DEFAULT_MIN_SPEED_RATIO
}

/// The paper's added mass: `P / v_foot` (the column's momentum over the foot's speed, both
/// down positive) while the foot moves down at least `min_ratio` of its fastest speed
/// `v_max_m_s`; NaN otherwise.
pub fn paper_added_mass(p_kg_m_s: f64, v_m_s: f64, v_max_m_s: f64, min_ratio: f64) -> f64 {
    if v_m_s > 0.0 && v_m_s >= min_ratio * v_max_m_s {
        p_kg_m_s / v_m_s
    } else {
        f64::NAN
    }
}

/// One row of `force_depth.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ForceRow {
    /// End of the interval, s.
    pub t_s: f64,
    /// Intruder depth below the surface, m.
    pub depth_m: f64,
    /// Intruder velocity, m/s (down positive).
    pub velocity_m_s: f64,
    /// Mean force of the grains on the intruder over the interval, N (up positive).
    pub force_n: f64,
}

/// One row of `flow.csv`: a sample of the flow.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlowRow {
    /// Sample number.
    pub sample: u64,
    /// s.
    pub t_s: f64,
    /// m.
    pub depth_m: f64,
    /// Intruder speed, m/s (down positive).
    pub foot_speed_m_s: f64,
    /// Momentum from the left half-plane, kg m/s (down positive).
    pub momentum_left_kg_m_s: f64,
    /// From the right half-plane.
    pub momentum_right_kg_m_s: f64,
    /// Their mean: the wide window (every grain below the surface, r-weighted), kg m/s.
    pub momentum_kg_m_s: f64,
    /// The paper's `P`: the column under the foot (`r <= R`, below it), kg m/s (down
    /// positive).
    #[serde(default)]
    pub momentum_under_foot_kg_m_s: f64,
    /// The same column cut at the jammed cone's depth `R tan 60` under the foot, kg m/s:
    /// how much of `P` comes from deeper (the column above runs to the window's bottom).
    #[serde(default)]
    pub momentum_under_foot_to_cone_depth_kg_m_s: f64,
    /// The wide window split in bands (a diagnostic): below the foot between `R` and `2R` from
    /// the axis, kg m/s (down positive).
    #[serde(default)]
    pub momentum_band_r_to_2r_kg_m_s: f64,
    /// Between `2R` and `3R`.
    #[serde(default)]
    pub momentum_band_2r_to_3r_kg_m_s: f64,
    /// The rest of the window: beyond `3R`, and every grain above the foot's bottom (pushed up
    /// beside it), kg m/s. The bands and the column add up to the window (within the window's
    /// cell-centre weighting against the columns' per-pixel `r`).
    #[serde(default)]
    pub momentum_elsewhere_kg_m_s: f64,
    /// The column's momentum in the window's bottom tenth (between the window's bottom and a
    /// tenth of the column's depth above it), kg m/s: motion reaching the bottom.
    #[serde(default)]
    pub momentum_in_window_bottom_tenth_kg_m_s: f64,
    /// The paper's added mass `P / v_foot` with `P` under the foot, kg; NaN while the foot
    /// moves slower than the spec's share of its fastest speed (`null` in a checkpoint's
    /// JSON, read back as NaN).
    #[serde(deserialize_with = "nan_if_null")]
    pub added_mass_kg: f64,
    /// Largest shear rate in the field, 1/s.
    pub max_shear_rate_per_s: f64,
    /// Grid cells counted in the momentum.
    pub cells: usize,
}

/// The run's progress (what a checkpoint's record holds beside the spec).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunState {
    /// Force rows so far.
    pub force: Vec<ForceRow>,
    /// Flow rows so far.
    pub flow: Vec<FlowRow>,
    /// Force sum over the open interval, N.
    pub force_sum_n: f64,
    /// Steps in the open interval.
    pub force_steps: u64,
}

/// Everything a run needs, ready.
pub struct Run {
    /// Spec.
    pub spec: IntrudeSpec,
    /// World.
    pub world: World,
    /// Progress.
    pub state: RunState,
    /// Coarse fields per sample: u, v, shear rate, vorticity (flattened in `extra`).
    pub fields: Vec<[Vec<f64>; 4]>,
    /// The grid.
    pub grid: GridSpec,
    /// The camera.
    pub camera: SideCamera,
    /// Total steps.
    pub total_steps: u64,
    /// Stepping speed in this process (not checkpointed: it is a property of the machine).
    pub performance: Performance,
}

/// How fast this process stepped: wall time inside [`World::step`] only (no sampling,
/// frames or checkpoints), as LAMMPS's "Performance" line reports its run loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Performance {
    /// Steps taken by this process.
    pub steps: u64,
    /// Wall time spent in them, s.
    pub wall_s: f64,
    /// Grains times steps over wall time, 1/s.
    pub atom_steps_per_s: f64,
    /// Neighbour-list builds in these steps (one per grain drift of half the skin, and
    /// one at each checkpoint).
    pub list_builds: u64,
}

impl IntrudeSpec {
    /// The trajectory.
    pub fn trajectory(&self) -> Trajectory {
        Trajectory::Table {
            t_s: self.t_s.clone(),
            depth_m: self.depth_m.clone(),
            source: self.trajectory.clone(),
        }
    }

    /// The intruder.
    pub fn intruder(&self) -> IntruderSpec {
        IntruderSpec {
            width_m: self.foot_width_m,
            x_centre_m: 0.5 * (self.bed_x_m.0 + self.bed_x_m.1),
            grain_d_m: self.params.diameter_m,
        }
    }

    /// Steps of sample `k`.
    pub fn sample_step(&self, k: u64) -> u64 {
        (k as f64 / (self.fps * self.params.dt_s)).round() as u64
    }

    /// Steps per force row.
    pub fn force_steps(&self) -> u64 {
        ((1.0 / (self.force_rate_hz * self.params.dt_s)).round() as u64).max(1)
    }

    /// The grid and camera around the intruder: three foot widths wide (within the bed),
    /// from a third of a foot width above the surface down to the deepest point plus a foot
    /// width (above the floor).
    pub fn views(&self) -> (GridSpec, SideCamera) {
        let (x0, x1) = self.bed_x_m;
        let c = 0.5 * (x0 + x1);
        let half = (1.5 * self.foot_width_m).min(0.5 * (x1 - x0));
        let deepest = self.depth_m.iter().copied().fold(0.0, f64::max);
        let top = self.surface_m + self.foot_width_m / 3.0;
        let bottom = (self.surface_m - deepest - self.foot_width_m).max(0.0);
        let h = self.grid_spacing_m;
        let nx = ((2.0 * half / h) as usize).max(2);
        let ny = (((top - bottom) / h) as usize).max(2);
        let grid = GridSpec {
            x0_m: c - 0.5 * (nx - 1) as f64 * h,
            top_m: top,
            nx,
            ny,
            spacing_m: h,
            width_m: self.cg_width_m,
            min_density_share: 0.2,
        };
        let cam = SideCamera {
            m_per_px: self.m_per_px,
            left_m: c - half,
            top_m: top,
            width_px: ((2.0 * half / self.m_per_px) as u32).max(8),
            height_px: (((top - bottom) / self.m_per_px) as u32).max(8),
        };
        (grid, cam)
    }
}

/// Bulk 2-D density of the bed (kg/m^2 of the plane) for the coarse-graining threshold.
pub fn plane_density(w: &World, x: (f64, f64), surface_m: f64) -> f64 {
    let (_, m) = w.g.free_mass();
    m / ((x.1 - x.0) * surface_m).max(f64::MIN_POSITIVE)
}

/// What a sample gives the caller to write (frames are written by the caller).
pub struct SampleOut<'a> {
    /// Sample number.
    pub k: u64,
    /// The world now.
    pub world: &'a World,
    /// Coarse field.
    pub field: &'a CoarseField,
}

impl Run {
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.world.steps
    }

    /// Advance to `until_step` (or the end), calling `on_sample` at each sample and
    /// `on_checkpoint` at each checkpoint step, `on_progress` now and then.
    pub fn advance(
        &mut self,
        until_step: u64,
        on_sample: &mut dyn FnMut(&SampleOut) -> Result<(), String>,
        on_checkpoint: &mut dyn FnMut(&Run) -> Result<(), String>,
        on_progress: &mut dyn FnMut(u64),
    ) -> Result<(), String> {
        let traj = self.spec.trajectory();
        let dt = self.spec.params.dt_s;
        let fsteps = self.spec.force_steps();
        let rho_plane = plane_density(&self.world, self.spec.bed_x_m, self.spec.surface_m);
        let rho_phi = self.spec.params.density_kg_m3 * self.spec.phi_bulk;
        let intr = self.spec.intruder();
        let (fl, fr) = intr.edges();
        let axis = intr.x_centre_m;
        let end = until_step.min(self.total_steps);
        // Sample 0 at the start (if not taken yet).
        if self.world.steps == 0 && self.state.flow.is_empty() {
            self.sample(0, &traj, rho_plane, rho_phi, axis, (fl, fr), on_sample)?;
        }
        while self.world.steps < end {
            let t_next = (self.world.steps + 1) as f64 * dt;
            let d = traj.depth(t_next);
            self.world.intruder_next = Some((self.spec.surface_m - d, -traj.speed(t_next)));
            let t0 = std::time::Instant::now();
            let builds = self.world.nl.builds;
            self.world.step();
            let perf = &mut self.performance;
            perf.list_builds += self.world.nl.builds - builds;
            perf.wall_s += t0.elapsed().as_secs_f64();
            perf.steps += 1;
            perf.atom_steps_per_s = perf.steps as f64 * self.world.g.len() as f64 / perf.wall_s;
            self.state.force_sum_n += self.world.last.intruder_fy_n;
            self.state.force_steps += 1;
            let s = self.world.steps;
            if s.is_multiple_of(fsteps) {
                self.state.force.push(ForceRow {
                    t_s: self.world.t_s,
                    depth_m: d,
                    velocity_m_s: traj.speed(self.world.t_s),
                    force_n: self.state.force_sum_n / self.state.force_steps as f64,
                });
                self.state.force_sum_n = 0.0;
                self.state.force_steps = 0;
            }
            let k = self.state.flow.len() as u64;
            if s == self.spec.sample_step(k) {
                self.sample(k, &traj, rho_plane, rho_phi, axis, (fl, fr), on_sample)?;
            }
            if self.spec.checkpoint_every > 0
                && s.is_multiple_of(self.spec.checkpoint_every)
                && s < self.total_steps
            {
                self.world.rebuild();
                on_checkpoint(self)?;
            }
            if s.is_multiple_of(1000) {
                on_progress(s);
            }
        }
        on_progress(self.world.steps);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn sample(
        &mut self,
        k: u64,
        traj: &Trajectory,
        rho_plane: f64,
        rho_phi: f64,
        axis: f64,
        edges: (f64, f64),
        on_sample: &mut dyn FnMut(&SampleOut) -> Result<(), String>,
    ) -> Result<(), String> {
        let t = self.world.t_s;
        let depth = traj.depth(t);
        let speed = traj.speed(t);
        let field = coarse_grain(&self.world, &self.grid, rho_plane);
        let d = derive(&field.u, &field.v);
        let bottom = self.spec.surface_m - depth;
        let momenta = sample_momenta(
            &field,
            &self.grid,
            axis,
            self.spec.surface_m,
            rho_phi,
            (edges.0, edges.1, bottom),
        );
        let m = momenta.window;
        // Momentum is computed height-up; the paper's P is along the intrusion (down).
        let (l, r, p) = (-m.left_kg_m_s, -m.right_kg_m_s, -m.momentum_kg_m_s);
        let p_column = -momenta.under_foot.momentum_kg_m_s;
        let p_cone = -momenta.under_foot_to_cone.momentum_kg_m_s;
        let p_2r = -momenta.under_foot_2r.momentum_kg_m_s;
        let p_3r = -momenta.under_foot_3r.momentum_kg_m_s;
        let p_above_bottom = -momenta.under_foot_above_bottom_tenth.momentum_kg_m_s;
        let max_shear = d
            .shear_rate
            .values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        self.state.flow.push(FlowRow {
            sample: k,
            t_s: t,
            depth_m: depth,
            foot_speed_m_s: speed,
            momentum_left_kg_m_s: l,
            momentum_right_kg_m_s: r,
            momentum_kg_m_s: p,
            momentum_under_foot_kg_m_s: p_column,
            momentum_under_foot_to_cone_depth_kg_m_s: p_cone,
            momentum_band_r_to_2r_kg_m_s: p_2r - p_column,
            momentum_band_2r_to_3r_kg_m_s: p_3r - p_2r,
            momentum_elsewhere_kg_m_s: p - p_3r,
            momentum_in_window_bottom_tenth_kg_m_s: p_column - p_above_bottom,
            added_mass_kg: paper_added_mass(
                p_column,
                speed,
                traj.max_intrusion_speed(),
                self.spec.min_speed_ratio,
            ),
            max_shear_rate_per_s: max_shear,
            cells: m.cells,
        });
        self.fields.push([
            field.u.values.clone(),
            field.v.values.clone(),
            d.shear_rate.values,
            d.vorticity.values,
        ]);
        on_sample(&SampleOut {
            k,
            world: &self.world,
            field: &field,
        })
    }

    /// The fields flattened for a checkpoint's extra array.
    pub fn fields_flat(&self) -> Vec<f64> {
        self.fields
            .iter()
            .flat_map(|f| f.iter().flat_map(|a| a.iter().copied()))
            .collect()
    }

    /// Restore fields from a checkpoint's extra array.
    pub fn fields_from_flat(flat: &[f64], cells: usize) -> Vec<[Vec<f64>; 4]> {
        flat.chunks_exact(4 * cells)
            .map(|c| {
                [
                    c[..cells].to_vec(),
                    c[cells..2 * cells].to_vec(),
                    c[2 * cells..3 * cells].to_vec(),
                    c[3 * cells..].to_vec(),
                ]
            })
            .collect()
    }
}

/// Set up a run: the bed world `bed` (its grains at rest), the intruder added with its
/// bottom at the trajectory's first depth, the run's own world settings.
pub fn start(spec: IntrudeSpec, bed: World) -> Result<Run, String> {
    let (x0, x1) = spec.bed_x_m;
    if !(spec.foot_width_m.is_finite() && spec.foot_width_m > 0.0) {
        return Err(format!(
            "--foot-width {} m (allowed: a positive number)",
            spec.foot_width_m
        ));
    }
    if spec.foot_width_m > x1 - x0 {
        return Err(format!(
            "the intruder ({:.4} m wide) is wider than the bed ({:.4} m; allowed: at most the bed's width, better a third of it)",
            spec.foot_width_m,
            x1 - x0
        ));
    }
    if spec.foot_width_m < 3.0 * spec.params.diameter_m {
        return Err(format!(
            "--foot-width {} m (allowed: at least 3 grain diameters, {:.3e} m)",
            spec.foot_width_m,
            3.0 * spec.params.diameter_m
        ));
    }
    let mut g = bed.g;
    // Keep free grains only (a bed checkpoint has no intruder).
    let traj = spec.trajectory();
    let intr = spec.intruder();
    intr.add_to(
        &mut g,
        spec.surface_m - traj.depth(0.0),
        spec.params.density_kg_m3,
    );
    let walls = if spec.params.walls {
        super::world::Walls {
            floor_m: Some(0.0),
            left_m: Some(x0),
            right_m: Some(x1),
            lid_m: None,
        }
    } else {
        super::world::Walls::default()
    };
    let mut world = World::new(spec.params.world(walls), g);
    world.u = super::world::Velocities {
        x: world.g.vx.clone(),
        y: world.g.vy.clone(),
        w: world.g.w.clone(),
    };
    let total_steps = (traj.duration_s() / spec.params.dt_s).ceil() as u64;
    let (grid, camera) = spec.views();
    Ok(Run {
        spec,
        world,
        state: RunState::default(),
        fields: Vec::new(),
        grid,
        camera,
        total_steps,
        performance: Performance::default(),
    })
}

/// Resume a run from a checkpoint's world, record and extra array.
pub fn resume(world: World, record: &serde_json::Value, extra: &[f64]) -> Result<Run, String> {
    let spec: IntrudeSpec = serde_json::from_value(record["spec"].clone())
        .map_err(|e| format!("not an intrusion checkpoint: {e}"))?;
    let state: RunState = serde_json::from_value(record["state"].clone())
        .map_err(|e| format!("not an intrusion checkpoint: {e}"))?;
    let (grid, camera) = spec.views();
    let cells = grid.nx * grid.ny;
    if !extra.len().is_multiple_of(4 * cells) || extra.len() / (4 * cells) != state.flow.len() {
        return Err(format!(
            "corrupt: {} field values for {} samples of {} cells",
            extra.len(),
            state.flow.len(),
            cells
        ));
    }
    let traj = spec.trajectory();
    let total_steps = (traj.duration_s() / spec.params.dt_s).ceil() as u64;
    Ok(Run {
        fields: Run::fields_from_flat(extra, cells),
        spec,
        world,
        state,
        grid,
        camera,
        total_steps,
        performance: Performance::default(),
    })
}

/// The checkpoint record of a run.
pub fn record(run: &Run) -> serde_json::Value {
    serde_json::json!({ "spec": run.spec, "state": run.state })
}

#[cfg(test)]
mod paper_added_mass_tests {
    use super::paper_added_mass;

    #[test]
    fn the_added_mass_is_taken_only_while_the_foot_moves_fast_enough() {
        assert_eq!(paper_added_mass(0.03, 0.3, 0.3, 0.3), 0.1);
        assert_eq!(paper_added_mass(0.03, 0.09, 0.3, 0.3), 0.03 / 0.09);
        assert!(
            paper_added_mass(0.03, 0.089, 0.3, 0.3).is_nan(),
            "below 0.3 v_max"
        );
        assert!(
            paper_added_mass(0.03, -0.3, 0.3, 0.3).is_nan(),
            "withdrawing"
        );
        assert!(paper_added_mass(0.03, 0.0, 0.3, 0.0).is_nan(), "still");
    }
}
