//! The stroke family searched: a chain of rest-to-rest cosine moves with holds between them.
//!
//! The motor starts at rest at `p = start_m`; move `i` goes from the previous position to
//! `to_m` in `duration_s` along a half cosine,
//! `p(t) = c + r cos(pi (t - t0) / d)`, `c` the mid-point and `r` half the signed distance
//! (zero velocity at both ends, acceleration `r (pi / d)^2` at the ends), then holds for
//! `hold_s`; after the last move the motor holds its position. A move to where the motor
//! already is takes no time (its hold still does). The paper's three strokes are
//! members, exactly:
//! - single, `p = -A cos(2 pi f t)`: from `-A` to `+A` in `T/2`, back to `-A` in `T/2`;
//! - stutter, `p = +A cos(2 pi f t)`: from `+A` to `-A` in `T/2`, back to `+A` in `T/2`;
//! - delayed stutter: the stutter with a hold of `tau` at `-A` between its halves.
//!
//! With four moves (the default) the family also holds multi-hop strokes, pre-compaction
//! pushes, partial strokes, asymmetric speeds (a slow descent, a fast push) and pauses
//! anywhere.
//!
//! [`Encoding`] maps a point of the optimiser's unbounded space onto a chain within the
//! bounds (each coordinate reflected into `[0, 1]`): positions linear over the stroke,
//! durations logarithmic between the fastest move the drive allows for that distance and
//! the longest allowed, holds linear.

use sandjumper_core::trajectory::Kinematics;
use sandjumper_model::trajectory::{CosinePiece, Stroke};
use serde::{Deserialize, Serialize};

/// One rest-to-rest move and the hold after it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Move {
    /// Target position, m.
    pub to_m: f64,
    /// Duration of the move, s (> 0).
    pub duration_s: f64,
    /// Hold at the target before the next move, s (>= 0; unused after the last move).
    pub hold_s: f64,
}

/// A chain of moves from rest at `start_m` (see the module's documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveChain {
    /// Position at rest before the first move, m.
    pub start_m: f64,
    /// The moves, in order.
    pub moves: Vec<Move>,
}

/// A [`MoveChain`] as a prescribed stroke: its cosine pieces and holds, in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainStroke {
    pieces: Vec<CosinePiece>,
    start_m: f64,
    end_s: f64,
    push_off_start_s: f64,
}

impl MoveChain {
    /// The paper's single jump of amplitude `a` at `f` Hz, padded with null moves to `moves`.
    pub fn single(a: f64, f: f64, moves: usize) -> Self {
        Self::padded(-a, &[(a, 0.5 / f, 0.0), (-a, 0.5 / f, 0.0)], moves)
    }

    /// The paper's stutter.
    pub fn stutter(a: f64, f: f64, moves: usize) -> Self {
        Self::padded(a, &[(-a, 0.5 / f, 0.0), (a, 0.5 / f, 0.0)], moves)
    }

    /// The paper's delayed stutter with delay `tau` s.
    pub fn delayed_stutter(a: f64, f: f64, tau: f64, moves: usize) -> Self {
        Self::padded(a, &[(-a, 0.5 / f, tau), (a, 0.5 / f, 0.0)], moves)
    }

    /// `start` then `moves` `(to, duration, hold)`, then null moves (staying put) up to `n`.
    fn padded(start: f64, moves: &[(f64, f64, f64)], n: usize) -> Self {
        Self {
            start_m: start,
            moves: moves
                .iter()
                .map(|&(to_m, duration_s, hold_s)| Move {
                    to_m,
                    duration_s,
                    hold_s,
                })
                .collect(),
        }
        .padded_to(n)
    }

    /// This chain with null moves (staying put) appended up to `n` moves.
    pub fn padded_to(mut self, n: usize) -> Self {
        let last = self.moves.last().map_or(self.start_m, |m| m.to_m);
        while self.moves.len() < n {
            self.moves.push(Move {
                to_m: last,
                duration_s: NULL_MOVE_S,
                hold_s: 0.0,
            });
        }
        self
    }

