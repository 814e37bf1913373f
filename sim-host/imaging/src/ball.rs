//! Finding the ball (a bright disc on a darker background) in a frame and measuring its centre
//! to sub-pixel precision.
//!
//! **Detection** works on block means (blocks of about a sixth of the ball's radius): the
//! background level and its noise come from the median and the median absolute deviation of
//! the blocks, blocks brighter than the background by 40 % of the brightest block's contrast
//! form connected objects, and an object is ball-sized when its area is between a quarter and
//! four times the disc's (motion blur stretches it, the frame's edge cuts it).
//!
//! **Centre: intensity-weighted centroid after removing a local background plane**, iterated.
//! A box around the ball (its radius plus a margin, taller by the blur streak) is re-centred on
//! the estimate three times; a plane `a + b x + c y` is fitted to a 4 px ring of pixels around
//! the box and subtracted, and every pixel of the box counts with its full background-free
//! value, negative noise included. No threshold is applied inside the box, so the estimator
//! has no pixel locking, and the plane removes the uneven light's tilt that would otherwise
//! pull the centroid. Why not a Gaussian or radial-symmetry fit: those are built for spots a
//! few pixels wide; the ball here is a ~95 px flat-topped disc, often smeared by motion, whose
//! centroid over ~7,000 pixels already averages the noise down to a few thousandths of a
//! pixel, and stays right for a blurred streak (its centroid is the mean position over the
//! exposure), where a disc model would not fit.

use super::frame::{GrayFrame, Roi};

/// What a frame's measurement came to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FixStatus {
    /// Measured.
    Ok,
    /// No ball-sized bright object (where it was expected).
    Missing,
    /// The ball touches the edge of the frame (or region): its centroid would be biased.
    Clipped,
    /// More than one ball-sized object could be the ball.
    Ambiguous,
}

impl FixStatus {
    /// Name as written in `track.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::Missing => "missing",
            Self::Clipped => "clipped",
            Self::Ambiguous => "ambiguous",
        }
    }
}

/// The ball in one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct BallFix {
    /// Outcome.
    pub status: FixStatus,
    /// Centre, px (frame coordinates; NaN unless `status` is `Ok`).
    pub x_px: f64,
    /// Centre, px, `y` growing downward.
    pub y_px: f64,
    /// Why the frame is flagged (empty when `Ok`).
    pub reason: String,
}

impl BallFix {
    fn flagged(status: FixStatus, reason: String) -> Self {
        Self {
            status,
            x_px: f64::NAN,
            y_px: f64::NAN,
            reason,
        }
    }
}

/// A bright, ball-sized object found by the block search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// Coarse centre, px.
    pub x_px: f64,
    /// Coarse centre, px.
    pub y_px: f64,
    /// Area above the detection threshold, px^2.
    pub area_px2: f64,
    /// Extent, px: `(x0, y0, x1, y1)`, end exclusive.
    pub bbox: (u32, u32, u32, u32),
}

/// Ring of background pixels around the centroid box, px.
const RING_PX: u32 = 4;
/// Re-centring passes of the centroid box.
const PASSES: usize = 3;

/// Finds the ball of a known size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BallFinder {
    /// Ball radius, px.
    pub radius_px: f64,
}

impl BallFinder {
    /// A finder for a ball `diameter_m` across at `m_per_px`.
    pub fn new(diameter_m: f64, m_per_px: f64) -> Self {
        Self {
            radius_px: 0.5 * diameter_m / m_per_px,
        }
    }

    fn block(&self) -> u32 {
        ((self.radius_px / 6.0).floor() as u32).clamp(1, 8)
    }

