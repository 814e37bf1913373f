//! What every subcommand shares: the error and exit statuses ([`error`]), progress bars
//! ([`progress`]) and the argument vocabulary ([`args`]).

pub use error::*;

pub mod args;
pub mod error;
pub mod progress;
pub mod resolve;
pub mod unavailable;

/// Print a run's outcome on stdout: its JSON summary (`json`: what `to_json` gives) or its
/// human summary (its `Display`, which ends its own lines).
pub fn print_outcome<E: sandjumper_output::Blamed>(
    json: bool,
    outcome: &impl std::fmt::Display,
    to_json: impl FnOnce() -> Result<String, E>,
) -> Result<(), CliError> {
    if json {
        println!("{}", to_json()?);
    } else {
        print!("{outcome}");
    }
    Ok(())
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
