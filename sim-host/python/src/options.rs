//! Keyword options onto a library request: each name (the command line's flag, `_` for `-`)
//! has a setter that converts the Python value, checks it with the library's own check and
//! sets the request's field. An unknown name is a `TypeError` listing the names allowed.

use std::path::PathBuf;

use clap::ValueEnum;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

use crate::convert::path_arg;
use crate::errors::checked;

/// Sets one field of a request `R` from a Python value.
pub type Setter<R> = fn(&mut R, &Bound<'_, PyAny>) -> PyResult<()>;

/// Where an option not in a request's own table goes (a nested request's table), if
/// anywhere: None when the name is unknown there too.
pub type Rest<'r, R> = dyn FnMut(&mut R, &str, &Bound<'_, PyAny>) -> Option<PyResult<()>> + 'r;

/// Apply `options` (None values left out) through `table`; names not in it go to `rest` (a
/// nested request's table, e.g. the DEM's contact model), else are refused.
pub fn apply<R>(
    request: &mut R,
    options: Option<&Bound<'_, PyDict>>,
    table: &[(&str, Setter<R>)],
    rest: &mut Rest<'_, R>,
) -> PyResult<()> {
    let Some(options) = options else {
        return Ok(());
    };
    for (key, value) in options.iter() {
        let key: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        if let Some((_, set)) = table.iter().find(|(n, _)| *n == key) {
            set(request, &value)?;
        } else if let Some(done) = rest(request, &key, &value) {
            done?;
        } else {
            let names: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
            return Err(PyTypeError::new_err(format!(
                "unexpected keyword argument '{key}' (allowed here: {})",
                names.join(", ")
            )));
        }
    }
    Ok(())
}

/// Nothing further: every option is in the table.
pub fn none<R>(_: &mut R, _: &str, _: &Bound<'_, PyAny>) -> Option<PyResult<()>> {
    None
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// A number checked by the library's `parse`.
pub fn number<T>(
    name: &str,
    obj: &Bound<'_, PyAny>,
    parse: impl Fn(&str) -> Result<T, String>,
) -> PyResult<T> {
    if obj.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a number, got bool"
        )));
    }
    let v: f64 = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!("{name}: expected a number, got {}", type_name(obj)))
    })?;
    checked(name, v, parse)
}

/// A non-negative integer.
pub fn count<T: for<'a, 'py> FromPyObject<'a, 'py>>(
    name: &str,
    obj: &Bound<'_, PyAny>,
) -> PyResult<T> {
    if obj.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an integer, got bool"
        )));
    }
    if let Ok(v) = obj.extract::<i64>()
        && v < 0
    {
        return Err(PyValueError::new_err(format!(
            "{name}: {v} is negative (allowed: 0 or more)"
        )));
    }
    obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a non-negative integer, got {}",
            type_name(obj)
        ))
    })
}

/// A bool.
pub fn flag(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    if !obj.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a bool, got {}",
            type_name(obj)
        )));
    }
    obj.extract()
}

/// A path.
pub fn path(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    path_arg(name, obj)
}

/// A name of `T`'s choices, as the command line offers them.
pub fn choice<T: ValueEnum>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<T> {
    let s: String = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a name (str), got {}",
            type_name(obj)
        ))
    })?;
    T::from_str(&s, false).map_err(|_| {
        let allowed: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value().map(|p| p.get_name().to_string()))
            .collect();
        PyValueError::new_err(format!(
            "invalid value '{s}' for '{name}' [possible values: {}]",
            allowed.join(", ")
        ))
    })
}

/// A list of numbers (or one number, or the command line's comma-separated text), as the
/// command line's text `A,B,C` for the library's list parser.
pub fn list_text(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(s);
    }
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(v.to_string());
    }
    let items = obj.try_iter().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a number or a list of numbers, got {}",
            type_name(obj)
        ))
    })?;
    let mut parts = Vec::new();
    for item in items {
        let item = item?;
        if let Ok(v) = item.extract::<i64>() {
            parts.push(v.to_string());
        } else if let Ok(v) = item.extract::<f64>() {
            parts.push(v.to_string());
        } else {
            return Err(PyTypeError::new_err(format!(
                "{name}: every item must be a number"
            )));
        }
    }
    Ok(parts.join(","))
}