    /// Time from the start to the end of the last move, s (the final hold excluded).
    pub fn duration_s(&self) -> f64 {
        self.stroke().end_s
    }

    /// The chain as a stroke the plant can be driven by. Moves of zero length become holds.
    pub fn stroke(&self) -> ChainStroke {
        let mut pieces = Vec::with_capacity(2 * self.moves.len());
        let (mut t, mut p) = (0.0, self.start_m);
        let n = self.moves.len();
        // Start of the final rise: the first of the last run of rising moves with no hold
        // between them (see `TableStroke`'s push-off).
        let mut rise_start = 0.0;
        let mut rising_since: Option<f64> = None;
        for (i, m) in self.moves.iter().enumerate() {
            if m.to_m != p {
                let end = t + m.duration_s;
                let (c, r) = (0.5 * (p + m.to_m), 0.5 * (p - m.to_m));
                pieces.push(CosinePiece {
                    start_s: t,
                    end_s: end,
                    amplitude_m: r,
                    angular_freq_rad_s: core::f64::consts::PI / m.duration_s,
                    phase_origin_s: t,
                    offset_m: c,
                });
                if m.to_m > p {
                    let since = *rising_since.get_or_insert(t);
                    rise_start = since;
                } else {
                    rising_since = None;
                }
                t = end;
            }
            p = m.to_m;
            if i + 1 < n && m.hold_s > 0.0 {
                pieces.push(CosinePiece::hold(t, t + m.hold_s, p));
                t += m.hold_s;
                rising_since = None;
            }
        }
        ChainStroke {
            pieces,
            start_m: self.start_m,
            end_s: t,
            push_off_start_s: rise_start,
        }
    }

    /// Positions at `t = k / rate_hz` from 0 to the end of the last move (inclusive, the
    /// final hold's first sample), m.
    pub fn samples(&self, rate_hz: u32) -> Vec<f64> {
        let stroke = self.stroke();
        let rate = f64::from(rate_hz);
        let n = (stroke.end_s * rate).ceil() as usize + 1;
        (0..n)
            .map(|k| stroke.eval(k as f64 / rate).position_m)
            .collect()
    }
}

/// Duration given to a null move (a move that stays put) by the paper's strokes' padding, s.
pub const NULL_MOVE_S: f64 = 0.01;

impl ChainStroke {
    fn piece_at(&self, t_s: f64) -> Option<&CosinePiece> {
        let i = self.pieces.partition_point(|p| p.end_s <= t_s);
        self.pieces.get(i).filter(|p| p.contains(t_s))
    }

    fn final_position_m(&self) -> f64 {
        self.pieces
            .last()
            .map_or(self.start_m, |p| p.eval(p.end_s).position_m)
    }
}

impl Stroke for ChainStroke {
    fn eval(&self, t_s: f64) -> Kinematics {
        let hold = |p| Kinematics {
            position_m: p,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        };
        if t_s.is_nan() || t_s < 0.0 {
            return hold(self.start_m);
        }
        match self.piece_at(t_s) {
            Some(p) => p.eval(t_s),
            None => hold(self.final_position_m()),
        }
    }

    fn breakpoints_s(&self) -> Vec<f64> {
        self.pieces
            .iter()
            .map(|p| p.end_s)
            .filter(|&t| t > 0.0)
            .collect()
    }

    fn end_s(&self) -> f64 {
        self.end_s
    }

    fn push_off_start_s(&self) -> f64 {
        self.push_off_start_s
    }

    fn cosine_piece(&self, t_s: f64) -> Option<CosinePiece> {
        if t_s.is_nan() || t_s < 0.0 {
            return Some(CosinePiece::hold(
                f64::NEG_INFINITY,
                self.pieces.first().map_or(f64::INFINITY, |p| p.start_s),
                self.start_m,
            ));
        }
        match self.piece_at(t_s) {
            Some(p) => Some(*p),
            None => Some(CosinePiece::hold(
                self.end_s,
                f64::INFINITY,
                self.final_position_m(),
            )),
        }
    }
}

