//! A motor stroke as the rig replays it: positions at a fixed table rate, the rig's
//! feasibility check, the `stroke.csv` file and the upload into the controller's replay table.
//!
//! The check is the one every stroke passes before anything moves (`rig replay`, `hil
//! --stroke`, `jump --stroke`) and the constraint `sandjumper optimize` searches within, so the
//! optimiser's answer is never refused by the rig:
//! - at most [`REPLAY_CAPACITY`] samples at the table rate;
//! - `|p| <= STROKE_M` (25 mm) at every sample;
//! - the motor force on a standing rod, `m_m (p'' + g)` with `p''` the table's second
//!   difference, within the drive's peak force at every sample; the first and last samples
//!   count with the holds around them (the controller holds `p[0]` before and `p[n-1]`
//!   after), so a table that starts or ends moving is refused. The push-off, where the rod
//!   barely moves, is where the force peaks. It is an estimate: the controller's feedforward
//!   is its Catmull-Rom `p''`, which at a step in acceleration (a cosine leaving a hold)
//!   reaches about 1.5 times the second difference for a millisecond, a saturation the
//!   position loop absorbs (a 10 Hz single jump replays within 1 mm); `sandjumper optimize`
//!   reports how many periods the drive saturated through the controller.

use std::fmt::{self, Write as _};
use std::path::Path;

use sandjumper_core::Command;
use sandjumper_core::command::REPLAY_CHUNK;
use sandjumper_core::replay::{REPLAY_CAPACITY, replay_checksum};
use sandjumper_core::trajectory::STROKE_M;
use sandjumper_model::params::Params;
use sandjumper_model::table_stroke::TableStroke;

use crate::protocol::link::{LinkError, RigLink};
use crate::protocol::query_status;

/// The limits of the rig's feasibility check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigLimits {
    /// Motor and carriage mass m_m, kg.
    pub motor_mass_kg: f64,
    /// Gravity, m/s^2.
    pub gravity_m_s2: f64,
    /// The drive's peak force, N.
    pub peak_force_n: f64,
    /// Largest |p|, m (the stroke).
    pub stroke_m: f64,
    /// Most table samples (the firmware's replay buffer).
    pub capacity: usize,
}

impl RigLimits {
    /// The limits of a robot with `params`: its motor mass, gravity and drive, the firmware's
    /// stroke and replay buffer.
    pub fn of(params: &Params) -> Self {
        Self {
            motor_mass_kg: params.robot.motor_mass_kg,
            gravity_m_s2: params.robot.gravity_m_s2,
            peak_force_n: params.drive.peak_force_n,
            stroke_m: STROKE_M,
            capacity: REPLAY_CAPACITY,
        }
    }

    /// The acceleration range `[lo, hi]` of `p''`, m/s^2, that keeps `|m_m (p'' + g)|` within
    /// the peak force.
    pub fn accel_range_m_s2(&self) -> (f64, f64) {
        let a = self.peak_force_n / self.motor_mass_kg;
        (-a - self.gravity_m_s2, a - self.gravity_m_s2)
    }

    /// The longest stroke the buffer holds at `rate_hz`, s.
    pub fn max_duration_s(&self, rate_hz: u32) -> f64 {
        (self.capacity - 1) as f64 / f64::from(rate_hz)
    }
}

/// A stroke sampled at a fixed rate: `p[k]` at `t = k / rate_hz`.
#[derive(Clone, Debug, PartialEq)]
pub struct StrokeTable {
    /// Positions, m.
    pub samples_m: Vec<f64>,
    /// Samples per second, Hz.
    pub rate_hz: u32,
}

/// What the feasibility check measured on a table that passed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableCheck {
    /// Largest |p|, m.
    pub max_abs_p_m: f64,
    /// Largest |m_m (p'' + g)| with `p''` the table's second difference, N.
    pub peak_force_n: f64,
    /// Time of the peak force, s.
    pub peak_force_at_s: f64,
}

