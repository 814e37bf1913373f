//! The `sandjumper` command line (see [`sandjumper_sim::cli`]).
fn main() -> std::process::ExitCode {
    sandjumper_sim::cli::run(std::env::args_os())
}