/// The map from the optimiser's space (`3 n` coordinates for `n` moves) onto chains within
/// the bounds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Encoding {
    /// Moves per chain.
    pub moves: usize,
    /// Largest |p|, m.
    pub stroke_m: f64,
    /// Largest |p''| of a move, m/s^2: the fastest move over a distance `D` takes
    /// `pi sqrt(D / (2 a))`.
    pub max_accel_m_s2: f64,
    /// Shortest move, s (small moves are not faster than this).
    pub min_move_s: f64,
    /// Longest move, s.
    pub max_move_s: f64,
    /// Longest hold between moves, s.
    pub max_hold_s: f64,
}

/// `x` reflected into `[0, 1]` (a triangle wave of period 2).
pub fn reflect(x: f64) -> f64 {
    let y = x.rem_euclid(2.0);
    if y > 1.0 { 2.0 - y } else { y }
}

impl Encoding {
    /// Coordinates of the optimiser's space.
    pub fn dim(&self) -> usize {
        3 * self.moves
    }

    /// The shortest duration of a move over `distance_m`, s.
    pub fn fastest_move_s(&self, distance_m: f64) -> f64 {
        let d = core::f64::consts::PI * (distance_m.abs() / (2.0 * self.max_accel_m_s2)).sqrt();
        d.max(self.min_move_s).min(self.max_move_s)
    }

    /// The chain at `x` (any real coordinates; `x.len() == dim()`). Layout: `start`, then per
    /// move `to`, `duration`, `hold` (the last move's hold is the last coordinate's only
    /// unused reading: it is kept for a uniform layout and ignored).
    pub fn decode(&self, x: &[f64]) -> MoveChain {
        let pos = |u: f64| self.stroke_m * (2.0 * reflect(u) - 1.0);
        let start_m = pos(x[0]);
        let mut p = start_m;
        let mut moves = Vec::with_capacity(self.moves);
        for i in 0..self.moves {
            let to_m = pos(x[1 + 3 * i]);
            let lo = self.fastest_move_s(to_m - p);
            let u = reflect(x[2 + 3 * i]);
            let duration_s = lo * (self.max_move_s / lo).powf(u);
            let hold_s = if i + 1 < self.moves {
                self.max_hold_s * reflect(x.get(3 + 3 * i).copied().unwrap_or(0.0))
            } else {
                0.0
            };
            moves.push(Move {
                to_m,
                duration_s,
                hold_s,
            });
            p = to_m;
        }
        MoveChain { start_m, moves }
    }

