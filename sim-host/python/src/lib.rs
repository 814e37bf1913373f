//! The `sandjumper` Python module: the simulator and the analyses of the `sandjumper` CLI,
//! called in-process (no subprocess), with results as dicts and numpy arrays.
//!
//! Every function takes the CLI's arguments under Python names (`freq_hz` for `--freq`) and
//! goes through the CLI's own argument parser and library code, so the defaults, the checks
//! and the error messages are the CLI's: bad input raises `ValueError` with the CLI's message
//! (the flag replaced by the Python argument's name), a wrong type raises `TypeError` naming
//! the argument, and a failure after the input was accepted raises `RuntimeError`.

mod analyses;
mod argv;
mod convert;
mod simulate;
mod typed;

use pyo3::prelude::*;

/// Simulate the spring-mass jumping robot on granular media (Aguilar & Goldman, Nature
/// Physics 2016) and analyse its measurements, from Python.
#[pymodule]
#[pyo3(name = "sandjumper")]
fn sandjumper_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The libraries' notes (a partial output a killed run left beside `out`) on stderr, as the
    // command line has them.
    sandjumper_output::set_note_sink(|line| eprintln!("{line}"));
    m.add_class::<simulate::JumpResult>()?;
    m.add_class::<simulate::SweepResult>()?;
    m.add_class::<simulate::HilResult>()?;
    m.add_class::<analyses::FolderResult>()?;
    m.add_function(wrap_pyfunction!(simulate::params, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::jump, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::hil, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::replay, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::track, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::piv, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::dem_collide, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::dem_bed, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::dem_intrude, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::read_log, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::log_to_mcap, m)?)?;
    Ok(())
}
