//! Check an acquisition log from Rust, as `sandjumper log check FILE` does, and convert it to
//! MCAP beside itself, as `sandjumper log convert FILE FILE.mcap` does.
//!
//! Run it with `cargo run -p sandjumper-acqlog --example check_log -- acquisition.csv`.

use sandjumper_acqlog::check::{self, CheckRequest};
use sandjumper_acqlog::convert::{self, ConvertRequest};
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(file) = std::env::args_os().nth(1) else {
        return Err("usage: check_log FILE (a CSV or binary acquisition log)".into());
    };
    let request = CheckRequest {
        file: file.into(),
        allow_gaps: true,
    };
    let checked = check::run(&request, &Silent)?;
    // The text `log check` prints; the log itself is `checked.log`.
    print!("{checked}");
    println!("{} samples in memory", checked.log.rows.len());
    let outcome = convert::run(
        &ConvertRequest {
            input: request.file.clone(),
            output: request.file.with_extension("mcap"),
            allow_gaps: true,
            ..ConvertRequest::default()
        },
        &Silent,
    )?;
    print!("{outcome}");
    Ok(())
}
