//! The `sandjumper` Python module: the project's libraries from Python, each command one call
//! of its library crate (no command line, no subprocess), results in memory as dicts and numpy
//! arrays, a folder written only when asked (`out=`).
//!
//! Every function takes the command line's arguments under Python names (`freq_hz` for
//! `--freq`) and builds the library's typed request, with the libraries' own defaults and
//! checks, so the error messages are the command line's: bad input raises `ValueError` (the
//! flag written as the Python argument's name), a wrong type raises `TypeError` naming the
//! argument, and a failure after the input was accepted raises `RuntimeError`. Long calls run
//! with the GIL released, report to a `progress` callback and stop on Ctrl-C (the `call` module).

mod analyses;
mod call;
mod convert;
mod dem;
mod errors;
mod options;
mod rig;
mod simulate;
mod studies;
mod typed;

use pyo3::prelude::*;

/// Simulate the spring-mass jumping robot on granular media (Aguilar & Goldman, Nature
/// Physics 2016) and analyse its measurements, from Python.
#[pymodule]
#[pyo3(name = "sandjumper")]
fn sandjumper_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The libraries' notes (a partial output a killed run left beside `out`) to Python's
    // logging, as every call's own notes ([`call::PyProgress`]): the module prints nothing.
    sandjumper_output::set_note_sink(|line| {
        Python::attach(|py| {
            let _ = call::log_note(py, line);
        });
    });
    m.add_class::<simulate::JumpResult>()?;
    m.add_class::<simulate::SweepResult>()?;
    m.add_class::<simulate::HilResult>()?;
    m.add_class::<analyses::FolderResult>()?;
    m.add_function(wrap_pyfunction!(simulate::params, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::jump, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::sweep_slurm, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::hil, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::replay, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::track, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::piv, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::piv_synthetic, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::camera_scale, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::sweep_merge, m)?)?;
    m.add_function(wrap_pyfunction!(dem::dem_collide, m)?)?;
    m.add_function(wrap_pyfunction!(dem::dem_bed, m)?)?;
    m.add_function(wrap_pyfunction!(dem::dem_intrude, m)?)?;
    m.add_function(wrap_pyfunction!(dem::lammps, m)?)?;
    m.add_function(wrap_pyfunction!(dem::lammps_slurm, m)?)?;
    m.add_function(wrap_pyfunction!(dem::lammps_read, m)?)?;
    m.add_function(wrap_pyfunction!(studies::fit, m)?)?;
    m.add_function(wrap_pyfunction!(studies::optimize, m)?)?;
    m.add_function(wrap_pyfunction!(studies::campaign_run, m)?)?;
    m.add_function(wrap_pyfunction!(studies::campaign_resume, m)?)?;
    m.add_function(wrap_pyfunction!(studies::campaign_status, m)?)?;
    m.add_function(wrap_pyfunction!(studies::figures, m)?)?;
    m.add_function(wrap_pyfunction!(studies::figures_dem, m)?)?;
    m.add("RunNotCompleted", m.py().get_type::<rig::RunNotCompleted>())?;
    m.add_function(wrap_pyfunction!(rig::rig_status, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_jump, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_intrude, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_replay, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_calibrate_drive, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_acknowledge_reset, m)?)?;
    m.add_function(wrap_pyfunction!(rig::rig_flash, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::read_log, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::log_to_mcap, m)?)?;
    Ok(())
}
