//! The PIV analysis of a frame sequence, stage by stage, as `sandjumper piv` and the Python
//! module run it: the frames pre-processed ([`prepare`]), paired ([`frame_pairs`]), each pair
//! masked ([`pair_mask`]: the static mask and the foot's outline), correlated and turned into
//! SI fields, grain momentum and added mass ([`analyse_pair`]), and the whole run summed up
//! ([`PivRun::totals`]). [`run`] strings the stages together; each one is a function a test
//! can feed with known values.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::fields::{Grid, derive};
use crate::momentum::{
    Calibration, Momentum, Polygon, column_momentum, foot_depth_m, grain_momentum, inside,
};
use crate::piv::{Image, PivConfig, VectorField, check_config, flag, piv_pair};
use crate::preprocess::{Preprocess, apply, background};

/// How frames are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Pairing {
    /// 1-2, 2-3, 3-4, ...
    Consecutive,
    /// 1-2, 3-4, ... (double-frame cameras).
    Ab,
}

/// The frames of one sequence, in memory.
#[derive(Clone, Debug)]
pub struct Frames {
    /// Each frame's number in its sequence (what the foot outlines and the log refer to).
    pub numbers: Vec<u64>,
    /// The frames as floats, in the sequence's grey levels.
    pub images: Vec<Image>,
    /// Largest grey level of the sequence's bit depth (255 or 65535).
    pub max_value: f32,
    /// Each frame's time, s (from a frame rate or an acquisition log), if known.
    pub times_s: Option<Vec<f64>>,
}

impl Frames {
    /// Width and height of the frames, px.
    pub fn size(&self) -> (usize, usize) {
        self.images.first().map_or((0, 0), |i| (i.width, i.height))
    }
}

/// What a PIV run is asked to do.
#[derive(Clone, Debug)]
pub struct PivOptions {
    /// The correlation passes.
    pub piv: PivConfig,
    /// Pre-processing of every frame.
    pub preprocess: Preprocess,
    /// How frames are paired.
    pub pairing: Pairing,
    /// Analyse every Nth pair (>= 1).
    pub every: usize,
    /// Pixels to metres and the foot's axis at the surface; with frame times, enables the SI
    /// fields, momentum and added mass.
    pub calibration: Option<Calibration>,
    /// Bulk density of the bed `rho phi`, kg/m^3 (momentum per unit volume of grains).
    pub rho_phi_kg_m3: f64,
    /// Pixels that are not grain flow in every frame (row-major, the frames' size).
    pub static_mask: Option<Vec<bool>>,
    /// The foot's outline per frame number (its inside is masked; its lowest point gives the
    /// foot's depth and velocity, its half width the column's radius `R`).
    pub feet: Option<BTreeMap<u64, Polygon>>,
    /// The added mass `P / v_foot` is kept only while the foot intrudes at least this fraction
    /// of its fastest intrusion (the paper: near `v = 0` the ratio is singular), 0..1.
    pub min_speed_ratio: f64,
}

/// The paper's threshold: `m_a` only while `v_foot >= 0.3 v_max`.
pub const DEFAULT_MIN_SPEED_RATIO: f64 = 0.3;

/// One row of `flow.csv`: one pair's momentum, foot and vector counts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlowRow {
    /// Pair index.
    pub pair: usize,
    /// Frame numbers.
    pub frame_a: u64,
    /// Frame numbers.
    pub frame_b: u64,
    /// Mid time of the pair, s (NaN without a clock).
    pub t_s: f64,
    /// Foot depth below the surface (mean over the pair), m.
    pub foot_depth_m: f64,
    /// Foot velocity, m/s (height up: negative when intruding).
    pub foot_velocity_m_s: f64,
    /// Grain momentum from the left half-plane, kg m/s.
    pub momentum_left_kg_m_s: f64,
    /// From the right.
    pub momentum_right_kg_m_s: f64,
    /// Mean, kg m/s.
    pub momentum_kg_m_s: f64,
    /// The paper's control volume: the column under the foot (`r <= R`, below the foot), kg m/s.
    pub momentum_under_foot_kg_m_s: f64,
    /// The paper's added mass: the column's momentum over the foot's velocity, kg, while the
    /// foot intrudes at least `min_speed_ratio` of its fastest (NaN otherwise).
    pub added_mass_kg: f64,
    /// Vectors measured and accepted.
    pub vectors_valid: usize,
    /// Outliers replaced.
    pub vectors_replaced: usize,
    /// Masked.
    pub vectors_masked: usize,
}