/// Why the rig refuses a table (before anything moves).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableRefusal {
    /// Fewer than 2 samples.
    TooShort {
        /// Samples given.
        samples: usize,
    },
    /// More samples than the replay buffer holds.
    TooLong {
        /// Samples needed.
        samples: usize,
        /// The buffer, samples.
        capacity: usize,
        /// Table rate, Hz.
        rate_hz: u32,
        /// Duration of the stroke, s.
        duration_s: f64,
    },
    /// A sample that is not finite or leaves the stroke.
    Stroke {
        /// Time of the sample, s.
        at_s: f64,
        /// Its position, m.
        p_m: f64,
        /// The stroke, m.
        stroke_m: f64,
    },
    /// A sample whose motor force exceeds the drive's peak force.
    Force {
        /// Time of the sample, s.
        at_s: f64,
        /// The force, N.
        force_n: f64,
        /// The drive's peak force, N.
        limit_n: f64,
    },
}

impl fmt::Display for TableRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::TooShort { samples } => {
                write!(
                    f,
                    "a stroke needs at least 2 samples, this one has {samples}"
                )
            }
            Self::TooLong {
                samples,
                capacity,
                rate_hz,
                duration_s,
            } => write!(
                f,
                "the stroke lasts {duration_s:.4} s, which at {rate_hz} samples/s needs \
                 {samples} samples; the firmware's replay buffer holds {capacity} ({:.3} s)",
                (capacity - 1) as f64 / f64::from(rate_hz)
            ),
            Self::Stroke {
                at_s,
                p_m,
                stroke_m,
            } => write!(
                f,
                "the stroke reaches p = {:.3} mm at t = {at_s:.4} s, outside the stroke \
                 (|p| <= {} mm)",
                1e3 * p_m,
                1e3 * stroke_m
            ),
            Self::Force {
                at_s,
                force_n,
                limit_n,
            } => write!(
                f,
                "at t = {at_s:.4} s the stroke needs about {force_n:.0} N of motor force \
                 (m_m (p'' + g) on a standing rod), beyond the drive's {limit_n} N"
            ),
        }
    }
}

impl std::error::Error for TableRefusal {}

