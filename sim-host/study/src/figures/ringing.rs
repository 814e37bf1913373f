//! The robot's natural frequencies after a small kick (docs/model.md section 4: ~8 Hz on hard
//! ground, ~5 Hz during intrusion at low phi): the spring force after the kick on hard ground
//! and on sand, and the measured frequencies against packing fraction beside the
//! series-spring estimates ([`crate::ringing`]).

use serde::Serialize;

use super::grid::GridFigure;
use crate::ringing::{DEFAULT_KICK_M_S, KickRun, Ringing};
use sandjumper_model::params::ModelName;
use sandjumper_output::plot::lines::{Line, LinePanel};
use sandjumper_output::plot::palette;

/// The packing fractions kicked (the preset rows).
pub const RINGING_PHIS: [f64; 6] = [0.57, 0.58, 0.59, 0.60, 0.61, 0.62];
/// The sand models kicked (eq1-linear is the paper's literal series spring `k1 z`).
pub const RINGING_MODELS: [ModelName; 3] = [ModelName::Eq1Linear, ModelName::Eq1, ModelName::Eq4];
/// Time drawn after the kick, s.
pub const SERIES_S: f64 = 0.5;

/// One sample of a kick's series (a row of `ringing_series.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KickSample {
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// Time after the kick, s.
    pub t_s: f64,
    /// Rod height relative to its rest height, m.
    pub rod_m: f64,
    /// Foot height relative to its rest height, m.
    pub foot_m: f64,
    /// Spring force minus the weight of motor and rod, N.
    pub spring_force_change_n: f64,
}

/// Header of `ringing_series.csv`.
pub const SERIES_HEADER: [&str; 6] = [
    "model",
    "phi",
    "t_s",
    "rod_m",
    "foot_m",
    "spring_force_change_n",
];

/// The kicks drawn in the left panel: hard ground and eq4 at both ends of the presets.
fn drawn(r: &Ringing) -> bool {
    r.model == ModelName::Hard.as_str()
        || (r.model == ModelName::Eq4.as_str()
            && [0.57, 0.62].iter().any(|p| (p - r.phi).abs() < 1e-9))
}

/// The series of the drawn kicks, up to [`SERIES_S`].
pub fn series_rows(runs: &[KickRun], weight_n: f64) -> Vec<KickSample> {
    let mut out = Vec::new();
    for run in runs.iter().filter(|r| drawn(&r.ringing)) {
        let Some(first) = run.series.first() else {
            continue;
        };
        out.extend(
            run.series
                .iter()
                .filter(|s| s.t_s <= SERIES_S)
                .map(|s| KickSample {
                    model: run.ringing.model,
                    phi: run.ringing.phi,
                    t_s: s.t_s,
                    rod_m: s.x_r - first.x_r,
                    foot_m: s.x_f - first.x_f,
                    spring_force_change_n: s.f_s - weight_n,
                }),
        );
    }
    out
}

/// Left: spring force after the kick; right: frequencies against phi.
pub fn figure(rows: &[Ringing], series: &[KickSample]) -> GridFigure {
    let mut left = Vec::new();
    let mut keys: Vec<(&str, f64)> = Vec::new();
    for s in series {
        if !keys
            .iter()
            .any(|(m, p)| *m == s.model && (p - s.phi).abs() < 1e-9)
        {
            keys.push((s.model, s.phi));
        }
    }
    for (i, (model, phi)) in keys.into_iter().enumerate() {
        left.push(Line {
            label: if model == ModelName::Hard.as_str() {
                "hard ground".into()
            } else {
                format!("{model}, φ = {phi}")
            },
            points: series
                .iter()
                .filter(|s| s.model == model && (s.phi - phi).abs() < 1e-9)
                .map(|s| (s.t_s, s.spring_force_change_n))
                .collect(),
            color: palette(i),
            dashed: false,
            markers: false,
        });
    }
    let sand = |model: ModelName| -> Vec<&Ringing> {
        rows.iter().filter(|r| r.model == model.as_str()).collect()
    };
    let points = |rs: &[&Ringing], f: fn(&Ringing) -> f64| -> Vec<(f64, f64)> {
        rs.iter()
            .map(|r| (r.phi, f(r)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let (eq1, eq4) = (sand(ModelName::Eq1Linear), sand(ModelName::Eq4));
    let hard = rows.iter().find(|r| r.model == ModelName::Hard.as_str());
    let mut right = vec![
        Line {
            label: "intrusion, eq1-linear (k1 z)".into(),
            points: points(&eq1, |r| r.intrusion_freq_hz),
            color: palette(0),
            dashed: false,
            markers: true,
        },
        Line {
            label: "series spring k1 (paper)".into(),
            points: points(&eq1, |r| r.series_k1_estimate_hz),
            color: palette(0),
            dashed: true,
            markers: false,
        },
        Line {
            label: "intrusion, eq4 (cone)".into(),
            points: points(&eq4, |r| r.intrusion_freq_hz),
            color: palette(1),
            dashed: false,
            markers: true,
        },
        Line {
            label: "series spring dF_p/dz at rest".into(),
            points: points(&eq4, |r| r.series_local_estimate_hz),
            color: palette(1),
            dashed: true,
            markers: false,
        },
        Line {
            label: "foot at rest (eq4)".into(),
            points: points(&eq4, |r| r.static_freq_hz),
            color: palette(2),
            dashed: false,
            markers: true,
        },
    ];
    if let (Some(h), Some(lo), Some(hi)) = (hard, eq4.first(), eq4.last()) {
        right.push(Line {
            label: "hard ground sqrt(k_s/M)/2π".into(),
            points: vec![(lo.phi, h.hard_estimate_hz), (hi.phi, h.hard_estimate_hz)],
            color: palette(3),
            dashed: true,
            markers: false,
        });
    }
    GridFigure::row(
        "Natural frequency after a small kick: intrusion (series spring) and foot at rest",
        vec![
            LinePanel {
                caption: format!("spring force after a {DEFAULT_KICK_M_S} m/s downward kick"),
                x_desc: "time after the kick (s)".into(),
                y_desc: "F_s - M g (N)".into(),
                lines: left,
                y_from_zero: false,
            },
            LinePanel {
                caption: "measured frequency vs estimates".into(),
                x_desc: "packing fraction φ".into(),
                y_desc: "frequency (Hz)".into(),
                lines: right,
                y_from_zero: true,
            },
        ],
    )
}
