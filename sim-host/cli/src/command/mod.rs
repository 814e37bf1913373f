//! What every subcommand shares: the error and exit statuses (from `sandjumper_output`) and
//! the argument vocabulary ([`args`]).

pub use error::*;

pub mod args;
pub mod error;
pub mod progress;
pub mod resolve;
#[cfg(feature = "rig")]
pub mod stroke;
pub mod unavailable;

/// Print an analysis's JSON (`json`) or its human summary on stdout.
pub fn print_analysed(analysed: &Analysed, json: bool) {
    if json {
        println!("{}", analysed.json);
    } else {
        print!("{}", analysed.human);
    }
}

/// A progress bar on stderr for `len` items called `what`, shown only on a terminal (hidden
/// otherwise, so logs and pipes stay clean).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    on_terminal(
        || indicatif::ProgressBar::new(len),
        &format!(
            "{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {what} (eta {{eta}})"
        ),
    )
}

/// A counter on stderr for work whose total is not known in advance (`N what` with the time
/// elapsed), shown only on a terminal.
pub fn progress_counter(what: &str) -> indicatif::ProgressBar {
    on_terminal(
        indicatif::ProgressBar::new_spinner,
        &format!("{{spinner}} [{{elapsed_precise}}] {{pos}} {what}"),
    )
}

/// The bar `make` builds, styled by `template`, when stderr is a terminal; a hidden one
/// otherwise.
fn on_terminal(
    make: impl FnOnce() -> indicatif::ProgressBar,
    template: &str,
) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = make();
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}
