//! The robot's natural frequencies, measured the way one would on the bench: the robot
//! stands at rest (motor held, docs/model.md's initial equilibrium), the motor and rod get a small
//! downward kick, and the spring force is watched (docs/model.md section 4: ~8 Hz on hard ground,
//! ~5 Hz during intrusion at low phi, "k1 acting as a series spring").
//!
//! Sand in this model is rigid-plastic: it resists a foot moving down with the force law and
//! holds a foot at rest like a floor. So a kick on sand shows two frequencies, one after the
//! other:
//! - **intrusion** (the loading half-cycle): the foot moves down, the sand's stiffness
//!   `dF_p/dz` acts in series with the spring, and motor + rod reach their lowest point a
//!   quarter period of that series oscillator after the kick. The intrusion frequency is
//!   `1 / (4 t_low)`, `t_low` the time from the kick to the rod's lowest point. (Damping moves
//!   the lowest point earlier by `atan(zeta)/omega`: about 2 % for the spring's zeta = 0.03,
//!   so the measured frequency reads that much high; the sand's drag adds a little more.)
//! - **static ringing**: once the foot stops the sand holds it rigidly, and motor + rod ring
//!   on the spring alone at the hard-ground frequency; measured from the zero crossings of
//!   `F_s - M g` (the rod's acceleration times `M`) after the foot stopped.
//!
//! On hard ground both are the hard-ground frequency `sqrt(k_s/M)/2pi`. Beside the
//! measurements stand two estimates: the paper's series spring with `k1`,
//! `sqrt(k_s k1/(k_s+k1)/M)/2pi`, and the same with the law's actual stiffness `dF_p/dz` at
//! the rest depth (the cone law of eq4 is softer than `k1` there: its flat area has already
//! shrunk).

use core::f64::consts::PI;

use nalgebra::Vector4;
use serde::Serialize;

use sandjumper_model::error::SimError;
use sandjumper_model::events::EventKind;
use sandjumper_model::ground::{GroundLaw, Sand};
use sandjumper_model::hybrid::Contact;
use sandjumper_model::jump::{Kinematic, rest_heights};
use sandjumper_model::options::{SimOptions, check_options};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::SeriesRow;
use sandjumper_model::robot::Robot;
use sandjumper_model::simulation::Simulation;
use sandjumper_model::trajectory::HoldStroke;

/// The default kick: downward speed given to motor and rod at t = 0, m/s (small: the spring
/// force changes by a few newtons, the foot sinks well under a millimetre at phi 0.57).
pub const DEFAULT_KICK_M_S: f64 = 0.05;
/// How long the robot is watched after the kick, s (eight hard-ground periods).
pub const DEFAULT_DURATION_S: f64 = 1.0;
/// Spacing of the recorded spring force, s.
pub const SAMPLE_S: f64 = 1e-4;
/// Fewest zero crossings of `F_s - M g` after the foot stops for a static frequency.
const MIN_CROSSINGS: usize = 3;

/// What to kick and how.
#[derive(Clone, Debug, PartialEq)]
pub struct KickSpec {
    /// Parameters (the sand's preset, or any params file).
    pub params: Params,
    /// Ground model (`hard` for the floor).
    pub model: ModelName,
    /// Downward speed given to motor and rod at t = 0, m/s (> 0).
    pub kick_m_s: f64,
    /// How long to watch, s.
    pub duration_s: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
}

impl KickSpec {
    /// The default kick on `model` with `params`.
    pub fn new(params: Params, model: ModelName) -> Self {
        Self {
            params,
            model,
            kick_m_s: DEFAULT_KICK_M_S,
            duration_s: DEFAULT_DURATION_S,
            rtol: 1e-10,
        }
    }
}

/// The measured frequencies of one kick, beside their estimates (a row of `ringing.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ringing {
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction (the params' own; meaningless on hard ground).
    pub phi: f64,
    /// Kick speed, m/s.
    pub kick_m_s: f64,
    /// Time from the kick to the rod's lowest point, s.
    pub lowest_point_s: f64,
    /// Intrusion (loading) frequency `1 / (4 lowest_point_s)`, Hz.
    pub intrusion_freq_hz: f64,
    /// How far the kick pushed the foot into the sand, m (0 on hard ground).
    pub extra_depth_m: f64,
    /// When the foot came to rest, s (0 on hard ground: it never moved).
    pub foot_stopped_s: f64,
    /// Ringing frequency after the foot stopped, from zero crossings of `F_s - M g`, Hz.
    pub static_freq_hz: f64,
    /// Zero crossings the static frequency was taken from.
    pub static_crossings: usize,
    /// `sqrt(k_s/M)/2pi`, Hz.
    pub hard_estimate_hz: f64,
    /// Sand stiffness `k1` (scaled to the foot), N/m; infinite on hard ground.
    pub k1_n_m: f64,
    /// `sqrt(k_s k1/(k_s+k1)/M)/2pi`, Hz (the paper's series spring).
    pub series_k1_estimate_hz: f64,
    /// The law's stiffness `dF_p/dz` just below the rest depth, N/m.
    pub local_stiffness_n_m: f64,
    /// The series estimate with `local_stiffness_n_m`, Hz.
    pub series_local_estimate_hz: f64,
}

