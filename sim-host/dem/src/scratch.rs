//! The step's reusable buffers: force accumulators, the per-grain forces on the intruder and
//! the floor, and the copy of the cross pairs taken before each step.

use super::grains::{NEAR_WALL, PRESCRIBED};

/// Force accumulators reused from step to step: per grain (zero between steps), the
/// per-grain forces on the intruder and the floor that the step's sums add up in slot
/// order, and the copy of the grains and slip histories of the cross pairs taken before
/// each step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scratch {
    pub(super) fx: Vec<f64>,
    pub(super) fy: Vec<f64>,
    pub(super) ft: Vec<f64>,
    /// Force of the grains on each intruder grain, N (x, y).
    pub(super) out_x: Vec<f64>,
    pub(super) out_y: Vec<f64>,
    /// Force of each grain on the floor, N.
    pub(super) out_floor: Vec<f64>,
    /// Slots of the intruder grains and of the grains near a wall, increasing.
    pub(super) prescribed: Vec<u32>,
    pub(super) near_wall: Vec<u32>,
    /// Where each chunk's grains start in `prescribed` and in `near_wall` (one more entry
    /// than the chunks, the last the list's length).
    pub(super) prescribed_at: Vec<usize>,
    pub(super) near_wall_at: Vec<usize>,
    /// The step's forces on the intruder grains (`out_x`, `out_y` of `prescribed`'s slots)
    /// and on the floor (`out_floor` of `near_wall`'s), N, packed side by side by the chunk
    /// that owns them, so the sums after the step read a few cache lines from another
    /// core, not one per grain.
    pub(super) packed_intruder: Vec<[f64; 2]>,
    pub(super) packed_floor: Vec<f64>,
    /// Before the step, the grains of every chunk boundary's cross pairs (slots
    /// `cross_lo[k]..cross_hi[k]` of the list, boundary after boundary): position, m;
    /// velocity the forces see, m/s; spin, rad/s (0 without friction).
    pub(super) snap: Vec<[f64; 5]>,
    /// Before the step, the slip histories of the entries of every boundary's owners, m
    /// (empty without friction).
    pub(super) snap_hist: Vec<f64>,
}

impl Scratch {
    /// Sized for grains of the classes `class` ([`super::world::INTERIOR`] and the others)
    /// in chunks starting at the slots `chunk_start` (the list's), zeroed (`friction`: with
    /// the tangential sums).
    pub fn sized(class: &[u8], chunk_start: &[u32], friction: bool) -> Self {
        let n = class.len();
        let t = |len| if friction { vec![0.0; len] } else { Vec::new() };
        let slots = |c: u8| {
            (0..n as u32)
                .filter(|&i| class[i as usize] == c)
                .collect::<Vec<u32>>()
        };
        let (prescribed, near_wall) = (slots(PRESCRIBED), slots(NEAR_WALL));
        let at = |list: &[u32]| -> Vec<usize> {
            chunk_start
                .iter()
                .map(|&c| list.partition_point(|&i| i < c))
                .collect()
        };
        Self {
            prescribed_at: at(&prescribed),
            near_wall_at: at(&near_wall),
            fx: vec![0.0; n],
            fy: vec![0.0; n],
            ft: t(n),
            out_x: vec![0.0; n],
            out_y: vec![0.0; n],
            out_floor: vec![0.0; n],
            packed_intruder: vec![[0.0; 2]; prescribed.len()],
            packed_floor: vec![0.0; near_wall.len()],
            prescribed,
            near_wall,
            snap: Vec::new(),
            snap_hist: Vec::new(),
        }
    }

    /// Bytes per grain for `n` grains.
    pub fn bytes_per_grain(&self, n: usize) -> f64 {
        (8 * (self.fx.capacity()
            + self.fy.capacity()
            + self.ft.capacity()
            + self.out_x.capacity()
            + self.out_y.capacity()
            + self.out_floor.capacity()
            + 2 * self.packed_intruder.capacity()
            + self.packed_floor.capacity()
            + 5 * self.snap.capacity()
            + self.snap_hist.capacity())
            + 4 * (self.prescribed.capacity() + self.near_wall.capacity())
            + 8 * (self.prescribed_at.capacity() + self.near_wall_at.capacity())) as f64
            / n.max(1) as f64
    }
}
