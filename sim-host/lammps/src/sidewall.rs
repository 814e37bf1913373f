//! The paper's PIV, done on a 3-D run against a sidewall
//! ([`crate::spec::LammpsSpec::sidewall`]), beside
//! the exact momentum of the same run.
//!
//! The paper filmed a half foot against a glass wall and measured the grains' velocity at the
//! wall; it took the column's momentum as `rho phi int int v(r, h) 2 pi r dr dh`, assuming the
//! flow at the wall is the flow on any plane through the axis. Here the same run gives both:
//!
//! - **the exact column**: every grain under the half foot (within `R` of the axis, below the
//!   foot's bottom), its down momentum summed and doubled (the full foot's by the wall's
//!   symmetry): [`crate::analysis::frame_row`];
//! - **the sidewall PIV**: the grains touching the wall (their surface within a quarter grain
//!   of it), drawn as the camera behind the glass sees them (projected discs, nearer ones on
//!   top, each its own grey, [`sandjumper_dem::render::disc_frame`]), at the dumps' rate, and
//!   run through the project's own PIV and column momentum
//!   ([`sandjumper_flow::analysis::run`]: the same passes, foot mask, azimuthal integral and
//!   speed rule as `sandjumper piv` on the lab's video).
//!
//! Their ratio, pair by pair, is how much the sidewall PIV itself over- or under-states the
//! column (the grains at a frictional wall move more slowly than inside, and the wall's
//! layer is not the bed's packing).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use sandjumper_dem::render::{Disc, SideCamera, disc_frame};
use sandjumper_flow::analysis::{self as piv, Frames, Pairing, PivOptions};
use sandjumper_flow::momentum::Calibration;
use sandjumper_flow::piv::{Image, PivConfig};
use sandjumper_flow::preprocess::Preprocess;

use crate::analysis::{FlowRow, Geometry};
use crate::bed::FOOT;
use crate::dump::Frame;

/// Grains this close to the wall (their surface), in grain diameters, are the camera's.
pub const WALL_LAYER_DIAMETERS: f64 = 0.25;

/// The camera's scale: pixels per mean grain diameter.
pub const PX_PER_GRAIN: f64 = 10.0;

/// One row of `sidewall.csv`: one PIV pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SidewallRow {
    /// The pair's mid time, s.
    pub t_s: f64,
    /// The foot's depth (the pair's mean), m.
    pub depth_m: f64,
    /// The foot's down speed, m/s.
    pub foot_speed_m_s: f64,
    /// The exact column's momentum (the pair's two frames' mean, the full foot's), down
    /// positive, kg m/s.
    pub exact_column_kg_m_s: f64,
    /// The sidewall PIV's column momentum (azimuthal integral of the wall's field), down
    /// positive, kg m/s.
    pub piv_column_kg_m_s: f64,
    /// The exact column over the foot's speed while the speed rule holds (NaN otherwise), kg.
    pub exact_added_mass_kg: f64,
    /// The sidewall PIV's added mass (NaN where the rule excludes it), kg.
    pub piv_added_mass_kg: f64,
    /// Eq. 6 at the pair's depth, kg.
    pub eq6_added_mass_kg: f64,
}

/// The camera of a run: 3 foot diameters wide about the axis, from 2R/3 above the surface to
/// a foot diameter below the deepest point (the 2-D DEM's framing), at
/// [`PX_PER_GRAIN`] pixels a grain.
pub fn camera(g: &Geometry, max_depth_m: f64) -> SideCamera {
    let w = 2.0 * g.foot_radius_m;
    let m_per_px = g.grain_diameter_m / PX_PER_GRAIN;
    let top = g.surface_m + w / 3.0;
    let bottom = g.surface_m - max_depth_m - w;
    SideCamera {
        m_per_px,
        left_m: g.axis_m.0 - 1.5 * w,
        top_m: top,
        width_px: (3.0 * w / m_per_px).round() as u32,
        height_px: ((top - bottom) / m_per_px).round() as u32,
    }
}