    /// Ball-sized bright objects inside `window`; or why there are none.
    pub fn candidates(&self, frame: &GrayFrame, window: Roi) -> Result<Vec<Candidate>, String> {
        let b = self.block();
        let (nx, ny) = (window.width / b, window.height / b);
        if nx < 3 || ny < 3 {
            return Err(format!(
                "search window {}x{} px is too small for a ball {:.0} px across",
                window.width,
                window.height,
                2.0 * self.radius_px
            ));
        }
        let mut means = vec![0.0_f32; (nx * ny) as usize];
        let mut row = Vec::with_capacity((nx * b) as usize);
        let inv = 1.0 / (b * b) as f32;
        for by in 0..ny {
            let cells = &mut means[(by * nx) as usize..((by + 1) * nx) as usize];
            for dy in 0..b {
                frame.row_into(
                    window.y + by * b + dy,
                    window.x,
                    window.x + nx * b,
                    &mut row,
                );
                for (cell, chunk) in cells.iter_mut().zip(row.chunks_exact(b as usize)) {
                    *cell += chunk.iter().sum::<f32>();
                }
            }
            for c in cells.iter_mut() {
                *c *= inv;
            }
        }
        let mut sorted = means.clone();
        let mid = sorted.len() / 2;
        let (_, &mut background, _) = sorted.select_nth_unstable_by(mid, f32::total_cmp);
        let mut dev: Vec<f32> = means.iter().map(|m| (m - background).abs()).collect();
        let (_, &mut mad, _) = dev.select_nth_unstable_by(mid, f32::total_cmp);
        let noise = 1.4826 * mad;
        let peak = means.iter().copied().fold(f32::MIN, f32::max);
        let contrast = peak - background;
        let floor = frame.depth().max_value() * (4.0 / 255.0);
        if contrast < (8.0 * noise).max(floor) {
            return Err(format!(
                "no bright object: brightest block {contrast:.1} above the background ({background:.1}), noise {noise:.2}"
            ));
        }
        let threshold = background + 0.4 * contrast;
        let disc = core::f64::consts::PI * self.radius_px * self.radius_px;
        let mut label = vec![false; means.len()];
        let mut out = Vec::new();
        let mut rejected: Vec<String> = Vec::new();
        let mut stack = Vec::new();
        for start in 0..means.len() {
            if label[start] || means[start] < threshold {
                continue;
            }
            label[start] = true;
            stack.push(start);
            let (mut n, mut sx, mut sy) = (0_u64, 0.0_f64, 0.0_f64);
            let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
            while let Some(i) = stack.pop() {
                let (bx, by) = (i as u32 % nx, i as u32 / nx);
                n += 1;
                sx += f64::from(bx);
                sy += f64::from(by);
                (x0, y0, x1, y1) = (x0.min(bx), y0.min(by), x1.max(bx), y1.max(by));
                let mut visit = |j: usize| {
                    if !label[j] && means[j] >= threshold {
                        label[j] = true;
                        stack.push(j);
                    }
                };
                if bx > 0 {
                    visit(i - 1);
                }
                if bx + 1 < nx {
                    visit(i + 1);
                }
                if by > 0 {
                    visit(i - nx as usize);
                }
                if by + 1 < ny {
                    visit(i + nx as usize);
                }
            }
            let area = n as f64 * f64::from(b * b);
            // Block k covers pixels k b ..= k b + b - 1, centred at k b + (b - 1) / 2 (pixel
            // (row i, column j) centred at x = j, y = i).
            let (cx, cy) = (
                f64::from(window.x) + (sx / n as f64 + 0.5) * f64::from(b) - 0.5,
                f64::from(window.y) + (sy / n as f64 + 0.5) * f64::from(b) - 0.5,
            );
            if area < 0.25 * disc || area > 4.0 * disc {
                if area >= 0.05 * disc {
                    rejected.push(format!("{area:.0} px^2 at ({cx:.0}, {cy:.0})"));
                }
                continue;
            }
            out.push(Candidate {
                x_px: cx,
                y_px: cy,
                area_px2: area,
                bbox: (
                    window.x + x0 * b,
                    window.y + y0 * b,
                    window.x + (x1 + 1) * b,
                    window.y + (y1 + 1) * b,
                ),
            });
        }
        if out.is_empty() {
            return Err(if rejected.is_empty() {
                "no ball-sized bright object".into()
            } else {
                format!(
                    "no ball-sized bright object (ball ~{disc:.0} px^2; bright objects of {})",
                    rejected.join(", ")
                )
            });
        }
        Ok(out)
    }

