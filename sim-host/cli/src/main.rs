//! The `sandjumper` command line (see [`sandjumper_cli::cli`]).
fn main() -> std::process::ExitCode {
    restore_default_sigpipe();
    // The libraries' notes (a partial output a killed run left beside --out) on stderr.
    sandjumper_output::set_note_sink(|line| eprintln!("{line}"));
    sandjumper_cli::cli::run(std::env::args_os())
}

/// Rust starts programs with SIGPIPE ignored, so `println!` panics ("Broken pipe") when stdout
/// is a pipe whose reader has gone (`sandjumper params | head -3`). Restore the default action
/// so the process ends quietly, as other Unix command-line tools do.
#[cfg(unix)]
fn restore_default_sigpipe() {
    // SAFETY: called first thing in `main`, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_default_sigpipe() {}