    /// Coordinates in `[0, 1]` that decode to `chain` (clamped into the bounds), the inverse
    /// of [`decode`](Self::decode). The chain's moves are truncated or padded with null moves
    /// to [`moves`](Self::moves).
    pub fn encode(&self, chain: &MoveChain) -> Vec<f64> {
        let unpos = |q: f64| ((q / self.stroke_m + 1.0) * 0.5).clamp(0.0, 1.0);
        let mut x = vec![0.0; self.dim()];
        x[0] = unpos(chain.start_m);
        let mut p = chain.start_m;
        for i in 0..self.moves {
            let m = chain.moves.get(i).copied().unwrap_or(Move {
                to_m: p,
                duration_s: NULL_MOVE_S,
                hold_s: 0.0,
            });
            x[1 + 3 * i] = unpos(m.to_m);
            let q = self.stroke_m * (2.0 * x[1 + 3 * i] - 1.0);
            let lo = self.fastest_move_s(q - p);
            x[2 + 3 * i] = if self.max_move_s > lo {
                ((m.duration_s.clamp(lo, self.max_move_s) / lo).ln() / (self.max_move_s / lo).ln())
                    .clamp(0.0, 1.0)
            } else {
                0.0
            };
            if i + 1 < self.moves {
                x[3 + 3 * i] = if self.max_hold_s > 0.0 {
                    (m.hold_s / self.max_hold_s).clamp(0.0, 1.0)
                } else {
                    0.0
                };
            }
            p = q;
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_core::trajectory::{JumpKind, SineJump};

    fn encoding() -> Encoding {
        Encoding {
            moves: 4,
            stroke_m: 0.025,
            max_accel_m_s2: 256.9,
            min_move_s: 0.004,
            max_move_s: 0.5,
            max_hold_s: 0.5,
        }
    }

    #[test]
    fn the_papers_strokes_are_members_exactly() {
        let cases = [
            (JumpKind::Single, 0.01875, 11.0, 0.0),
            (JumpKind::Stutter, 0.02, 13.0, 0.0),
            (JumpKind::DelayedStutter, 0.01875, 9.0, 0.21),
        ];
        for (kind, a, f, tau) in cases {
            let sine = SineJump::new(kind, a, f, tau).unwrap();
            let chain = match kind {
                JumpKind::Single => MoveChain::single(a, f, 4),
                JumpKind::Stutter => MoveChain::stutter(a, f, 4),
                JumpKind::DelayedStutter => MoveChain::delayed_stutter(a, f, tau, 4),
            };
            let stroke = chain.stroke();
            assert!((stroke.end_s() - sine.end_s()).abs() < 1e-12);
            assert!((stroke.push_off_start_s() - sine.push_off_start_s()).abs() < 1e-12);
            for k in -5..3000 {
                let t = k as f64 * 1e-4;
                let (c, s) = (Stroke::eval(&stroke, t), sine.eval(t));
                let w = core::f64::consts::TAU * f;
                assert!((c.position_m - s.position_m).abs() < 1e-15, "{kind:?} {t}");
                assert!((c.velocity_m_s - s.velocity_m_s).abs() < 1e-13 * w);
                assert!(
                    (c.accel_m_s2 - s.accel_m_s2).abs() < 1e-11 * w * w,
                    "{kind:?} {t}"
                );
                // The closed-form piece agrees with eval.
                let piece = stroke.cosine_piece(t).unwrap();
                assert!(piece.contains(t) || t < 0.0);
                assert!((piece.eval(t).position_m - c.position_m).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn encode_then_decode_is_the_identity_within_the_bounds() {
        let e = encoding();
        let chain = MoveChain::delayed_stutter(0.01875, 9.0, 0.21, 4);
        let back = e.decode(&e.encode(&chain));
        assert!((back.start_m - chain.start_m).abs() < 1e-15);
        for (a, b) in back.moves.iter().zip(&chain.moves) {
            assert!((a.to_m - b.to_m).abs() < 1e-15);
            assert!((a.duration_s - b.duration_s).abs() < 1e-12, "{a:?} {b:?}");
        }
        assert!((back.moves[0].hold_s - 0.21).abs() < 1e-12);
    }

    #[test]
    fn every_point_decodes_within_the_bounds() {
        let e = encoding();
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 20.0
        };
        for _ in 0..2000 {
            let x: Vec<f64> = (0..e.dim()).map(|_| next()).collect();
            let c = e.decode(&x);
            assert!(c.start_m.abs() <= e.stroke_m);
            let mut p = c.start_m;
            for m in &c.moves {
                assert!(m.to_m.abs() <= e.stroke_m);
                assert!(m.duration_s >= e.fastest_move_s(m.to_m - p) * (1.0 - 1e-12));
                assert!(m.duration_s <= e.max_move_s * (1.0 + 1e-12));
                assert!((0.0..=e.max_hold_s).contains(&m.hold_s));
                // The move's peak acceleration stays within the bound.
                let peak =
                    0.5 * (m.to_m - p).abs() * (core::f64::consts::PI / m.duration_s).powi(2);
                assert!(peak <= e.max_accel_m_s2 * (1.0 + 1e-9), "{peak}");
                p = m.to_m;
            }
        }
        assert_eq!(reflect(1.5), 0.5);
        assert_eq!(reflect(-0.25), 0.25);
    }
}
