//! The live view of a jump or a campaign while it runs.
//!
//! - [`bus`]: what the control loop and the campaign write into. Samples are reduced for
//!   display (a min/max envelope over 2 ms) and sent in batches of 50 ms of rig time through
//!   a bounded queue that drops the oldest batch when full, counting what it drops; the
//!   producer never waits for a lock. State transitions, faults, jump start and end and
//!   campaign records go through a separate unbounded channel: nothing a busy sample stream
//!   does can push them out. Full-rate data still goes only to the logs.
//! - [`state`]: what the page shows, gathered from the bus (rolling window, events,
//!   campaign table), as `state.json`.
//! - [`server`]: the HTTP server (axum): the page with its chart library embedded (uPlot,
//!   MIT), `state.json`, and Server-Sent Events of everything new.
//! - [`address`]: the address forms `--live` and `--foxglove` take, the refusal of a bind
//!   beyond this machine without `--live-public`, and the `Host` names a request may carry.
//! - [`view`]: one run's view: its bus and page, the run's pace, the page kept up after.
pub mod address;
pub mod bus;
#[cfg(feature = "foxglove")]
pub mod foxglove_bridge;
#[cfg(feature = "foxglove")]
pub mod foxglove_gate;
#[cfg(feature = "server")]
pub mod server;
pub mod state;
pub mod view;

pub use bus::{CampaignRecord, Event, LiveBus, LiveFeed, channel};
#[cfg(feature = "server")]
pub use server::{FOXGLOVE, LiveServer, serve, serve_with_foxglove};
pub use view::{LiveConfig, LiveView};