/// Header of `flow.csv`.
pub const FLOW_HEADER: [&str; 14] = [
    "pair",
    "frame_a",
    "frame_b",
    "t_s",
    "foot_depth_m",
    "foot_velocity_m_s",
    "momentum_left_kg_m_s",
    "momentum_right_kg_m_s",
    "momentum_kg_m_s",
    "momentum_under_foot_kg_m_s",
    "added_mass_kg",
    "vectors_valid",
    "vectors_replaced",
    "vectors_masked",
];

/// One pair's fields in SI units (height up), on the vector grid.
#[derive(Clone, Debug, PartialEq)]
pub struct SiFields {
    /// Horizontal velocity, m/s.
    pub u: Grid,
    /// Vertical velocity (up positive), m/s.
    pub v: Grid,
    /// Vorticity, 1/s.
    pub vorticity: Grid,
    /// Maximum shear strain rate (the paper's eq. 2), 1/s.
    pub shear_rate: Grid,
}

/// One pair analysed.
#[derive(Clone, Debug)]
pub struct PairResult {
    /// The displacement field, px.
    pub field: VectorField,
    /// Its row of `flow.csv`.
    pub row: FlowRow,
    /// Its SI fields (calibrated and timed runs only).
    pub si: Option<SiFields>,
}

/// A whole run.
#[derive(Clone, Debug)]
pub struct PivRun {
    /// The pairs analysed, as indices into the frames.
    pub pairs: Vec<(usize, usize)>,
    /// One result per pair.
    pub results: Vec<PairResult>,
}

/// The counts and quality of a whole run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Totals {
    /// Vectors accepted as measured, over all pairs.
    pub valid: usize,
    /// Outliers replaced by their neighbours' mean (flag 1), over all pairs.
    pub replaced: usize,
    /// Masked (flag 2), over all pairs.
    pub masked: usize,
    /// Median ratio of the first to the second correlation peak of the accepted vectors.
    pub median_peak_ratio: f64,
}

impl PivRun {
    /// The counts over all pairs and the median peak ratio.
    pub fn totals(&self) -> Totals {
        let (mut valid, mut replaced, mut masked) = (0, 0, 0);
        let mut ratios = Vec::new();
        for r in &self.results {
            let (v, rep, m) = r.field.counts();
            valid += v;
            replaced += rep;
            masked += m;
            ratios.extend(
                r.field
                    .peak_ratio
                    .iter()
                    .zip(&r.field.flag)
                    .filter(|(_, fl)| **fl == flag::VALID)
                    .map(|(p, _)| *p),
            );
        }
        ratios.sort_by(f64::total_cmp);
        Totals {
            valid,
            replaced,
            masked,
            median_peak_ratio: ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
        }
    }

    /// The rows of `flow.csv`, one per pair.
    pub fn rows(&self) -> Vec<FlowRow> {
        self.results.iter().map(|r| r.row.clone()).collect()
    }

    /// The foot's radius `R` the column under it used: half the outlines' mean width, m
    /// (`None` without outlines or a calibration).
    pub fn foot_radius_m(opts: &PivOptions) -> Option<f64> {
        let (feet, cal) = (opts.feet.as_ref()?, opts.calibration.as_ref()?);
        let n = feet.len();
        (n > 0)
            .then(|| feet.values().map(|p| half_width_px(p)).sum::<f64>() / n as f64 * cal.m_per_px)
    }

    /// The intruding pairs' `(foot depth m, added mass kg)`, depth increasing (what
    /// `added_mass.csv` holds and `fit added-mass` reads).
    pub fn added_mass_points(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::new();
        for r in &self.results {
            let r = &r.row;
            let deeper = out.last().is_none_or(|&(z, _)| r.foot_depth_m > z);
            if r.added_mass_kg.is_finite() && r.foot_velocity_m_s < 0.0 && deeper {
                out.push((r.foot_depth_m, r.added_mass_kg));
            }
        }
        out
    }
}

