//! The campaign's points: the grid expanded (kinds x frequencies x delays x target phis x
//! repeats), in the order written or shuffled with the campaign's seed.

use rand::SeedableRng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

use super::file::{CampaignFile, Order};

/// One jump of the campaign.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Position in the run order (0-based); also the folder `points/NNNN`.
    pub index: usize,
    /// `single`, `stutter` or `delayed`.
    pub kind: String,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay, s (0 unless delayed).
    pub tau_s: f64,
    /// Target packing fraction.
    pub target_phi: f64,
    /// Repeat number (0-based).
    pub repeat: u32,
}

impl Point {
    /// The point's folder, relative to the campaign's.
    pub fn folder(&self) -> String {
        format!("points/{:04}", self.index)
    }

    /// The seed of everything random about this point (the simulated bed's scatter and
    /// noise): a function of the campaign seed and the point alone, so a point started
    /// again after an interruption repeats itself.
    pub fn seed(&self, campaign_seed: u64) -> u64 {
        let mut h = campaign_seed ^ 0x9e37_79b9_7f4a_7c15;
        for v in [self.index as u64, u64::from(self.repeat)] {
            h = (h ^ v).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            h ^= h >> 31;
        }
        h
    }
}

/// The points of `f`, in run order.
pub fn points(f: &CampaignFile) -> Vec<Point> {
    let g = &f.grid;
    let mut out = Vec::new();
    for kind in g.kinds.get_ref() {
        for &freq in g.frequencies_hz.get_ref() {
            let delays: Vec<f64> = if kind == "delayed" {
                g.delays_s.get_ref().clone()
            } else {
                vec![0.0]
            };
            for tau in delays {
                for &phi in g.phis.get_ref() {
                    for repeat in 0..*f.repeats.get_ref() {
                        out.push(Point {
                            index: 0,
                            kind: kind.clone(),
                            freq_hz: freq,
                            tau_s: tau,
                            target_phi: phi,
                            repeat,
                        });
                    }
                }
            }
        }
    }
    if f.order == Order::Shuffled {
        let mut rng = rand::rngs::StdRng::seed_from_u64(f.seed);
        out.shuffle(&mut rng);
    }
    for (i, p) in out.iter_mut().enumerate() {
        p.index = i;
    }
    out
}
