//! The plant of docs/model.md: the robot on simulated sand, and the integrator that runs it.
//!
//! One module per concept, in the order a reader with the paper open meets them:
//! [`params`] (serde + presets per packing fraction), [`robot`] (bodies, spring, equations of
//! motion), [`ground`] (the force laws: eq1, eq4, added mass, re-intrusion), [`hybrid`]
//! (ground modes and their guards), [`events`] (touchdown, lift-off, apex), [`integrate`]
//! (Dormand-Prince 5(4), dense output, event location) with [`fastmath`] (its approximations),
//! [`simulation`] (the hybrid run loop), [`trajectory`] (the core's trajectories as a
//! prescribed `p(t)`), [`table_stroke`] (a stroke sampled at a fixed rate, as the rig replays it), [`jump`] (one kinematic jump, the paper's method), [`plant`] (the
//! force-driven plant the rig links drive), [`options`] and [`record`] (what a run is asked
//! and what it records), [`resolve`] (a preset with a user's overrides on top), [`error`] (why a run could not run).

//!
//! # Choices where docs/model.md is open
//! - **Events** are located on the dense output to 1e-12 s; the switch is applied at the
//!   first time the guard is positive (right end of the bracket), so the new mode's
//!   condition holds. Load guards (lift-off, restart of a static foot) need a margin of
//!   1 uN ([`hybrid::LOAD_GUARD_MARGIN_N`]) and an apex needs the rod to have risen faster than
//!   1e-9 m/s, so rounding noise at rest never switches modes.
//! - **Re-intrusion anchor**: literal docs/model.md by default (every episode re-anchors the
//!   overshoot, so a static foot restarts only above `F_p(z) + kappa z`);
//!   `[model] reintrusion_anchor = "touchdown"` keeps the touchdown's anchor instead
//!   ([`params::ReintrusionAnchor`]). The added-mass depth `s` restarts at every episode.
//! - **Foot area**: k1, k2 and kappa scale with `(R / reference_foot_radius_m)^2`; alpha, b
//!   and sigma_cone do not.
//! - **Run length**: "extended while airborne up to 3 s" is read as up to trajectory end + 3 s.
//! - **Peak motor force** (kinematic runs) is sampled at every step end and event, not located.
//! - **`hard`** ignores the `[model]` overrides (no sand); an intruding foot whose velocity
//!   reaches 0 while its load still exceeds `F_p` keeps intruding (with v = 0).
//! - **Drive** (force-driven): `K_f` = 10 N/A (chosen, no number in docs/model.md); the 0.2 ms
//!   current lag is on by default (`drive.current_lag_s = 0` disables it) and solved exactly
//!   inside each zero-order-hold period; the stroke limit is not an end stop (not modelled).
//! - **Spring rest length** L0 = 0.1 m (only differences of heights are reported).
//! - **Error control**: max norm over components (as ode45); `SimOptions::atol` 1e-11. The
//!   relative part of a component's tolerance is taken of the largest size it has reached in
//!   the run (Gear's `YMAX`), a position's size being its displacement from the initial state
//!   (heights are reported from there), not its height above an arbitrary origin.
//! - **Breakpoints**: a step ending on a jump of `p''` sees the left limit of `p(t)`
//!   ([`jump::Kinematic::begin_segment`]), so no step straddles the jump.

pub mod error;
pub mod events;
pub mod fastmath;
pub mod ground;
pub mod hybrid;
pub mod integrate;
pub mod intrusion_rig;
pub mod jump;
pub mod options;
pub mod params;
pub mod plant;
pub mod record;
pub mod resolve;
pub mod robot;
pub mod simulation;
pub mod table_stroke;
pub mod trajectory;

pub use error::SimError;
pub use events::{Event, EventKind};
pub use hybrid::GroundMode;
pub use jump::{JumpOutcome, JumpSpec, simulate_jump, simulate_many};
pub use options::SimOptions;
pub use params::{ModelName, Params, ParamsError};
pub use plant::{MotorDrive, Plant, PlantState};
pub use record::{JumpSummary, SeriesRow};
pub use sandjumper_core::trajectory::JumpKind;
