//! `sandjumper-sim`: the plant simulator of MODEL.md (the robot on simulated sand) and the
//! `sandjumper` CLI.
//!
//! Modules read like the physics: [`params`] (serde + presets), [`robot`] (bodies, spring,
//! equations of motion), [`ground`] (force laws), [`hybrid`] (ground modes and their guards),
//! [`integrate`] (Dormand-Prince 5(4), dense output, events), [`trajectory`] (the core's
//! trajectories as a prescribed `p(t)`), [`jump`] (one kinematic jump and its metrics),
//! [`plant`] (force-driven plant for hardware-in-the-loop), [`simulation`] (the hybrid run
//! loop both share).
//!
//! # Choices where MODEL.md is open
//! - **Events** are located on the dense output to 1e-12 s; the switch is applied at the
//!   first time the guard is positive (right end of the bracket), so the new mode's
//!   condition holds. Load guards (lift-off, restart of a static foot) need a margin of
//!   1 uN ([`hybrid::LOAD_GUARD_MARGIN_N`]) and an apex needs the rod to have risen faster than
//!   1e-9 m/s, so rounding noise at rest never switches modes.
//! - **Re-intrusion anchor**: literal MODEL.md by default (every episode re-anchors the
//!   overshoot, so a static foot restarts only above `F_p(z) + kappa z`);
//!   `[model] reintrusion_anchor = "touchdown"` keeps the touchdown's anchor instead
//!   ([`params::ReintrusionAnchor`]). The added-mass depth `s` restarts at every episode.
//! - **Foot area**: k1, k2 and kappa scale with `(R / reference_foot_radius_m)^2`; alpha, b
//!   and sigma_cone do not.
//! - **Run length**: "extended while airborne up to 3 s" is read as up to trajectory end + 3 s.
//! - **Peak motor force** (kinematic runs) is sampled at every step end and event, not located.
//! - **`hard`** ignores the `[model]` overrides (no sand); an intruding foot whose velocity
//!   reaches 0 while its load still exceeds `F_p` keeps intruding (with v = 0).
//! - **Drive** (force-driven): `K_f` = 10 N/A (chosen, no number in MODEL.md); the 0.2 ms
//!   current lag is on by default (`drive.current_lag_s = 0` disables it) and solved exactly
//!   inside each zero-order-hold period; the stroke limit is not an end stop (not modelled).
//! - **Spring rest length** L0 = 0.1 m (only differences of heights are reported).
//! - **Error control**: max norm over components (as ode45); `SimOptions::atol` 1e-11. The
//!   relative part of a component's tolerance is taken of the largest size it has reached in
//!   the run (Gear's `YMAX`), a position's size being its displacement from the initial state
//!   (heights are reported from there), not its height above an arbitrary origin.
//! - **Breakpoints**: a step ending on a jump of `p''` sees the left limit of `p(t)`
//!   ([`jump::Kinematic::begin_segment`]), so no step straddles the jump.

pub mod acqlog;
pub mod cli;
pub mod differentiate;
pub mod error;
pub mod fastmath;
pub mod figures;
pub mod fit;
pub mod ground;
pub mod hil;
pub mod hybrid;
pub mod integrate;
pub mod jump;
pub mod output;
pub mod params;
pub mod plant;
pub mod plot;
pub mod replay;
pub mod replay_cmd;
pub mod rig_tool;
pub mod robot;
pub mod simulation;
pub mod sweep;
pub mod trajectory;

pub use error::SimError;
pub use hybrid::GroundMode;
pub use jump::{
    Event, EventKind, JumpOutcome, JumpSpec, JumpSummary, SeriesRow, SimOptions, simulate_jump,
    simulate_many,
};
pub use params::{ModelName, Params, ParamsError};
pub use plant::{MotorDrive, Plant, PlantState};
pub use sandjumper_core::trajectory::JumpKind;
