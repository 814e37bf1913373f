//! The search for the best stroke the robot can make (`sandjumper optimize`).
//!
//! [`family`] (the strokes searched: chains of rest-to-rest cosine moves with holds, the
//! paper's three strokes among them), [`evaluate`] (one candidate: the rig's feasibility
//! check, the kinematic jump, the objective), [`paper_sweep`] (the best single, stutter and
//! delayed stutter at the same limits: the baseline), [`search`] (CMA-ES from several starts,
//! in parallel) with its [`checkpoint`] (resumable after a crash), [`verify`] (the best
//! strokes through the real controller), [`refine`] (the best refined through sil),
//! [`figure`] (the stroke and the jump beside the paper's best), [`validity`] (the answer
//! against the paper's measured regime, re-scored under the model's alternative rules).
//!
//! The whole command is one call: an [`OptimizeRequest`] (its `Default` holds the command
//! line's defaults), [`run`] (the F407 link on the virtual board; or [`run_with_board`],
//! with another board's runs), an [`OptimizeOutcome`] (`summary.json` when serialised, the
//! human summary when displayed, the folder it writes) or an [`OptimizeError`].
//! `examples/stroke_search.rs` is a small search.

pub mod checkpoint;
pub mod error;
pub mod evaluate;
pub mod family;
pub mod figure;
pub mod outcome;
pub mod paper_sweep;
pub mod refine;
pub mod request;
pub mod search;
pub mod stages;
pub mod validity;
pub mod verify;

pub use error::OptimizeError;
pub use outcome::OptimizeOutcome;
pub use request::{
    OptimizeRequest, PhiRange, checkpoint_lock_path, checkpoint_path, parse_phi_range,
    parse_verify, ranged,
};
pub use stages::{run, run_with_board};
pub use verify::{LinkRun, NoBoard, StrokeOnBoard, VirtualBoard};
