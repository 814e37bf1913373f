//! The search for the best stroke the robot can make (`sandjumper optimize`).
//!
//! [`family`] (the strokes searched: chains of rest-to-rest cosine moves with holds, the
//! paper's three strokes among them), [`evaluate`] (one candidate: the rig's feasibility
//! check, the kinematic jump, the objective), [`paper_sweep`] (the best single, stutter and
//! delayed stutter at the same limits: the baseline), [`search`] (CMA-ES from several starts,
//! in parallel) with its [`checkpoint`] (resumable after a crash), [`verify`] (the best
//! strokes through the real controller), [`refine`] (the best refined through sil), [`figure`] (the stroke and the jump beside the
//! paper's best).

pub mod checkpoint;
pub mod evaluate;
pub mod family;
pub mod figure;
pub mod paper_sweep;
pub mod refine;
pub mod search;
pub mod verify;
