//! Typed arguments that name themselves: a wrong type raises `TypeError("freq_hz: expected
//! a number (Hz), got str")` on every Python version (PyO3 itself names the argument only in
//! an exception note, which Python 3.9 and 3.10 do not have).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

fn typed<T: for<'a, 'py> FromPyObject<'a, 'py>>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    what: &str,
) -> PyResult<T> {
    obj.extract::<T>().map_err(|_| {
        PyTypeError::new_err(format!("{name}: expected {what}, got {}", type_name(obj)))
    })
}

macro_rules! extractors {
    ($($fn:ident: $ty:ty, $what:literal;)*) => {$(
        #[doc = concat!("`", stringify!($fn), "`: ", $what, ".")]
        pub fn $fn(obj: &Bound<'_, PyAny>) -> PyResult<$ty> {
            typed::<$ty>(obj, stringify!($fn), $what)
        }
    )*};
}

macro_rules! optional_extractors {
    ($($fn:ident($name:literal): $ty:ty, $what:literal;)*) => {$(
        #[doc = concat!("`", $name, "`: ", $what, ", or None.")]
        pub fn $fn(obj: &Bound<'_, PyAny>) -> PyResult<Option<$ty>> {
            if obj.is_none() {
                return Ok(None);
            }
            typed::<$ty>(obj, $name, concat!($what, " or None")).map(Some)
        }
    )*};
}

extractors! {
    kind: String, "a jump kind name (str)";
    model: String, "a ground model name (str)";
    link: String, "a link name (str)";
    freq_hz: f64, "a number (Hz)";
    phi: f64, "a number (packing fraction)";
    rtol: f64, "a number (relative tolerance)";
    encoder_noise: f64, "a number (counts)";
    camera_fps: i64, "an integer (frames/s)";
    m_per_px: f64, "a number (m/px)";
    d1_m: f64, "a number (m)";
    kn: f64, "a number (N/m)";
    damping: f64, "a number (N s/m)";
    speed: f64, "a number (m/s)";
    wall: bool, "a bool";
    allow_gaps: bool, "a bool";
    force: bool, "a bool";
    mcap: bool, "a bool";
    start: f64, "a number (m)";
    depth: f64, "a number (m)";
    withdraw: f64, "a number (m)";
    reintrusion_depth: f64, "a number (m)";
    hold: f64, "a number (s)";
    bin: f64, "a number (m)";
    scale: f64, "a number (factor)";
    time_stretch: f64, "a number (factor)";
    tasks: i64, "an integer (tasks)";
    cpus_per_task: i64, "an integer (CPUs)";
    zero_code: i64, "an integer (DAC code)";
    min_speed_ratio: f64, "a number (share of the foot's speed)";
}

optional_extractors! {
    tau_s("tau_s"): f64, "a number (s)";
    gain_lowering("gain_lowering"): f64, "a number (position gain factor)";
    phi_opt("phi"): f64, "a number (packing fraction)";
    rtol_opt("rtol"): f64, "a number (relative tolerance)";
    window_ms("window_ms"): f64, "a number (ms)";
    d2_m("d2_m"): f64, "a number (m)";
    link_opt("link"): String, "a link name (str)";
    kind_opt("kind"): String, "a jump kind name (str)";
    freq_hz_opt("freq_hz"): f64, "a number (Hz)";
    threads("threads"): usize, "a positive integer";
    board_pace("board_pace"): f64, "a number (factor of real time)";
    clip("clip"): (f64, f64), "a (start_s, end_s) pair of numbers";
    table_rate("table_rate"): i64, "an integer (Hz)";
}

/// `stop_after`: a count of points (0 or more), or None; a negative one is refused as the
/// command line refuses it.
pub fn stop_after(obj: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    if obj.is_none() {
        return Ok(None);
    }
    let n: i64 = typed(obj, "stop_after", "an integer (points) or None")?;
    usize::try_from(n)
        .map(Some)
        .map_err(|_| crate::errors::invalid_value("stop_after", n, "a count of points, 0 or more"))
}