impl StrokeTable {
    /// Sample `record` (`(t, p)` pairs, t ascending from 0) at `rate_hz`, linearly between
    /// its points. A record already on the table's grid (`t_k = k / rate_hz`) is taken as it
    /// is, bit for bit.
    pub fn resample(record: &[(f64, f64)], rate_hz: u32) -> Self {
        let rate = f64::from(rate_hz);
        let on_grid = record
            .iter()
            .enumerate()
            .all(|(k, &(t, _))| t == k as f64 / rate);
        if on_grid {
            return Self {
                samples_m: record.iter().map(|r| r.1).collect(),
                rate_hz,
            };
        }
        let duration = record.last().map_or(0.0, |r| r.0);
        let n = (duration * rate + 1e-9).floor() as usize + 1;
        let mut samples_m = Vec::with_capacity(n);
        let mut j = 0;
        for k in 0..n {
            let t = k as f64 / rate;
            while j + 2 < record.len() && record[j + 1].0 <= t {
                j += 1;
            }
            let (ta, pa) = record[j];
            let (tb, pb) = record[(j + 1).min(record.len() - 1)];
            let u = if tb > ta {
                ((t - ta) / (tb - ta)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            samples_m.push(pa + u * (pb - pa));
        }
        Self { samples_m, rate_hz }
    }

    /// `(t, p)` of every sample, s and m.
    pub fn points(&self) -> Vec<(f64, f64)> {
        let rate = f64::from(self.rate_hz);
        self.samples_m
            .iter()
            .enumerate()
            .map(|(k, &p)| (k as f64 / rate, p))
            .collect()
    }

    /// Duration from the first sample to the last, s.
    pub fn duration_s(&self) -> f64 {
        self.samples_m.len().saturating_sub(1) as f64 / f64::from(self.rate_hz)
    }

    /// The rig's feasibility check (see the module's documentation).
    pub fn check(&self, limits: &RigLimits) -> Result<TableCheck, TableRefusal> {
        let s = &self.samples_m;
        let n = s.len();
        let rate = f64::from(self.rate_hz);
        if n < 2 {
            return Err(TableRefusal::TooShort { samples: n });
        }
        if n > limits.capacity {
            return Err(TableRefusal::TooLong {
                samples: n,
                capacity: limits.capacity,
                rate_hz: self.rate_hz,
                duration_s: self.duration_s(),
            });
        }
        let mut max_abs = 0.0f64;
        for (k, &p) in s.iter().enumerate() {
            if !(p.is_finite() && p.abs() <= limits.stroke_m) {
                return Err(TableRefusal::Stroke {
                    at_s: k as f64 / rate,
                    p_m: p,
                    stroke_m: limits.stroke_m,
                });
            }
            max_abs = max_abs.max(p.abs());
        }
        let (mut peak, mut peak_k) = (0.0f64, 0);
        for k in 1..n - 1 {
            let a = (s[k + 1] - 2.0 * s[k] + s[k - 1]) * rate * rate;
            let f = (limits.motor_mass_kg * (a + limits.gravity_m_s2)).abs();
            if f > peak {
                (peak, peak_k) = (f, k);
            }
        }
        // Held before the start and after the end: a table that starts or ends moving asks
        // for its speed at once; the second difference with the held neighbour measures it.
        for (k, a) in [(0, s[1] - s[0]), (n - 1, s[n - 2] - s[n - 1])] {
            let f = (limits.motor_mass_kg * (a * rate * rate + limits.gravity_m_s2)).abs();
            if f > peak {
                (peak, peak_k) = (f, k);
            }
        }
        if peak > limits.peak_force_n {
            return Err(TableRefusal::Force {
                at_s: peak_k as f64 / rate,
                force_n: peak,
                limit_n: limits.peak_force_n,
            });
        }
        Ok(TableCheck {
            max_abs_p_m: max_abs,
            peak_force_n: peak,
            peak_force_at_s: peak_k as f64 / rate,
        })
    }

    /// Control ticks per sample at `tick_hz`; an error when the rate does not divide it.
    pub fn period_ticks(&self, tick_hz: u32) -> Result<u32, String> {
        if self.rate_hz == 0 || !tick_hz.is_multiple_of(self.rate_hz) {
            return Err(format!(
                "a table rate of {} Hz does not divide the {tick_hz} Hz control rate (allowed: \
                 e.g. 500, 1000, 2000, 5000)",
                self.rate_hz
            ));
        }
        Ok(tick_hz / self.rate_hz)
    }

    /// The samples as the controller stores them (f32 metres).
    pub fn samples_f32(&self) -> Vec<f32> {
        self.samples_m.iter().map(|&p| p as f32).collect()
    }

    /// CRC-32 of the f32 samples (what the controller's commit verifies).
    pub fn checksum(&self) -> u32 {
        replay_checksum(&self.samples_f32())
    }

    /// The stroke as the plant is driven by it in kinematic runs (the controller's
    /// interpolation, in f64).
    pub fn kinematic_stroke(&self) -> Result<TableStroke, String> {
        TableStroke::new(self.samples_m.clone(), f64::from(self.rate_hz))
    }

    /// `stroke.csv`: a `t_s,p_m` header and one row per sample, every number written so that
    /// it reads back to the same f64.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t_s,p_m\n");
        let rate = f64::from(self.rate_hz);
        for (k, p) in self.samples_m.iter().enumerate() {
            let _ = writeln!(s, "{},{}", k as f64 / rate, p);
        }
        s
    }

    /// Read a `stroke.csv` (`t_s,p_m`, uniformly sampled at a whole number of samples per
    /// second, t from 0; `#` lines are comments). Errors name the file, the line and what is
    /// allowed.
    pub fn read_csv(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read the stroke file: {e}", path.display()))?;
        Self::parse_csv(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// [`read_csv`](Self::read_csv) of a file's text.
    pub fn parse_csv(text: &str) -> Result<Self, String> {
        let mut rows = Vec::new();
        let mut header = false;
        for (i, line) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            if !header {
                let cols: Vec<&str> = line.split(',').map(str::trim).collect();
                if cols != ["t_s", "p_m"] {
                    return Err(format!(
                        "line {line_no}: header `{line}` not allowed (allowed: `t_s,p_m`)"
                    ));
                }
                header = true;
                continue;
            }
            let mut cols = line.split(',').map(str::trim);
            let (Some(t), Some(p), None) = (cols.next(), cols.next(), cols.next()) else {
                return Err(format!(
                    "line {line_no}: `{line}` is not two numbers `t_s,p_m`"
                ));
            };
            let num = |x: &str, what: &str| {
                x.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("line {line_no}: {what} `{x}` is not a finite number"))
            };
            rows.push((line_no, num(t, "t_s")?, num(p, "p_m")?));
        }
        if !header {
            return Err("no `t_s,p_m` header: not a stroke file".into());
        }
        if rows.len() < 2 {
            return Err(format!(
                "{} sample(s): a stroke needs at least 2",
                rows.len()
            ));
        }
        if rows[0].1 != 0.0 {
            return Err(format!(
                "line {}: the first sample is at t = {} s (allowed: t starts at 0)",
                rows[0].0, rows[0].1
            ));
        }
        let dt = rows[1].1 - rows[0].1;
        let rate = (1.0 / dt).round();
        if !(dt > 0.0 && (1.0..=1e6).contains(&rate) && ((1.0 / dt) - rate).abs() < 1e-6 * rate) {
            return Err(format!(
                "line {}: sample spacing {dt} s is not a whole number of samples per second \
                 (allowed: t_k = k / rate, rate 1..=1000000 Hz)",
                rows[1].0
            ));
        }
        for (k, &(line_no, t, _)) in rows.iter().enumerate() {
            let want = k as f64 / rate;
            if (t - want).abs() > 1e-9 * want.max(1.0) {
                return Err(format!(
                    "line {line_no}: t = {t} s, but a stroke sampled at {rate} Hz has sample \
                     {k} at {want} s (allowed: uniform sampling)"
                ));
            }
        }
        Ok(Self {
            samples_m: rows.iter().map(|r| r.2).collect(),
            rate_hz: rate as u32,
        })
    }

    /// Upload into the controller's replay table in chunks (`ReplayBegin`, `ReplayChunk` x n,
    /// `ReplayCommit` with the CRC-32) at `tick_hz`, and verify the controller's committed
    /// checksum. Returns the checksum.
    pub fn upload(&self, link: &mut dyn RigLink, tick_hz: u32) -> Result<u32, LinkError> {
        let period_ticks = self.period_ticks(tick_hz).map_err(LinkError::Protocol)?;
        let samples = self.samples_f32();
        let checksum = replay_checksum(&samples);
        link.command(&Command::ReplayBegin {
            len: samples.len() as u32,
            period_ticks,
        })?;
        for (k, chunk) in samples.chunks(REPLAY_CHUNK).enumerate() {
            let samples = heapless::Vec::from_slice(chunk)
                .map_err(|_| LinkError::Protocol("replay chunk larger than REPLAY_CHUNK".into()))?;
            link.command(&Command::ReplayChunk {
                offset: (k * REPLAY_CHUNK) as u32,
                samples,
            })?;
        }
        link.command(&Command::ReplayCommit { checksum })?;
        let status = query_status(link)?;
        if status.replay_checksum != Some(checksum) {
            return Err(LinkError::Protocol(format!(
                "verification failed: the controller's committed table has checksum {:?}, the \
                 host's is {checksum:#010x}",
                status.replay_checksum
            )));
        }
        Ok(checksum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> RigLimits {
        RigLimits {
            motor_mass_kg: 1.125,
            gravity_m_s2: 9.81,
            peak_force_n: 300.0,
            stroke_m: 0.025,
            capacity: 4096,
        }
    }

    #[test]
    fn the_check_refuses_stroke_force_and_length_and_passes_the_rest() {
        let l = limits();
        let rest = StrokeTable {
            samples_m: vec![0.01; 100],
            rate_hz: 1000,
        };
        let ok = rest.check(&l).unwrap();
        assert!((ok.peak_force_n - 1.125 * 9.81).abs() < 1e-9);
        let mut out = rest.clone();
        out.samples_m[50] = 0.0251;
        assert!(matches!(
            out.check(&l),
            Err(TableRefusal::Stroke { at_s, .. }) if (at_s - 0.05).abs() < 1e-12
        ));
        // A 1 mm kink at 1 kHz: p'' = 1000 m/s^2 -> 1136 N.
        let mut kink = rest.clone();
        kink.samples_m[20] = 0.009;
        let e = kink.check(&l).unwrap_err();
        assert!(
            matches!(e, TableRefusal::Force { force_n, .. } if force_n > 1000.0),
            "{e}"
        );
        assert!(e.to_string().contains("300 N"), "{e}");
        let long = StrokeTable {
            samples_m: vec![0.0; 4097],
            rate_hz: 1000,
        };
        assert!(matches!(
            long.check(&l),
            Err(TableRefusal::TooLong { samples: 4097, .. })
        ));
        assert!(
            StrokeTable {
                samples_m: vec![0.0; 4096],
                rate_hz: 1000
            }
            .check(&l)
            .is_ok()
        );
    }

    #[test]
    fn a_table_that_starts_or_ends_moving_is_refused() {
        let l = limits();
        // Held before and after: a jump from -20 to +20 mm in one sample, or a ramp that stops
        // dead at its last sample, asks for its speed at once.
        let jump = StrokeTable {
            samples_m: vec![-0.02, 0.02],
            rate_hz: 1000,
        };
        assert!(matches!(jump.check(&l), Err(TableRefusal::Force { .. })));
        let ramp = StrokeTable {
            samples_m: (0..40).map(|k| -0.02 + 0.001 * k as f64).collect(),
            rate_hz: 1000,
        };
        let e = ramp.check(&l).unwrap_err();
        assert!(
            matches!(e, TableRefusal::Force { at_s, .. } if at_s == 0.0 || (at_s - 0.039).abs() < 1e-12),
            "{e}"
        );
        // The same ramp eased in and out at the drive's pace passes.
        let eased = StrokeTable {
            samples_m: (0..400)
                .map(|k| -0.02 + 0.02 * (1.0 - (core::f64::consts::PI * k as f64 / 399.0).cos()))
                .collect(),
            rate_hz: 1000,
        };
        eased.check(&l).unwrap();
    }

    #[test]
    fn the_force_limit_is_an_acceleration_range() {
        let (lo, hi) = limits().accel_range_m_s2();
        assert!((1.125 * (hi + 9.81) - 300.0).abs() < 1e-9);
        assert!((1.125 * (lo + 9.81) + 300.0).abs() < 1e-9);
    }

    #[test]
    fn stroke_csv_round_trips_bit_for_bit_and_refuses_bad_files() {
        let t = StrokeTable {
            samples_m: (0..777).map(|k| 0.02 * (k as f64 * 0.013).sin()).collect(),
            rate_hz: 1000,
        };
        let back = StrokeTable::parse_csv(&t.to_csv()).unwrap();
        assert_eq!(back, t);
        // Resampling a table on its own grid changes nothing.
        let record: Vec<(f64, f64)> = t
            .samples_m
            .iter()
            .enumerate()
            .map(|(k, &p)| (k as f64 / 1000.0, p))
            .collect();
        assert_eq!(StrokeTable::resample(&record, 1000), t);
        for (text, want) in [
            ("t,p\n0,0\n", "header"),
            ("t_s,p_m\n0,0\n", "at least 2"),
            ("t_s,p_m\n0,0\n0.001,x\n", "line 3: p_m `x`"),
            ("t_s,p_m\n0.5,0\n0.501,0\n", "t starts at 0"),
            ("t_s,p_m\n0,0\n0.001,0\n0.0025,0\n", "line 4"),
            ("t_s,p_m\n0,0\n0.0003,0\n", "whole number"),
            ("", "header"),
        ] {
            let e = StrokeTable::parse_csv(text).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    #[test]
    fn resampling_off_grid_is_linear() {
        let t = StrokeTable::resample(&[(0.0, 0.0), (0.01, 0.01)], 1000);
        assert_eq!(t.samples_m.len(), 11);
        assert!((t.samples_m[5] - 0.005).abs() < 1e-15);
    }
}
