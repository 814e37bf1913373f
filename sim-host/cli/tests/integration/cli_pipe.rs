//! Output piped into a reader that stops early (`sandjumper ... | head`) must end the
//! program quietly, not with a "Broken pipe" panic.
#![cfg(unix)]

use std::process::{Command, Stdio};

#[test]
fn output_into_a_closed_pipe_does_not_panic() {
    // `true` exits without reading, so `params` writes into a pipe whose reader is gone.
    let script = format!(
        "for i in 1 2 3 4 5; do '{bin}' params --phi 0.6 | true; done",
        bin = env!("CARGO_BIN_EXE_sandjumper")
    );
    let out = Command::new("sh")
        .arg("-c")
        .arg(&script)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .expect("run sh");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "stderr: {stderr}");
    assert!(!stderr.contains("Broken pipe"), "stderr: {stderr}");
}
