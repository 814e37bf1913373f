//! One jump's row of `results.csv`: what the journal records when a point is done and what
//! the results table and the documents are made of.

use serde::{Deserialize, Serialize};

/// One jump's row of `results.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResultRow {
    /// Point index (run order).
    pub point: usize,
    /// Repeat (0-based).
    pub repeat: u32,
    /// `single`, `stutter`, `delayed`.
    pub kind: String,
    /// Hz.
    pub freq_hz: f64,
    /// s.
    pub tau_s: f64,
    /// Target phi.
    pub target_phi: f64,
    /// Achieved (measured) phi.
    pub achieved_phi: f64,
    /// Bed measurements taken.
    pub attempts: u32,
    /// Fluidizations.
    pub fluidizations: u32,
    /// Compaction doses.
    pub doses: u32,
    /// `done`, `bed-not-prepared`, or `faulted` (the jump latched a fault).
    pub status: String,
    /// Jump height from the rod camera, m.
    pub measured_jump_height_m: Option<f64>,
    /// Camera frames the tracker flagged (the ball out of view, or not found): a measured
    /// height with flagged frames around the apex reads low.
    pub frames_flagged: Option<usize>,
    /// Jump height from replaying the encoder log in the simulator, m.
    pub predicted_jump_height_m: Option<f64>,
    /// Jump height of the simulated plant (the twin's truth), m.
    pub plant_jump_height_m: Option<f64>,
    /// Faults the controller latched (names, `;`-separated), or why the bed could not be
    /// prepared.
    pub faults: String,
    /// The point's folder.
    pub folder: String,
}
