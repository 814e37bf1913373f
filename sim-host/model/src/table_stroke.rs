//! A stroke given as a table of positions at a fixed rate (a `stroke.csv`, the rig's replay
//! table), interpolated as the controller interpolates its replay table: Catmull-Rom cubics
//! between samples (position and velocity continuous, acceleration piecewise linear), holding
//! the first sample before the start and the last after the end. f64 here, f32 on the board.

use crate::trajectory::Stroke;
use sandjumper_core::trajectory::Kinematics;

/// A sampled stroke `p[k]` at `t = k / rate_hz` (m, Hz).
#[derive(Clone, Debug, PartialEq)]
pub struct TableStroke {
    samples_m: Vec<f64>,
    rate_hz: f64,
    push_off_start_s: f64,
}

impl TableStroke {
    /// A stroke through `samples_m` (at least 2, finite), one every `1 / rate_hz` s.
    pub fn new(samples_m: Vec<f64>, rate_hz: f64) -> Result<Self, String> {
        if samples_m.len() < 2 {
            return Err(format!(
                "a stroke table needs at least 2 samples, got {}",
                samples_m.len()
            ));
        }
        if let Some((k, v)) = samples_m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(format!("stroke sample {k} = {v} is not finite"));
        }
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(format!("stroke table rate {rate_hz} Hz: must be > 0"));
        }
        let push_off_start_s = final_rise_start(&samples_m) as f64 / rate_hz;
        Ok(Self {
            samples_m,
            rate_hz,
            push_off_start_s,
        })
    }

    /// The samples, m.
    pub fn samples_m(&self) -> &[f64] {
        &self.samples_m
    }

    /// Samples per second, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }
}

/// Index of the sample where the final rise begins: back from the end over any final fall or
/// hold to the top of the last rise, then down that rise to its foot (the last sample of a
/// hold there). For the paper's strokes this is the push-off's start: 0 for the single, `T/2`
/// for the stutter, `T/2 + tau` for the delayed stutter.
fn final_rise_start(p: &[f64]) -> usize {
    let mut k = p.len() - 1;
    while k > 0 && p[k - 1] >= p[k] {
        k -= 1;
    }
    while k > 0 && p[k - 1] < p[k] {
        k -= 1;
    }
    k
}

impl Stroke for TableStroke {
    fn eval(&self, t_s: f64) -> Kinematics {
        let s = &self.samples_m;
        let hold = |p| Kinematics {
            position_m: p,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        };
        if t_s.is_nan() || t_s < 0.0 {
            return hold(s[0]);
        }
        let x = t_s * self.rate_hz;
        if x >= (s.len() - 1) as f64 {
            return hold(s[s.len() - 1]);
        }
        let i = x.floor() as usize;
        let u = x - i as f64;
        let (p1, p2) = (s[i], s[i + 1]);
        let p0 = if i > 0 { s[i - 1] } else { p1 };
        let p3 = if i + 2 < s.len() { s[i + 2] } else { p2 };
        let (m1, m2) = (0.5 * (p2 - p0), 0.5 * (p3 - p1));
        let (u2, u3) = (u * u, u * u * u);
        let p = (2.0 * u3 - 3.0 * u2 + 1.0) * p1
            + (u3 - 2.0 * u2 + u) * m1
            + (3.0 * u2 - 2.0 * u3) * p2
            + (u3 - u2) * m2;
        let v = (6.0 * u2 - 6.0 * u) * (p1 - p2)
            + (3.0 * u2 - 4.0 * u + 1.0) * m1
            + (3.0 * u2 - 2.0 * u) * m2;
        let a = (12.0 * u - 6.0) * (p1 - p2) + (6.0 * u - 4.0) * m1 + (6.0 * u - 2.0) * m2;
        Kinematics {
            position_m: p,
            velocity_m_s: v * self.rate_hz,
            accel_m_s2: a * self.rate_hz * self.rate_hz,
        }
    }

    /// Every sample time after the first: `p''` is linear between samples and jumps at them.
    fn breakpoints_s(&self) -> Vec<f64> {
        (1..self.samples_m.len())
            .map(|k| k as f64 / self.rate_hz)
            .collect()
    }

    fn end_s(&self) -> f64 {
        (self.samples_m.len() - 1) as f64 / self.rate_hz
    }

    fn push_off_start_s(&self) -> f64 {
        self.push_off_start_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_core::replay::ReplayTable;
    use sandjumper_core::trajectory::{JumpKind, SineJump};

    fn sampled(jump: &SineJump, rate: f64) -> Vec<f64> {
        let n = (jump.end_s() * rate).round() as usize + 1;
        (0..n)
            .map(|k| jump.eval(k as f64 / rate).position_m)
            .collect()
    }

    #[test]
    fn interpolates_as_the_controllers_replay_table() {
        let jump = SineJump::new(JumpKind::DelayedStutter, 0.02, 9.0, 0.13).unwrap();
        let samples = sampled(&jump, 1000.0);
        let stroke = TableStroke::new(samples.clone(), 1000.0).unwrap();
        let mut table = ReplayTable::new();
        let f32s: Vec<f32> = samples.iter().map(|&p| p as f32).collect();
        table.begin(f32s.len() as u32, 10).unwrap();
        table.write_chunk(0, &f32s).unwrap();
        table
            .commit(sandjumper_core::replay::replay_checksum(&f32s))
            .unwrap();
        let ticks = sandjumper_core::profile::ReplayTicks::new(&table, 10_000).unwrap();
        for n in (0..table.end_tick().unwrap() + 20).step_by(7) {
            let (sp, _) = ticks.eval(n, &table);
            let k = stroke.eval(f64::from(n) / 10_000.0);
            assert!(
                (f64::from(sp.position_m) - k.position_m).abs() < 1e-7,
                "tick {n}"
            );
            assert!(
                (f64::from(sp.velocity_m_s) - k.velocity_m_s).abs() < 1e-4,
                "tick {n}: {sp:?} vs {k:?}"
            );
            assert!((f64::from(sp.accel_m_s2) - k.accel_m_s2).abs() < 0.05);
        }
        // And follows the sine it samples (Catmull-Rom at 1 kHz: well under a micrometre).
        for k in 0..400 {
            let t = k as f64 * 7.3e-4;
            let (a, b) = (stroke.eval(t), jump.eval(t));
            assert!((a.position_m - b.position_m).abs() < 2e-6, "{t}");
        }
    }

    #[test]
    fn the_push_off_starts_where_the_final_rise_does() {
        let rate = 1000.0;
        let cases = [
            (
                SineJump::new(JumpKind::Single, 0.02, 10.0, 0.0).unwrap(),
                0.0,
            ),
            (
                SineJump::new(JumpKind::Stutter, 0.02, 10.0, 0.0).unwrap(),
                0.05,
            ),
            (
                SineJump::new(JumpKind::DelayedStutter, 0.02, 10.0, 0.2).unwrap(),
                0.25,
            ),
        ];
        for (jump, want) in cases {
            let s = TableStroke::new(sampled(&jump, rate), rate).unwrap();
            assert!((s.push_off_start_s() - want).abs() < 1.5e-3, "{jump:?}");
            assert!((s.push_off_start_s() - jump.push_off_start_s()).abs() < 1.5e-3);
        }
    }

    #[test]
    fn refuses_short_or_non_finite_tables() {
        assert!(TableStroke::new(vec![0.0], 1000.0).is_err());
        assert!(TableStroke::new(vec![0.0, f64::NAN], 1000.0).is_err());
        assert!(TableStroke::new(vec![0.0, 0.0], 0.0).is_err());
    }
}