/// Header of `ringing.csv`.
pub const HEADER: [&str; 14] = [
    "model",
    "phi",
    "kick_m_s",
    "lowest_point_s",
    "intrusion_freq_hz",
    "extra_depth_m",
    "foot_stopped_s",
    "static_freq_hz",
    "static_crossings",
    "hard_estimate_hz",
    "k1_n_m",
    "series_k1_estimate_hz",
    "local_stiffness_n_m",
    "series_local_estimate_hz",
];

/// A measurement and the time series it was taken from.
#[derive(Clone, Debug)]
pub struct KickRun {
    /// The numbers.
    pub ringing: Ringing,
    /// The recorded series (every [`SAMPLE_S`], plus events).
    pub series: Vec<SeriesRow>,
}

/// Frequency of a mass `m` on spring `k_s` in series with `k` (infinite `k`: the spring
/// alone), Hz.
pub fn series_frequency_hz(k_s: f64, k: f64, m: f64) -> f64 {
    let k_eff = if k.is_finite() {
        k_s * k / (k_s + k)
    } else {
        k_s
    };
    (k_eff / m).sqrt() / (2.0 * PI)
}

/// Kick the robot at rest and measure its frequencies.
pub fn kick(spec: &KickSpec) -> Result<KickRun, SimError> {
    if !(spec.kick_m_s.is_finite() && spec.kick_m_s > 0.0) {
        return Err(SimError::InvalidInput {
            field: "kick_m_s",
            value: spec.kick_m_s.to_string(),
            allowed: "a downward speed > 0 m/s".into(),
        });
    }
    if !(spec.duration_s.is_finite() && spec.duration_s > 0.0) {
        return Err(SimError::InvalidInput {
            field: "duration_s",
            value: spec.duration_s.to_string(),
            allowed: "a duration > 0 s".into(),
        });
    }
    let params = &spec.params;
    params.validate()?;
    let opts = SimOptions {
        rtol: spec.rtol,
        record_series: true,
        series_interval_s: SAMPLE_S,
        max_step_s: 1e-3,
        ..SimOptions::default()
    };
    check_options(&opts)?;
    let robot = Robot::new(params);
    let sand = Sand::new(params, GroundLaw::resolve(spec.model, &params.model));
    let (x_r, x_f) = rest_heights(&robot, &sand);
    let stroke = HoldStroke {
        position_m: -params.robot.stroke_amplitude_m,
    };
    let mut sim = Simulation::new(
        robot,
        sand,
        Contact::at_rest(&sand, x_f),
        Kinematic::new(stroke),
        Vector4::new(x_r, -spec.kick_m_s, x_f, 0.0),
        0.0,
        &opts,
    );
    sim.settle()?;
    sim.actuation.begin_segment(f64::INFINITY);
    sim.advance_to(spec.duration_s, false)?;
    let events = sim.events().to_vec();
    let series = sim.take_series();
    if events.iter().any(|e| e.kind == EventKind::LiftOff) {
        return Err(SimError::InvalidInput {
            field: "kick_m_s",
            value: spec.kick_m_s.to_string(),
            allowed: "a kick small enough that the foot stays on the ground".into(),
        });
    }

    let m = robot.motor_rod_mass_kg();
    let weight = m * robot.gravity_m_s2();
    let samples: Vec<(f64, f64)> = series.iter().map(|r| (r.t_s, r.f_s)).collect();
    let depth_of_rod: Vec<(f64, f64)> = series.iter().map(|r| (r.t_s, -r.x_r)).collect();
    let lowest_point_s = first_maximum(&depth_of_rod).ok_or_else(|| SimError::InvalidInput {
        field: "duration_s",
        value: spec.duration_s.to_string(),
        allowed: "a duration long enough for the rod to reach its lowest point".into(),
    })?;
    let foot_stopped_s = events
        .iter()
        .find(|e| e.kind == EventKind::Static)
        .map_or(0.0, |e| e.t_s);
    let after: Vec<(f64, f64)> = samples
        .iter()
        .filter(|(t, _)| *t > foot_stopped_s.max(lowest_point_s))
        .map(|&(t, f)| (t, f - weight))
        .collect();
    let crossings = zero_crossings(&after);
    let static_freq_hz = if crossings.len() >= MIN_CROSSINGS {
        let span = crossings[crossings.len() - 1] - crossings[0];
        (crossings.len() - 1) as f64 / (2.0 * span)
    } else {
        f64::NAN
    };
    let depth_end = series.last().map_or(0.0, |r| -r.x_f);
    let k_s = robot.spring_stiffness_n_m();
    let rigid = sand.law.is_rigid();
    let z0 = -x_f;
    let (k1, local) = if rigid {
        (f64::INFINITY, f64::INFINITY)
    } else {
        let h = 1e-7;
        (
            sand.penetration_force(h) / h,
            (sand.penetration_force(z0 + h) - sand.penetration_force(z0)) / h,
        )
    };
    Ok(KickRun {
        ringing: Ringing {
            model: spec.model.as_str(),
            phi: params.sand.packing_fraction,
            kick_m_s: spec.kick_m_s,
            lowest_point_s,
            intrusion_freq_hz: 1.0 / (4.0 * lowest_point_s),
            extra_depth_m: if rigid { 0.0 } else { depth_end - z0 },
            foot_stopped_s,
            static_freq_hz,
            static_crossings: crossings.len(),
            hard_estimate_hz: series_frequency_hz(k_s, f64::INFINITY, m),
            k1_n_m: k1,
            series_k1_estimate_hz: series_frequency_hz(k_s, k1, m),
            local_stiffness_n_m: local,
            series_local_estimate_hz: series_frequency_hz(k_s, local, m),
        },
        series,
    })
}

