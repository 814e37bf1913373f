//! Library errors and refused values as Python exceptions, worded as the command line words
//! them: bad input is `ValueError`, a failure after the input was accepted `RuntimeError`.

use std::fmt::Display;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use sandjumper_output::{Blame, Blamed};

/// A library error as Python's: the caller's input (see [`Blame`]) is a `ValueError`, anything
/// else a `RuntimeError`; the message is the library's, each command-line flag in `names`
/// (`("--freq", "freq_hz")`) written as the Python argument that carries it.
pub fn lib_err<E: Blamed>(e: E, names: &[(&str, &str)]) -> PyErr {
    let message = with_names(&e.to_string(), names);
    match e.blame() {
        Blame::Input => PyValueError::new_err(message),
        Blame::Internal => PyRuntimeError::new_err(message),
    }
}

/// A value the library's check refused, as the command line words it: "invalid value 'RAW'
/// for 'NAME': REASON".
pub fn invalid_value(name: &str, raw: impl Display, reason: &str) -> PyErr {
    PyValueError::new_err(format!("invalid value '{raw}' for '{name}': {reason}"))
}

/// `value` through the library's check `parse` (which takes the value's text, as typed on a
/// command line: Rust's shortest exact form of a number), or the refusal as
/// [`invalid_value`].
pub fn checked<T, V: Display>(
    name: &str,
    value: V,
    parse: impl Fn(&str) -> Result<T, String>,
) -> PyResult<T> {
    let raw = value.to_string();
    parse(&raw).map_err(|reason| invalid_value(name, &raw, &reason))
}

/// `value` through the library's check `check` of a number (a frequency, a packing fraction),
/// or the refusal as [`invalid_value`].
pub fn checked_number(
    name: &str,
    value: f64,
    check: fn(f64) -> Result<f64, String>,
) -> PyResult<f64> {
    check(value).map_err(|reason| invalid_value(name, value, &reason))
}

/// One of the names `allowed` offers (a jump kind, a ground model), or the command line's
/// refusal: "invalid value 'hop' for 'kind' [possible values: single, stutter, delayed]".
pub fn choice<T: Copy>(name: &str, value: &str, allowed: &[(&str, T)]) -> PyResult<T> {
    allowed
        .iter()
        .find(|(n, _)| *n == value)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = allowed.iter().map(|(n, _)| *n).collect();
            PyValueError::new_err(format!(
                "invalid value '{value}' for '{name}' [possible values: {}]",
                names.join(", ")
            ))
        })
}

/// A required argument left out (or None) where another makes it required.
pub fn required(name: &str) -> PyErr {
    PyValueError::new_err(format!(
        "the following required arguments were not provided: {name}"
    ))
}

/// `message` with each flag of `names` (as a whole word, with its `<VALUE>` placeholder if
/// any) written as the Python argument's name.
pub fn with_names(message: &str, names: &[(&str, &str)]) -> String {
    let mut out = message.to_string();
    for (flag, py) in names {
        out = replace_flag(&out, flag, py);
    }
    out
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