    /// The sub-pixel centre of `candidate`, measured inside `region` (the frame or the
    /// region of interest): `Err` with the reason when the ball is clipped by its edge.
    pub fn refine(
        &self,
        frame: &GrayFrame,
        region: Roi,
        candidate: &Candidate,
    ) -> Result<(f64, f64), String> {
        let r = self.radius_px;
        let b = f64::from(self.block());
        let (bw, bh) = (
            f64::from(candidate.bbox.2 - candidate.bbox.0),
            f64::from(candidate.bbox.3 - candidate.bbox.1),
        );
        let streak = (bh - bw).max(0.0) + b;
        let pad = 3.0 + b;
        let (hw, hh) = (r + pad, r + pad + 0.5 * streak);
        let (rx0, ry0) = (f64::from(region.x), f64::from(region.y));
        let (rx1, ry1) = (
            rx0 + f64::from(region.width),
            ry0 + f64::from(region.height),
        );
        let (mut cx, mut cy) = (candidate.x_px, candidate.y_px);
        for _ in 0..PASSES {
            // Bounds in pixel-edge coordinates (pixel k spans k - 0.5 .. k + 0.5 around its
            // centre k): the estimate's edge position is its centre plus half a pixel.
            let (ex, ey) = (cx + 0.5, cy + 0.5);
            // The ball itself (radius plus the streak) must lie inside the region.
            let half_ball_h = r + 0.5 * (streak - b) + 1.0;
            if ex - r - 1.0 < rx0
                || ex + r + 1.0 > rx1
                || ey - half_ball_h < ry0
                || ey + half_ball_h > ry1
            {
                return Err(format!(
                    "the ball (centre near ({cx:.0}, {cy:.0}), radius {r:.0} px) touches the edge of the {}x{} region at ({}, {})",
                    region.width, region.height, region.x, region.y
                ));
            }
            let clamp_x = |v: f64| v.clamp(rx0, rx1) as u32;
            let clamp_y = |v: f64| v.clamp(ry0, ry1) as u32;
            let (x0, x1) = (clamp_x((ex - hw).floor()), clamp_x((ex + hw).ceil()));
            let (y0, y1) = (clamp_y((ey - hh).floor()), clamp_y((ey + hh).ceil()));
            let ring = f64::from(RING_PX);
            let (ex0, ex1) = (
                clamp_x((ex - hw).floor() - ring),
                clamp_x((ex + hw).ceil() + ring),
            );
            let (ey0, ey1) = (
                clamp_y((ey - hh).floor() - ring),
                clamp_y((ey + hh).ceil() + ring),
            );
            // Background plane a + b u + c v on the ring (u, v relative to the estimate).
            let mut m = [[0.0_f64; 3]; 3];
            let mut rhs = [0.0_f64; 3];
            let mut row = Vec::new();
            for y in ey0..ey1 {
                frame.row_into(y, ex0, ex1, &mut row);
                let v = f64::from(y) - cy;
                let inside_rows = y >= y0 && y < y1;
                for (k, &val) in row.iter().enumerate() {
                    let x = ex0 + k as u32;
                    if inside_rows && x >= x0 && x < x1 {
                        continue;
                    }
                    let u = f64::from(x) - cx;
                    let basis = [1.0, u, v];
                    for i in 0..3 {
                        for j in 0..3 {
                            m[i][j] += basis[i] * basis[j];
                        }
                        rhs[i] += basis[i] * f64::from(val);
                    }
                }
            }
            let plane = solve3(m, rhs).ok_or_else(|| {
                format!("no background around the ball near ({cx:.0}, {cy:.0}) to measure against")
            })?;
            let (mut sw, mut su, mut sv) = (0.0_f64, 0.0_f64, 0.0_f64);
            for y in y0..y1 {
                frame.row_into(y, x0, x1, &mut row);
                let v = f64::from(y) - cy;
                let base = plane[0] + plane[2] * v;
                let (mut rw, mut ru) = (0.0_f64, 0.0_f64);
                for (k, &val) in row.iter().enumerate() {
                    let u = f64::from(x0 + k as u32) - cx;
                    let wgt = f64::from(val) - base - plane[1] * u;
                    rw += wgt;
                    ru += wgt * u;
                }
                sw += rw;
                su += ru;
                sv += rw * v;
            }
            if sw <= 0.0 {
                return Err(format!(
                    "no light above the background near ({cx:.0}, {cy:.0})"
                ));
            }
            let (dx, dy) = (su / sw, sv / sw);
            cx += dx;
            cy += dy;
            if dx.abs() < 1e-4 && dy.abs() < 1e-4 {
                break;
            }
        }
        Ok((cx, cy))
    }