/// Time of the first local maximum of `(t, y)` samples, refined by the parabola through it
/// and its neighbours; `None` if the samples only rise.
pub fn first_maximum(samples: &[(f64, f64)]) -> Option<f64> {
    let i = (1..samples.len().checked_sub(1)?)
        .find(|&i| samples[i].1 >= samples[i - 1].1 && samples[i].1 > samples[i + 1].1)?;
    let [(t0, y0), (t1, y1), (t2, y2)] = [samples[i - 1], samples[i], samples[i + 1]];
    // Vertex of the parabola through three points (unequal spacing: events add rows).
    let d1 = (y1 - y0) / (t1 - t0);
    let d2 = (y2 - y1) / (t2 - t1);
    let curvature = (d2 - d1) / (t2 - t0);
    if curvature >= 0.0 || !curvature.is_finite() {
        return Some(t1);
    }
    let vertex = 0.5 * (t0 + t1) - d1 / (2.0 * curvature);
    Some(vertex.clamp(t0, t2))
}

/// Times where `(t, y)` samples change sign, by linear interpolation, s.
pub fn zero_crossings(samples: &[(f64, f64)]) -> Vec<f64> {
    samples
        .windows(2)
        .filter(|w| (w[0].1 < 0.0) != (w[1].1 < 0.0) && w[1].0 > w[0].0)
        .map(|w| {
            let [(t0, y0), (t1, y1)] = [w[0], w[1]];
            t0 + (t1 - t0) * y0 / (y0 - y1)
        })
        .collect()
}

/// Kicks on hard ground and on sand at every preset row under `models`, in parallel.
pub fn kick_presets(models: &[ModelName], phis: &[f64], rtol: f64) -> Result<Vec<KickRun>, String> {
    use rayon::prelude::*;
    let mut jobs = vec![(ModelName::Hard, phis.first().copied().unwrap_or(0.57))];
    for &model in models {
        jobs.extend(phis.iter().map(|&phi| (model, phi)));
    }
    jobs.par_iter()
        .map(|&(model, phi)| {
            let params = Params::preset(phi).map_err(|e| e.to_string())?;
            let spec = KickSpec {
                rtol,
                ..KickSpec::new(params, model)
            };
            kick(&spec).map_err(|e| format!("kick on {model} at phi {phi}: {e}"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parabola_peak_is_found_between_samples() {
        let samples: Vec<(f64, f64)> = (0..100)
            .map(|i| {
                let t = f64::from(i) * 0.01;
                (t, -(t - 0.3137).powi(2))
            })
            .collect();
        assert!((first_maximum(&samples).unwrap() - 0.3137).abs() < 1e-12);
        assert_eq!(first_maximum(&samples[..20]), None);
    }

    #[test]
    fn zero_crossings_of_a_sine_are_half_a_period_apart() {
        let f = 8.0;
        let samples: Vec<(f64, f64)> = (0..1000)
            .map(|i| {
                let t = f64::from(i) * 1e-3 + 0.01;
                (t, (2.0 * PI * f * t).sin())
            })
            .collect();
        let c = zero_crossings(&samples);
        assert_eq!(c.len(), 16);
        for w in c.windows(2) {
            assert!((w[1] - w[0] - 1.0 / (2.0 * f)).abs() < 1e-5, "{w:?}");
        }
    }

    #[test]
    fn a_kick_that_is_not_a_speed_is_refused() {
        let params = Params::preset(0.57).unwrap();
        for bad in [0.0, -0.1, f64::NAN] {
            let spec = KickSpec {
                kick_m_s: bad,
                ..KickSpec::new(params.clone(), ModelName::Eq4)
            };
            assert!(kick(&spec).is_err(), "{bad}");
        }
    }
}
