//! The subcommands `sandjumper jump`, `sweep`, `merge`, `replay`, `fit`, `figures`: faces over
//! `sandjumper_study`'s calls (re-exported here).

pub use sandjumper_study::*;

pub mod figures;
pub mod fit;
pub mod jump_command;
pub mod replay;
pub mod sweep;

/// Say where a jump's folder went (when `dir`), print the outcome (`text` with `--json`,
/// else `human`), then each of its `warnings` on stderr (`jump` and `replay`).
fn print_jump(
    dir: Option<std::path::PathBuf>,
    json: bool,
    text: &str,
    human: &impl std::fmt::Display,
    warnings: &[String],
) {
    if let Some(dir) = dir {
        eprintln!(
            "wrote {}/ (trajectory.csv, params.toml, summary.json, jump.png, jump.svg)",
            dir.display()
        );
    }
    if json {
        println!("{text}");
    } else {
        print!("{human}");
    }
    for w in warnings {
        eprintln!("warning: {w}");
    }
}