/// Check that `opts` can run on `frames`: at least two frames, the passes fit the frames, the
/// mask has the frames' size, a calibration comes with frame times.
pub fn check(frames: &Frames, opts: &PivOptions) -> Result<(), String> {
    let n = frames.images.len();
    if n < 2 {
        return Err(format!("frames: {n} frame (allowed: at least two)"));
    }
    if frames.numbers.len() != n {
        return Err(format!(
            "frames: {n} images but {} frame numbers (allowed: one number per image)",
            frames.numbers.len()
        ));
    }
    if let Some(t) = &frames.times_s
        && t.len() != n
    {
        return Err(format!(
            "frames: {n} images but {} times (allowed: one time per image)",
            t.len()
        ));
    }
    let (w, h) = frames.size();
    if let Some((k, i)) = frames
        .images
        .iter()
        .enumerate()
        .find(|(_, i)| (i.width, i.height) != (w, h))
    {
        return Err(format!(
            "frames: frame {} is {}x{} pixels, the first {w}x{h} (allowed: one size)",
            frames.numbers[k], i.width, i.height
        ));
    }
    check_config(&opts.piv, w, h).map_err(|e| e.to_string())?;
    if let Some(m) = &opts.static_mask
        && m.len() != w * h
    {
        return Err(format!(
            "the mask holds {} pixels, the frames {w}x{h} (allowed: the frames' size)",
            m.len()
        ));
    }
    if opts.calibration.is_some() && frames.times_s.is_none() {
        return Err(
            "a calibration needs frame times (--fps or --log) to turn displacements into velocities"
                .into(),
        );
    }
    Ok(())
}

/// Every frame pre-processed (with the sequence's background, if asked for).
pub fn prepare(frames: &Frames, pre: &Preprocess) -> Vec<Image> {
    let bg = pre
        .subtract_background
        .then(|| background(&frames.images.iter().collect::<Vec<_>>()))
        .flatten();
    frames
        .images
        .iter()
        .map(|i| apply(pre, i, bg.as_ref(), frames.max_value))
        .collect()
}

/// The pairs of `n` frames: consecutive or A/B, every `every`th.
pub fn frame_pairs(n: usize, pairing: Pairing, every: usize) -> Vec<(usize, usize)> {
    let pairs: Vec<(usize, usize)> = match pairing {
        Pairing::Consecutive => (0..n.saturating_sub(1)).map(|i| (i, i + 1)).collect(),
        Pairing::Ab => (0..n / 2).map(|i| (2 * i, 2 * i + 1)).collect(),
    };
    pairs.into_iter().step_by(every.max(1)).collect()
}

