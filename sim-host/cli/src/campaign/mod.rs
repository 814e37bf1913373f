//! The subcommands `sandjumper campaign`: run, resume, status (over `sandjumper_campaign`,
//! re-exported here).

pub use sandjumper_campaign::*;

pub mod command;
