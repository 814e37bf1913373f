//! Every command's `--help` is the text in `tests/help/` (one file per command path, e.g.
//! `sandjumper_dem_bed.txt` for `sandjumper dem bed --help`): a flag, a default or a help line
//! changed by accident (an argument moved between crates, a doc comment edited) fails here.
//! The files are the texts of the commit issue 49 started from. A change meant to be made:
//! run with `SANDJUMPER_BLESS_HELP=1` to write the new texts, and review their diff.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn help_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/help")
}

/// `sandjumper WORDS --help` as the binary prints it into a pipe.
fn help(words: &[String]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(words)
        .arg("--help")
        .env_remove("COLUMNS")
        .output()
        .expect("run sandjumper");
    assert!(out.status.success(), "{words:?} --help failed");
    String::from_utf8(out.stdout).expect("UTF-8 help")
}

/// The subcommands a help text lists under `Commands:` (without `help`).
fn subcommands(text: &str) -> Vec<String> {
    text.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|w| *w != "help")
        .map(String::from)
        .collect()
}

fn file_name(words: &[String]) -> String {
    format!("sandjumper_{}.txt", words.join("_"))
}

#[test]
fn every_commands_help_is_its_recorded_text() {
    let bless = std::env::var_os("SANDJUMPER_BLESS_HELP").is_some();
    let mut todo = vec![Vec::<String>::new()];
    let mut seen = BTreeSet::new();
    let mut changed = Vec::new();
    while let Some(words) = todo.pop() {
        let text = help(&words);
        let name = file_name(&words);
        let path = help_dir().join(&name);
        if bless {
            std::fs::write(&path, &text).expect("write the help text");
        } else {
            match std::fs::read_to_string(&path) {
                Ok(recorded) if recorded == text => {}
                Ok(_) => changed.push(format!("{name}: differs")),
                Err(_) => changed.push(format!("{name}: no recorded text")),
            }
        }
        for sub in subcommands(&text) {
            let mut next = words.clone();
            next.push(sub);
            todo.push(next);
        }
        seen.insert(name);
    }
    // A recorded text whose command is gone is a change too.
    for entry in std::fs::read_dir(help_dir()).expect("tests/help") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if !seen.contains(&name) {
            changed.push(format!("{name}: no such command any more"));
        }
    }
    assert!(seen.len() >= 40, "only {} commands found", seen.len());
    assert!(
        changed.is_empty(),
        "help texts changed (SANDJUMPER_BLESS_HELP=1 records new ones):\n{}",
        changed.join("\n")
    );
}