/// The mask of one pair (`w` x `h`, row-major): the static mask and the inside of the foot's
/// outline in either frame. `None` when there is no static mask and the pair's first frame
/// has no outline: a pair whose foot appears only in its second frame is not masked (the
/// rule of `sandjumper piv` since its first version; its figures depend on it).
pub fn pair_mask(
    static_mask: Option<&[bool]>,
    outlines: [Option<&Polygon>; 2],
    (w, h): (usize, usize),
) -> Option<Vec<bool>> {
    if static_mask.is_none() && outlines[0].is_none() {
        return None;
    }
    let mut m = static_mask.map_or_else(|| vec![false; w * h], <[bool]>::to_vec);
    for poly in outlines.into_iter().flatten() {
        // Only the polygon's bounding box can be inside it.
        let (x0, x1, y0, y1) = poly.iter().fold(
            (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
            |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
        );
        let span = |lo: f64, hi: f64, n: usize| {
            (lo.floor().clamp(0.0, n as f64) as usize)
                ..(hi.ceil() + 1.0).clamp(0.0, n as f64) as usize
        };
        for y in span(y0, y1, h) {
            for x in span(x0, x1, w) {
                if inside(poly, x as f64, y as f64) {
                    m[y * w + x] = true;
                }
            }
        }
    }
    Some(m)
}

/// Pair `k` (frames `ia`, `ib` of `frames`, pre-processed in `prepared`): its displacement
/// field, and with a calibration and frame times its SI fields, grain momentum and, when
/// both frames have a foot outline, the foot's depth, velocity and the added mass `P / v`.
pub fn analyse_pair(
    k: usize,
    (ia, ib): (usize, usize),
    frames: &Frames,
    prepared: &[Image],
    opts: &PivOptions,
) -> Result<PairResult, String> {
    let (w, h) = frames.size();
    let (fa, fb) = (frames.numbers[ia], frames.numbers[ib]);
    let outline = |f: u64| opts.feet.as_ref().and_then(|m| m.get(&f));
    let (foot_a, foot_b) = (outline(fa), outline(fb));
    let mask = pair_mask(opts.static_mask.as_deref(), [foot_a, foot_b], (w, h));
    let field = piv_pair(&prepared[ia], &prepared[ib], mask.as_deref(), &opts.piv)
        .map_err(|e| e.to_string())?;
    let (valid, replaced, masked) = field.counts();
    let times = frames.times_s.as_deref();
    let mut row = FlowRow {
        pair: k,
        frame_a: fa,
        frame_b: fb,
        t_s: times.map_or(f64::NAN, |t| 0.5 * (t[ia] + t[ib])),
        foot_depth_m: f64::NAN,
        foot_velocity_m_s: f64::NAN,
        momentum_left_kg_m_s: f64::NAN,
        momentum_right_kg_m_s: f64::NAN,
        momentum_kg_m_s: f64::NAN,
        momentum_under_foot_kg_m_s: f64::NAN,
        added_mass_kg: f64::NAN,
        vectors_valid: valid,
        vectors_replaced: replaced,
        vectors_masked: masked,
    };
    let (Some(cal), Some(t)) = (opts.calibration, times) else {
        return Ok(PairResult {
            field,
            row,
            si: None,
        });
    };
    let dt = t[ib] - t[ia];
    if dt <= 0.0 {
        return Err(format!(
            "frames {fa} and {fb}: the second is not later than the first (dt = {dt} s)"
        ));
    }
    let m: Momentum = grain_momentum(
        &field,
        &cal,
        dt,
        opts.rho_phi_kg_m3,
        mask.as_deref().map(|m| (m, w)),
    );
    row.momentum_left_kg_m_s = m.left_kg_m_s;
    row.momentum_right_kg_m_s = m.right_kg_m_s;
    row.momentum_kg_m_s = m.momentum_kg_m_s;
    if let (Some(pa), Some(pb)) = (foot_a, foot_b) {
        let (da, db) = (foot_depth_m(pa, &cal), foot_depth_m(pb, &cal));
        row.foot_depth_m = 0.5 * (da + db);
        row.foot_velocity_m_s = -(db - da) / dt;
        // The column under the foot: r <= R (the foot's half width), below its bottom.
        let radius_m = 0.5 * (half_width_px(pa) + half_width_px(pb)) * cal.m_per_px;
        let column = column_momentum(
            &field,
            &cal,
            dt,
            opts.rho_phi_kg_m3,
            mask.as_deref().map(|m| (m, w)),
            radius_m,
            -row.foot_depth_m,
        );
        row.momentum_under_foot_kg_m_s = column.momentum_kg_m_s;
        if row.foot_velocity_m_s.abs() > 1e-9 {
            row.added_mass_kg = column.momentum_kg_m_s / row.foot_velocity_m_s;
        }
    }
    let s = cal.m_per_px / dt;
    let spacing = field.step_px as f64 * cal.m_per_px;
    let u = Grid::new(
        field.nx,
        field.ny,
        spacing,
        field.u.iter().map(|u| u * s).collect(),
    );
    let v = Grid::new(
        field.nx,
        field.ny,
        spacing,
        field.v.iter().map(|v| -v * s).collect(),
    );
    let d = derive(&u, &v);
    Ok(PairResult {
        field,
        row,
        si: Some(SiFields {
            u,
            v,
            vorticity: d.vorticity,
            shear_rate: d.shear_rate,
        }),
    })
}

/// The start of the message of a run its caller stopped (Ctrl-C).
pub const INTERRUPTED: &str = "interrupted";

/// Run the whole analysis: check, pre-process, pair, analyse every pair (calling `on_pair`
/// after each, e.g. for a progress bar; it returns false to stop the run, which then ends as
/// [`INTERRUPTED`]).
pub fn run(
    frames: &Frames,
    opts: &PivOptions,
    mut on_pair: impl FnMut() -> bool,
) -> Result<PivRun, String> {
    check(frames, opts)?;
    let prepared = prepare(frames, &opts.preprocess);
    let pairs = frame_pairs(frames.images.len(), opts.pairing, opts.every);
    let mut results = Vec::with_capacity(pairs.len());
    for (k, &pair) in pairs.iter().enumerate() {
        results.push(analyse_pair(k, pair, frames, &prepared, opts)?);
        if !on_pair() {
            return Err(format!(
                "{INTERRUPTED} after {} of {} pairs",
                k + 1,
                pairs.len()
            ));
        }
    }
    apply_speed_threshold(&mut results, opts.min_speed_ratio);
    Ok(PivRun { pairs, results })
}

/// Half the width of a foot outline, px.
pub fn half_width_px(poly: &[(f64, f64)]) -> f64 {
    let (lo, hi) = poly.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p.0), hi.max(p.0))
    });
    if hi > lo { 0.5 * (hi - lo) } else { 0.0 }
}

