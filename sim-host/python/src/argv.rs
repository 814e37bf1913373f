//! Python keyword arguments as the CLI's argument list, parsed by the CLI's own parser, so a
//! Python call gets the CLI's defaults, checks and messages.

use std::fmt::Display;

use clap::Parser;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use sandjumper_cli::cli::Cli;
use sandjumper_cli::cli::args::Command;
use sandjumper_cli::command::CliError;

/// An argument list under construction, and which Python argument each flag came from.
pub struct Argv {
    args: Vec<String>,
    /// `(flag or <POSITIONAL>, Python name)`, for the error messages.
    names: Vec<(String, String)>,
}

impl Argv {
    /// `sandjumper <words…>`.
    pub fn new(words: &[&str]) -> Self {
        let mut args = vec!["sandjumper".to_string()];
        args.extend(words.iter().map(|w| (*w).to_string()));
        Self {
            args,
            names: Vec::new(),
        }
    }

    /// A positional argument (`value_name` as the CLI's help shows it, e.g. `FRAMES`).
    pub fn positional(&mut self, py: &str, value_name: &str, value: impl Display) {
        self.args.push(value.to_string());
        self.names.push((format!("<{value_name}>"), py.to_string()));
    }

    /// `--flag value` (floats print their shortest exact form, so nothing is rounded).
    pub fn value(&mut self, py: &str, flag: &str, value: impl Display) {
        // `--flag=value`: a negative number is a value, not a flag.
        self.args.push(format!("{flag}={value}"));
        self.names.push((flag.to_string(), py.to_string()));
    }

    /// `--flag value` when the value is given.
    pub fn opt(&mut self, py: &str, flag: &str, value: Option<impl Display>) {
        match value {
            Some(v) => self.value(py, flag, v),
            None => self.names.push((flag.to_string(), py.to_string())),
        }
    }

    /// `--flag` when `on`.
    pub fn switch(&mut self, py: &str, flag: &str, on: bool) {
        self.names.push((flag.to_string(), py.to_string()));
        if on {
            self.args.push(flag.to_string());
        }
    }

    /// Parse with the CLI's parser. A refusal is a `ValueError` with the CLI's message, each
    /// flag in it replaced by the Python argument's name.
    pub fn parse(&self) -> PyResult<Command> {
        Cli::try_parse_from(&self.args)
            .map(|cli| cli.command)
            .map_err(|e| PyValueError::new_err(self.message(&e.render().to_string())))
    }

    /// The command's own error (after parsing) as a Python exception, its flags named as the
    /// Python arguments (see [`crate::convert::py_err`]).
    pub fn error(&self, e: CliError) -> PyErr {
        let message = self.message(&e.message);
        crate::convert::py_err(CliError { message, ..e })
    }

    fn message(&self, rendered: &str) -> String {
        // The first paragraph, without `error: ` and the usage/help lines.
        let first: Vec<&str> = rendered
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .collect();
        let mut msg = first
            .join(" ")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        if let Some(rest) = msg.strip_prefix("error: ") {
            msg = rest.to_string();
        }
        for (flag, py) in &self.names {
            msg = replace_flag(&msg, flag, py);
        }
        msg
    }
}

/// `--flag <VALUE>` or `--flag` (as a whole word) replaced by `py`.
fn replace_flag(msg: &str, flag: &str, py: &str) -> String {
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    while let Some(at) = rest.find(flag) {
        let after = &rest[at + flag.len()..];
        let whole = after
            .chars()
            .next()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '-' || c == '_'));
        out.push_str(&rest[..at]);
        if whole {
            out.push_str(py);
            rest = match after
                .strip_prefix(" <")
                .and_then(|a| a.find('>').map(|e| &a[e + 1..]))
            {
                Some(tail) => tail,
                None => after,
            };
        } else {
            out.push_str(flag);
            rest = after;
        }
    }
    out.push_str(rest);
    out
}
