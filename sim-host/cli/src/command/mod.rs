//! What every subcommand shares: the error and exit statuses (from `sandjumper_output`) and
//! the argument vocabulary ([`args`]).

pub use sandjumper_output::error::*;
pub use sandjumper_output::resolve;

pub mod args;

/// Print an analysis's JSON (`json`) or its human summary on stdout.
pub fn print_analysed(analysed: &Analysed, json: bool) {
    if json {
        println!("{}", analysed.json);
    } else {
        print!("{}", analysed.human);
    }
}