/// The paper's rule: `m_a` only while the foot intrudes at least `ratio` of its fastest
/// intrusion in the run; other pairs' added mass becomes NaN (their momentum stays).
fn apply_speed_threshold(results: &mut [PairResult], ratio: f64) {
    let v_max = results
        .iter()
        .map(|r| -r.row.foot_velocity_m_s)
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    for r in results.iter_mut() {
        let intruding = -r.row.foot_velocity_m_s;
        if !(intruding.is_finite() && v_max > 0.0 && intruding >= ratio * v_max) {
            r.row.added_mass_kg = f64::NAN;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(sizes: &[(usize, usize)]) -> Frames {
        Frames {
            numbers: (0..sizes.len() as u64).collect(),
            images: sizes
                .iter()
                .map(|&(w, h)| Image {
                    width: w,
                    height: h,
                    data: vec![0.0; w * h],
                })
                .collect(),
            max_value: 255.0,
            times_s: None,
        }
    }

    fn options() -> PivOptions {
        PivOptions {
            piv: PivConfig {
                windows: vec![16],
                ..PivConfig::default()
            },
            preprocess: Preprocess {
                local_contrast_sigma_px: 0.0,
                clahe_tile_px: 0,
                clahe_clip: 0.01,
                subtract_background: false,
                cap_sigma: 0.0,
            },
            pairing: Pairing::Consecutive,
            every: 1,
            calibration: None,
            rho_phi_kg_m3: 570.0,
            static_mask: None,
            feet: None,
            min_speed_ratio: DEFAULT_MIN_SPEED_RATIO,
        }
    }

    #[test]
    fn inconsistent_frames_are_refused_not_indexed() {
        let opts = options();
        assert_eq!(check(&frames(&[(64, 64), (64, 64)]), &opts), Ok(()));
        assert!(
            check(&frames(&[(64, 64)]), &opts)
                .unwrap_err()
                .contains("at least two")
        );
        let mixed = check(&frames(&[(64, 64), (64, 48)]), &opts).unwrap_err();
        assert!(mixed.contains("frame 1 is 64x48"), "{mixed}");
        let mut f = frames(&[(64, 64), (64, 64)]);
        f.numbers.pop();
        assert!(check(&f, &opts).unwrap_err().contains("frame numbers"));
        let mut f = frames(&[(64, 64), (64, 64)]);
        f.times_s = Some(vec![0.0]);
        assert!(check(&f, &opts).unwrap_err().contains("times"));
        let mut cal = options();
        cal.calibration = Some(Calibration {
            m_per_px: 1e-4,
            origin_px: (32.0, 0.0),
        });
        assert!(check(&frames(&[(64, 64), (64, 64)]), &cal).is_err());
    }

    #[test]
    fn pairs_are_consecutive_or_ab_every_nth() {
        assert_eq!(
            frame_pairs(5, Pairing::Consecutive, 1),
            vec![(0, 1), (1, 2), (2, 3), (3, 4)]
        );
        assert_eq!(
            frame_pairs(5, Pairing::Consecutive, 2),
            vec![(0, 1), (2, 3)]
        );
        assert_eq!(frame_pairs(5, Pairing::Ab, 1), vec![(0, 1), (2, 3)]);
        assert_eq!(frame_pairs(1, Pairing::Consecutive, 1), vec![]);
    }

    #[test]
    fn a_pair_mask_covers_the_foot_in_both_frames_and_the_static_mask() {
        assert_eq!(pair_mask(None, [None, None], (4, 4)), None);
        let square: Polygon = vec![(0.5, 0.5), (2.5, 0.5), (2.5, 2.5), (0.5, 2.5)];
        let mut fixed = vec![false; 16];
        fixed[15] = true;
        let m = pair_mask(Some(&fixed), [Some(&square), None], (4, 4)).unwrap();
        assert!(m[15], "the static mask stays");
        assert!(
            m[4 + 1] && m[2 * 4 + 2],
            "the pixels within the square are masked"
        );
        assert!(!m[0] && !m[3 * 4], "outside the square");
        // Without a static mask, the first frame's outline decides whether the pair is masked.
        assert_eq!(pair_mask(None, [None, Some(&square)], (4, 4)), None);
        let both = pair_mask(None, [Some(&square), Some(&square)], (4, 4)).unwrap();
        assert_eq!(both.iter().filter(|&&b| b).count(), 4);
    }

    #[test]
    fn added_mass_points_keep_intruding_pairs_with_growing_depth() {
        let row = |depth: f64, v: f64, ma: f64| PairResult {
            field: VectorField {
                nx: 0,
                ny: 0,
                step_px: 16,
                xs: vec![],
                ys: vec![],
                u: vec![],
                v: vec![],
                flag: vec![],
                peak_ratio: vec![],
            },
            row: FlowRow {
                pair: 0,
                frame_a: 0,
                frame_b: 1,
                t_s: 0.0,
                foot_depth_m: depth,
                foot_velocity_m_s: v,
                momentum_left_kg_m_s: 0.0,
                momentum_right_kg_m_s: 0.0,
                momentum_kg_m_s: 0.0,
                momentum_under_foot_kg_m_s: 0.0,
                added_mass_kg: ma,
                vectors_valid: 0,
                vectors_replaced: 0,
                vectors_masked: 0,
            },
            si: None,
        };
        let run = PivRun {
            pairs: vec![],
            results: vec![
                row(0.001, -0.1, 0.01),
                row(0.002, -0.1, f64::NAN),
                row(0.003, 0.1, 0.02),
                row(0.0025, -0.1, 0.03),
                row(0.0015, -0.1, 0.05),
                row(0.004, -0.1, 0.04),
            ],
        };
        assert_eq!(
            run.added_mass_points(),
            vec![(0.001, 0.01), (0.0025, 0.03), (0.004, 0.04)]
        );
        // The paper's speed rule: below 0.3 of the fastest intrusion (1 m/s here) no added
        // mass; withdrawing pairs none either; the momentum stays.
        let mut results = vec![
            row(0.001, -1.0, 0.01),
            row(0.002, -0.31, 0.02),
            row(0.003, -0.29, 0.03),
            row(0.004, 0.5, 0.04),
        ];
        apply_speed_threshold(&mut results, DEFAULT_MIN_SPEED_RATIO);
        let kept: Vec<bool> = results
            .iter()
            .map(|r| r.row.added_mass_kg.is_finite())
            .collect();
        assert_eq!(kept, [true, true, false, false]);
        apply_speed_threshold(&mut results, 0.0);
        assert!(results[0].row.added_mass_kg.is_finite());
    }

    #[test]
    fn the_column_radius_is_half_the_outlines_width() {
        let square = vec![(10.0, 0.0), (30.0, 0.0), (30.0, 8.0), (10.0, 8.0)];
        assert_eq!(half_width_px(&square), 10.0);
        assert_eq!(half_width_px(&[]), 0.0);
    }
}
