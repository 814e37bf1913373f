//! The baseline: the best single, stutter and delayed stutter at the same ground, limits and
//! objective, found by a sweep over amplitude, frequency and delay. Every point is evaluated
//! as a member of the search's family ([`MoveChain`]), by the same [`Problem::evaluate`], so
//! the comparison is like for like.

use rayon::prelude::*;
use serde::Serialize;

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::trajectory::kind_name;

use crate::evaluate::{Evaluation, Problem};
use crate::family::MoveChain;

/// The sweep's grid.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PaperGrid {
    /// Amplitudes, m.
    pub amplitudes_m: Vec<f64>,
    /// Forcing frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// Delays of the delayed stutter, s.
    pub taus_s: Vec<f64>,
}

impl PaperGrid {
    /// Amplitudes from half the stroke to the stroke in 5 steps (the robot's 18.75 mm among
    /// them when the stroke is 25 mm), 1 to 25 Hz every `df` Hz, delays 0 to `max_tau` every
    /// `dtau` s.
    pub fn standard(stroke_m: f64, df: f64, max_tau_s: f64, dtau: f64) -> Self {
        let steps = |lo: f64, hi: f64, d: f64| -> Vec<f64> {
            let n = ((hi - lo) / d + 1e-9).floor() as usize;
            (0..=n).map(|i| lo + i as f64 * d).collect()
        };
        Self {
            amplitudes_m: (0..5)
                .map(|i| stroke_m * (0.5 + 0.125 * i as f64))
                .collect(),
            freqs_hz: steps(1.0, 25.0, df),
            taus_s: steps(0.0, max_tau_s, dtau),
        }
    }

    /// Points of the grid.
    pub fn len(&self) -> usize {
        self.amplitudes_m.len() * self.freqs_hz.len() * (2 + self.taus_s.len())
    }

    /// Whether the grid is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One of the paper's strokes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PaperStroke {
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Amplitude, m.
    pub amplitude_m: f64,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Delay, s (0 but for the delayed stutter).
    pub tau_s: f64,
}

impl PaperStroke {
    /// As a member of the family with `moves` moves.
    pub fn chain(&self, moves: usize) -> MoveChain {
        match self.kind {
            "single" => MoveChain::single(self.amplitude_m, self.freq_hz, moves),
            "stutter" => MoveChain::stutter(self.amplitude_m, self.freq_hz, moves),
            _ => MoveChain::delayed_stutter(self.amplitude_m, self.freq_hz, self.tau_s, moves),
        }
    }

    /// In words: `delayed stutter, A 18.75 mm, 9.1 Hz, tau 0.12 s`.
    pub fn describe(&self) -> String {
        let base = format!(
            "{}, A {:.2} mm, {:.2} Hz",
            self.kind,
            1e3 * self.amplitude_m,
            self.freq_hz
        );
        if self.kind == "delayed" {
            format!("{base}, tau {:.3} s", self.tau_s)
        } else {
            base
        }
    }
}

/// A swept point and its evaluation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweptPoint {
    /// The stroke.
    pub stroke: PaperStroke,
    /// Its evaluation.
    pub evaluation: Evaluation,
}

/// The sweep's outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperSweep {
    /// Every point, in grid order.
    pub points: Vec<SweptPoint>,
    /// The best feasible point of each kind (single, stutter, delayed), if any is feasible.
    pub best_by_kind: Vec<SweptPoint>,
}

impl PaperSweep {
    /// The best feasible point of all kinds.
    pub fn best(&self) -> Option<&SweptPoint> {
        self.best_by_kind
            .iter()
            .max_by(|a, b| a.evaluation.value.total_cmp(&b.evaluation.value))
    }
}

/// Sweep `grid` under `problem` (in parallel on the current rayon pool), `moves` moves per
/// chain, calling `progress(done)` as points finish; when it returns false no further point
/// starts and the sweep is `None`.
pub fn sweep(
    problem: &Problem,
    grid: &PaperGrid,
    moves: usize,
    progress: &(dyn Fn(usize) -> bool + Sync),
) -> Option<PaperSweep> {
    let mut strokes = Vec::with_capacity(grid.len());
    for kind in [
        JumpKind::Single,
        JumpKind::Stutter,
        JumpKind::DelayedStutter,
    ] {
        for &amplitude_m in &grid.amplitudes_m {
            for &freq_hz in &grid.freqs_hz {
                let taus: &[f64] = if kind == JumpKind::DelayedStutter {
                    &grid.taus_s
                } else {
                    &[0.0]
                };
                for &tau_s in taus {
                    strokes.push(PaperStroke {
                        kind: kind_name(kind),
                        amplitude_m,
                        freq_hz,
                        tau_s,
                    });
                }
            }
        }
    }
    let done = std::sync::atomic::AtomicUsize::new(0);
    let stopped = std::sync::atomic::AtomicBool::new(false);
    let points: Vec<SweptPoint> = strokes
        .par_iter()
        .map(|s| {
            if stopped.load(std::sync::atomic::Ordering::Relaxed) {
                return None;
            }
            let evaluation = problem.evaluate(&s.chain(moves));
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if (n.is_multiple_of(16) || n == strokes.len()) && !progress(n) {
                stopped.store(true, std::sync::atomic::Ordering::Relaxed);
            }
            Some(SweptPoint {
                stroke: *s,
                evaluation,
            })
        })
        .collect::<Option<Vec<_>>>()?;
    if stopped.into_inner() {
        return None;
    }
    let best_by_kind = ["single", "stutter", "delayed"]
        .iter()
        .filter_map(|k| {
            first_best(
                points
                    .iter()
                    .filter(|p| p.stroke.kind == *k && p.evaluation.feasible()),
            )
            .cloned()
        })
        .collect();
    Some(PaperSweep {
        points,
        best_by_kind,
    })
}

