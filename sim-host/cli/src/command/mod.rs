//! What every subcommand shares: the error and exit statuses (from `sandjumper_output`) and
//! the argument vocabulary ([`args`]).

pub use sandjumper_output::error::*;
pub use sandjumper_output::resolve;

pub mod args;
