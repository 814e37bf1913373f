//! `sandjumper-output`: what every command of the project shares below the command line.
//!
//! - [`parse`]: number parsers and range checks that name what they check;
//! - [`folder`]: atomically written output folders, CSV and `.npy` files;
//! - [`lock`]: one writer for a resumable run's state ([`WriterLock`]);
//! - [`plot`]: figures (PNG + SVG) in the project's style;
//! - [`progress`]: the sink a long call reports to ([`Progress`]) and whose fault a failure
//!   is ([`Blame`]).

pub mod folder;
pub mod lock;
pub mod parse;
pub mod plot;
pub mod progress;

pub use folder::*;
pub use lock::{LockError, WriterLock};
pub use progress::{Blame, Blamed, Progress, Silent, set_note_sink};
