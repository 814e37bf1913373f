//! Automated campaigns (`sandjumper campaign`): prepare the bed to a target packing
//! fraction, jump, record, analyse, over a parameter space; resumable after a crash.
//!
//! - [`mod@file`]: the campaign file and its checks.
//! - [`plan`]: the grid expanded into points, in order or shuffled.
//! - [`bed`]: the bed apparatus the preparation drives, and its simulated twin.
//! - [`board_bed`]: the apparatus of a real board, over its link.
//! - [`prepare`]: the closed-loop bed preparation.
//! - [`point`]: one point, from fluidization to its analysed folder.
//! - [`journal`]: the append-only journal, the campaign's only source of truth.
//! - [`records`]: state, `results.csv` and Bluesky documents derived from the journal.
//! - [`figure`]: jump height against phi and frequency.
//! - [`session`]: `campaign run`, `resume` and `status` as calls ([`session::run`],
//!   [`session::resume`], [`session::status`]), the journal's lock and the folder's names.
//! - [`error`]: what they return when they fail.
//!
//! The command line's `campaign run|resume|status` maps its arguments to these calls.

pub mod bed;
pub mod board_bed;
pub mod error;
pub mod figure;
pub mod file;
pub mod journal;
pub mod plan;
pub mod point;
pub mod prepare;
pub mod records;
pub mod result_row;
pub mod session;

pub use error::CampaignError;
pub use session::{Hooks, ResumeRequest, RunRequest, SessionOutcome, StatusReport, StatusRequest};