/// The point of `points` with the highest value, the first in their order on ties (so a
/// sweep's best does not depend on the threads).
pub fn first_best<'a>(points: impl Iterator<Item = &'a SweptPoint>) -> Option<&'a SweptPoint> {
    points.fold(None, |best, p| match best {
        Some(b) if b.evaluation.value >= p.evaluation.value => Some(b),
        _ => Some(p),
    })
}

/// The paper's strokes of one kind as coordinates for the refinement through the controller:
/// amplitude, frequency and, for the delayed stutter, the delay, each linear over the sweep
/// grid's range and reflected into it (so the refined stroke is still one of the paper's,
/// within the sweep's bounds).
#[derive(Clone, Debug, PartialEq)]
pub struct PaperSpace {
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Amplitudes from, to, m.
    pub amplitude_m: (f64, f64),
    /// Frequencies from, to, Hz.
    pub freq_hz: (f64, f64),
    /// Delays from, to, s.
    pub tau_s: (f64, f64),
}

impl PaperSpace {
    /// The space of `kind` (`single`, `stutter` or `delayed`) over `grid`'s ranges; None for
    /// another kind or a grid with no amplitude, frequency or (for `delayed`) delay.
    pub fn of(kind: &'static str, grid: &PaperGrid) -> Option<Self> {
        let range = |v: &[f64]| {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
        };
        if !["single", "stutter", "delayed"].contains(&kind) {
            return None;
        }
        Some(Self {
            kind,
            amplitude_m: range(&grid.amplitudes_m)?,
            freq_hz: range(&grid.freqs_hz)?,
            tau_s: if kind == "delayed" {
                range(&grid.taus_s)?
            } else {
                (0.0, 0.0)
            },
        })
    }

    /// `s`'s coordinates (`s` of this space's kind, within its ranges).
    pub fn encode(&self, s: &PaperStroke) -> Vec<f64> {
        let unit = |v: f64, (lo, hi): (f64, f64)| {
            if hi > lo {
                ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let mut x = vec![
            unit(s.amplitude_m, self.amplitude_m),
            unit(s.freq_hz, self.freq_hz),
        ];
        if self.kind == "delayed" {
            x.push(unit(s.tau_s, self.tau_s));
        }
        x
    }

    /// The stroke at `x` (any real coordinates, reflected into the ranges; a coordinate
    /// missing is 0, the range's low end).
    pub fn stroke(&self, x: &[f64]) -> PaperStroke {
        let at = |i: usize, (lo, hi): (f64, f64)| {
            lo + (hi - lo) * crate::family::reflect(x.get(i).copied().unwrap_or(0.0))
        };
        PaperStroke {
            kind: self.kind,
            amplitude_m: at(0, self.amplitude_m),
            freq_hz: at(1, self.freq_hz),
            tau_s: if self.kind == "delayed" {
                at(2, self.tau_s)
            } else {
                0.0
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_paper_stroke_is_its_own_point_and_every_point_a_stroke_within_the_grid() {
        let grid = PaperGrid::standard(0.025, 0.5, 0.5, 0.05);
        let space = PaperSpace::of("delayed", &grid).unwrap();
        let s = PaperStroke {
            kind: "delayed",
            amplitude_m: 0.01875,
            freq_hz: 9.5,
            tau_s: 0.2,
        };
        let back = space.stroke(&space.encode(&s));
        assert!((back.amplitude_m - s.amplitude_m).abs() < 1e-15);
        assert!((back.freq_hz - s.freq_hz).abs() < 1e-12);
        assert!((back.tau_s - s.tau_s).abs() < 1e-15);
        let far = space.stroke(&[1.3, -0.2, 2.5]);
        assert!((far.amplitude_m - (0.0125 + 0.7 * 0.0125)).abs() < 1e-12);
        assert!((far.freq_hz - (1.0 + 0.2 * 24.0)).abs() < 1e-9);
        assert!((far.tau_s - 0.25).abs() < 1e-12);
        let single = PaperSpace::of("single", &grid).unwrap();
        assert_eq!(single.stroke(&[]).freq_hz, 1.0);
        assert!(PaperSpace::of("Delayed", &grid).is_none());
        let no_taus = PaperGrid {
            taus_s: Vec::new(),
            ..grid.clone()
        };
        assert!(PaperSpace::of("delayed", &no_taus).is_none());
        assert!(PaperSpace::of("single", &no_taus).is_some());
        assert_eq!(
            single
                .encode(&PaperStroke {
                    kind: "single",
                    tau_s: 0.0,
                    ..s
                })
                .len(),
            2
        );
        assert_eq!(single.stroke(&[0.5, 0.5]).tau_s, 0.0);
    }
}