    /// Find and measure the ball in `region` of `frame`. With `prediction` (where the ball
    /// should be, px), only objects within `gate_px` of it count, and the search is limited to
    /// rows near it.
    pub fn find(
        &self,
        frame: &GrayFrame,
        region: Roi,
        prediction: Option<(f64, f64)>,
        gate_px: f64,
    ) -> BallFix {
        let window = match prediction {
            Some((_, py)) => {
                let reach = gate_px + 2.5 * self.radius_px;
                let top = (py - reach).floor().max(f64::from(region.y)) as u32;
                let bottom = ((py + reach).ceil() as u32).min(region.y + region.height);
                if bottom <= top + 2 {
                    region
                } else {
                    Roi {
                        x: region.x,
                        y: top,
                        width: region.width,
                        height: bottom - top,
                    }
                }
            }
            None => region,
        };
        let candidates = match self.candidates(frame, window) {
            Ok(c) => c,
            Err(reason) => {
                let reason = match prediction {
                    Some(p) => format!(
                        "{reason} in rows {}..{} around the predicted position ({:.0}, {:.0})",
                        window.y,
                        window.y + window.height,
                        p.0,
                        p.1
                    ),
                    None => reason,
                };
                return BallFix::flagged(FixStatus::Missing, reason);
            }
        };
        let chosen = match prediction {
            Some(p) => {
                let mut near: Vec<(f64, &Candidate)> = candidates
                    .iter()
                    .map(|c| ((c.x_px - p.0).hypot(c.y_px - p.1), c))
                    .filter(|(d, _)| *d <= gate_px)
                    .collect();
                near.sort_by(|a, b| a.0.total_cmp(&b.0));
                match near.as_slice() {
                    [] => {
                        return BallFix::flagged(
                            FixStatus::Missing,
                            format!(
                                "no ball-sized bright object within {gate_px:.0} px of the predicted position ({:.0}, {:.0})",
                                p.0, p.1
                            ),
                        );
                    }
                    [(d1, c1), (d2, c2), ..] if d2 - d1 < self.radius_px => {
                        return BallFix::flagged(
                            FixStatus::Ambiguous,
                            format!(
                                "two ball-sized objects near the predicted position: ({:.0}, {:.0}) and ({:.0}, {:.0})",
                                c1.x_px, c1.y_px, c2.x_px, c2.y_px
                            ),
                        );
                    }
                    [(_, c), ..] => **c,
                }
            }
            None => match candidates.as_slice() {
                [c] => *c,
                many => {
                    let at: Vec<String> = many
                        .iter()
                        .map(|c| format!("({:.0}, {:.0})", c.x_px, c.y_px))
                        .collect();
                    return BallFix::flagged(
                        FixStatus::Ambiguous,
                        format!(
                            "{} ball-sized bright objects, at {}: narrow the search with --roi",
                            many.len(),
                            at.join(", ")
                        ),
                    );
                }
            },
        };
        match self.refine(frame, region, &chosen) {
            Ok((x, y)) => BallFix {
                status: FixStatus::Ok,
                x_px: x,
                y_px: y,
                reason: String::new(),
            },
            Err(reason) => BallFix::flagged(FixStatus::Clipped, reason),
        }
    }
}

/// Solve a 3 x 3 linear system (normal equations); `None` when singular.
pub fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let a = nalgebra::Matrix3::from_fn(|i, j| m[i][j]);
    let x = a.lu().solve(&nalgebra::Vector3::from(r))?;
    x.iter().all(|v| v.is_finite()).then(|| [x[0], x[1], x[2]])
}