/// The frame the camera behind the wall sees: the grains (and the foot's spheres) whose
/// surface is within [`WALL_LAYER_DIAMETERS`] of the wall's plane, as discs at (x, z), the
/// farthest drawn first.
pub fn wall_frame(frame: &Frame, g: &Geometry, cam: &SideCamera, seed: u64) -> Image {
    let layer = WALL_LAYER_DIAMETERS * g.grain_diameter_m;
    let mut near: Vec<_> = frame
        .atoms
        .iter()
        .filter(|a| a.x[1] - g.axis_m.1 - a.radius_m < layer)
        .collect();
    near.sort_by(|a, b| b.x[1].total_cmp(&a.x[1]));
    let discs = near.into_iter().map(|a| Disc {
        x_m: a.x[0],
        h_m: a.x[2],
        radius_m: a.radius_m,
        id: a.id as u32,
        intruder: a.kind == FOOT,
    });
    let img = disc_frame(discs, cam, seed);
    Image {
        width: img.width() as usize,
        height: img.height() as usize,
        data: img.as_raw().iter().map(|&v| f32::from(v)).collect(),
    }
}

/// The sidewall PIV of a run's frames (`frames`: each dump's step and frame, read on demand
/// by `read`) against its exact column (`rows`, [`crate::analysis::frame_row`] of the same
/// frames, the added mass decided), with the bed's bulk density `rho_phi_kg_m3` and the speed
/// rule `min_speed_ratio`. One row a pair of consecutive frames.
pub fn measure(
    steps: &[u64],
    read: &mut dyn FnMut(u64) -> Result<Frame, String>,
    rows: &[FlowRow],
    g: &Geometry,
    rho_phi_kg_m3: f64,
    min_speed_ratio: f64,
) -> Result<Vec<SidewallRow>, String> {
    let max_depth = rows.iter().map(|r| r.depth_m).fold(0.0, f64::max);
    let cam = camera(g, max_depth);
    let mut images = Vec::with_capacity(steps.len());
    let mut feet = BTreeMap::new();
    let r = g.foot_radius_m;
    for (k, (&s, row)) in steps.iter().zip(rows).enumerate() {
        images.push(wall_frame(&read(s)?, g, &cam, 1));
        // The foot's outline: its width, from its bottom to above the frame.
        let bottom = g.surface_m - row.depth_m;
        let (x0, yb) = cam.to_px(g.axis_m.0 - r, bottom);
        let (x1, _) = cam.to_px(g.axis_m.0 + r, bottom);
        feet.insert(k as u64, vec![(x0, yb), (x1, yb), (x1, -1.0), (x0, -1.0)]);
    }
    let frames = Frames {
        numbers: (0..steps.len() as u64).collect(),
        images,
        max_value: 255.0,
        times_s: Some(rows.iter().map(|r| r.t_s).collect()),
    };
    let opts = PivOptions {
        piv: PivConfig::default(),
        preprocess: Preprocess::default(),
        pairing: Pairing::Consecutive,
        every: 1,
        calibration: Some(Calibration {
            m_per_px: cam.m_per_px,
            origin_px: cam.to_px(g.axis_m.0, g.surface_m),
        }),
        rho_phi_kg_m3,
        static_mask: None,
        feet: Some(feet),
        min_speed_ratio,
    };
    let run = piv::run(&frames, &opts, || true)?;
    Ok(run
        .results
        .iter()
        .map(|p| {
            let (a, b) = (&rows[p.row.frame_a as usize], &rows[p.row.frame_b as usize]);
            let exact = 0.5 * (a.momentum_under_foot_kg_m_s + b.momentum_under_foot_kg_m_s);
            let speed = -p.row.foot_velocity_m_s;
            let piv_column = -p.row.momentum_under_foot_kg_m_s;
            let exact_mass = if p.row.added_mass_kg.is_finite() {
                exact / speed
            } else {
                f64::NAN
            };
            SidewallRow {
                t_s: p.row.t_s,
                depth_m: p.row.foot_depth_m,
                foot_speed_m_s: speed,
                exact_column_kg_m_s: exact,
                piv_column_kg_m_s: piv_column,
                exact_added_mass_kg: exact_mass,
                piv_added_mass_kg: p.row.added_mass_kg,
                eq6_added_mass_kg: 0.5 * (a.eq6_added_mass_kg + b.eq6_added_mass_kg),
            }
        })
        .collect())
}

/// The median over the pairs where both added masses are measured of the sidewall PIV's
/// over the exact one (NaN: none), 1.
pub fn piv_over_exact_median(rows: &[SidewallRow]) -> f64 {
    let ratios: Vec<f64> = rows
        .iter()
        .filter(|r| r.piv_added_mass_kg.is_finite() && r.exact_added_mass_kg.is_finite())
        .map(|r| r.piv_added_mass_kg / r.exact_added_mass_kg)
        .collect();
    sandjumper_dem::outputs::median(ratios)
}
