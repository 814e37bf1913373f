//! Smoothing differentiation of sampled, quantized positions: Savitzky-Golay filters.
//!
//! Each output sample is the value (or first or second derivative) at that sample of the
//! least-squares polynomial of order `order` fitted to the `2 m + 1` samples centred on it
//! (Savitzky & Golay 1964). Near the two ends, where the centred window would leave the
//! data, the polynomial is fitted to the first (last) `2 m + 1` samples and evaluated at the
//! sample's own position, so no padding is invented.
//!
//! Why this suits encoder records: quantization (1 count) is white noise of standard
//! deviation `q / sqrt(12)`; the fit averages it over the window, and a cubic reproduces a
//! smooth trajectory's curvature without lag (the filter is symmetric, zero phase). Its
//! second-derivative gain rolls off above a cut-off given by [`SavitzkyGolay::cutoff_hz`]:
//! the frequency at which the filter's second derivative has fallen to `1/sqrt(2)` of the
//! exact one (computed from the filter's own weights, not a rule of thumb).

use nalgebra::DMatrix;

/// Highest polynomial order accepted.
pub const MAX_ORDER: usize = 6;
/// Longest window accepted, samples.
pub const MAX_WINDOW: usize = 2001;

/// A Savitzky-Golay smoothing differentiator on uniformly sampled data.
#[derive(Clone, Debug, PartialEq)]
pub struct SavitzkyGolay {
    half_width: usize,
    order: usize,
    /// Centred weights for value, first and second derivative (index units).
    central: [Vec<f64>; 3],
}

/// Value, first and second derivative at every sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Derivatives {
    /// Smoothed value (units of the input).
    pub value: Vec<f64>,
    /// First derivative, input units per second.
    pub first: Vec<f64>,
    /// Second derivative, input units per second squared.
    pub second: Vec<f64>,
}

impl SavitzkyGolay {
    /// A filter over `2 half_width + 1` samples with a polynomial of order `order`
    /// (`2 <= order <= MAX_ORDER`, `2 half_width + 1 > order + 1` so it smooths).
    pub fn new(half_width: usize, order: usize) -> Result<Self, String> {
        if !(2..=MAX_ORDER).contains(&order) {
            return Err(format!(
                "Savitzky-Golay order {order} not allowed: 2..={MAX_ORDER} (a second derivative needs at least a quadratic)"
            ));
        }
        if 2 * half_width + 1 > MAX_WINDOW {
            return Err(format!(
                "Savitzky-Golay window of {} samples is too long: at most {MAX_WINDOW}",
                2 * half_width + 1
            ));
        }
        if 2 * half_width < order + 1 {
            return Err(format!(
                "Savitzky-Golay window of {} samples is too short for order {order}: it needs at least {} samples",
                2 * half_width + 1,
                order + 2
            ));
        }
        let mut filter = Self {
            half_width,
            order,
            central: [Vec::new(), Vec::new(), Vec::new()],
        };
        for d in 0..3 {
            filter.central[d] = filter.weights(half_width, d);
        }
        Ok(filter)
    }

    /// A cubic filter of `2 m + 1` samples with `m = round(window_s * rate_hz / 2)`, at least
    /// 7 samples (3 ms at 10 kHz: 31 samples).
    pub fn for_window(rate_hz: f64, window_s: f64) -> Result<Self, String> {
        if !(window_s.is_finite() && window_s > 0.0) {
            return Err(format!(
                "differentiator window {window_s} s not allowed: a positive duration"
            ));
        }
        let samples = window_s * rate_hz;
        if samples > MAX_WINDOW as f64 {
            return Err(format!(
                "differentiator window {window_s} s is {samples:.0} samples at {rate_hz} Hz: at most {MAX_WINDOW}"
            ));
        }
        let half_width = (samples / 2.0).round().max(3.0) as usize;
        Self::new(half_width, 3)
    }

    /// Samples either side of the centre.
    pub fn half_width(&self) -> usize {
        self.half_width
    }

    /// Samples in the window, `2 m + 1`.
    pub fn window_len(&self) -> usize {
        2 * self.half_width + 1
    }

    /// Polynomial order.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Weights (index units, sample spacing 1) for derivative `d` evaluated at window
    /// position `at` (0..window_len).
    fn weights(&self, at: usize, d: usize) -> Vec<f64> {
        let n = self.window_len();
        let m = self.half_width.max(1) as f64;
        let cols = self.order + 1;
        let a = DMatrix::from_fn(n, cols, |j, k| ((j as f64 - at as f64) / m).powi(k as i32));
        let gram = a.transpose() * &a;
        let inv = gram
            .try_inverse()
            .expect("Vandermonde Gram matrix of distinct points is invertible");
        let pinv = inv * a.transpose();
        let factorial = [1.0, 1.0, 2.0][d];
        let scale = factorial / m.powi(d as i32);
        (0..n).map(|j| pinv[(d, j)] * scale).collect()
    }

    /// Smoothed value and derivatives of `samples` taken every `period_s`.
    pub fn apply(&self, samples: &[f64], period_s: f64) -> Result<Derivatives, String> {
        let n = self.window_len();
        let len = samples.len();
        if len < n {
            return Err(format!(
                "{len} samples are fewer than the differentiator's window of {n} samples"
            ));
        }
        let m = self.half_width;
        let mut out = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        let dot = |w: &[f64], start: usize| -> f64 {
            w.iter()
                .zip(&samples[start..start + n])
                .map(|(a, b)| a * b)
                .sum()
        };
        for (d, series) in out.iter_mut().enumerate() {
            for (i, value) in series.iter_mut().enumerate().take(len - m).skip(m) {
                *value = dot(&self.central[d], i - m);
            }
            for at in 0..m {
                let left = self.weights(at, d);
                series[at] = dot(&left, 0);
                let right = self.weights(n - 1 - at, d);
                series[len - 1 - at] = dot(&right, len - n);
            }
        }
        let [value, mut first, mut second] = out;
        first.iter_mut().for_each(|v| *v /= period_s);
        second.iter_mut().for_each(|v| *v /= period_s * period_s);
        Ok(Derivatives {
            value,
            first,
            second,
        })
    }

    /// Gain of the centred second-derivative filter relative to the exact second derivative
    /// at `freq_hz` (1 at low frequency).
    pub fn second_derivative_gain(&self, freq_hz: f64, rate_hz: f64) -> f64 {
        let omega = 2.0 * std::f64::consts::PI * freq_hz / rate_hz;
        let m = self.half_width as i64;
        let response: f64 = self.central[2]
            .iter()
            .enumerate()
            .map(|(j, w)| w * (omega * (j as i64 - m) as f64).cos())
            .sum();
        response / -(omega * omega)
    }

    /// Frequency where the second-derivative gain first falls to `1/sqrt(2)`, Hz (the
    /// Nyquist frequency if it never does).
    pub fn cutoff_hz(&self, rate_hz: f64) -> f64 {
        let target = std::f64::consts::FRAC_1_SQRT_2;
        let nyquist = rate_hz / 2.0;
        let steps = 4000;
        let mut lo = 1e-9 * nyquist;
        for k in 1..=steps {
            let f = nyquist * k as f64 / steps as f64;
            if self.second_derivative_gain(f, rate_hz) <= target {
                let mut hi = f;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if self.second_derivative_gain(mid, rate_hz) > target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return 0.5 * (lo + hi);
            }
            lo = f;
        }
        nyquist
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polynomial(coeffs: &[f64], x: f64) -> f64 {
        coeffs.iter().rev().fold(0.0, |acc, c| acc * x + c)
    }

    #[test]
    fn reproduces_a_cubic_and_its_derivatives_everywhere_including_the_ends() {
        let filter = SavitzkyGolay::new(6, 3).unwrap();
        let h = 1e-3;
        let c = [0.3, -2.0, 5.0, 40.0];
        let t: Vec<f64> = (0..60).map(|i| i as f64 * h).collect();
        let y: Vec<f64> = t.iter().map(|&t| polynomial(&c, t)).collect();
        let d = filter.apply(&y, h).unwrap();
        for (i, &t) in t.iter().enumerate() {
            assert!((d.value[i] - y[i]).abs() < 1e-9);
            let v = c[1] + 2.0 * c[2] * t + 3.0 * c[3] * t * t;
            let a = 2.0 * c[2] + 6.0 * c[3] * t;
            assert!((d.first[i] - v).abs() < 1e-6, "first at {i}");
            assert!(
                (d.second[i] - a).abs() < 1e-4,
                "second at {i}: {} vs {a}",
                d.second[i]
            );
        }
    }

    #[test]
    fn cutoff_falls_as_the_window_grows() {
        let short = SavitzkyGolay::new(10, 3).unwrap().cutoff_hz(10_000.0);
        let long = SavitzkyGolay::new(25, 3).unwrap().cutoff_hz(10_000.0);
        assert!(long < short, "{long} vs {short}");
        // A 51-sample cubic at 10 kHz passes the paper's forcing band (<= 20 Hz) within 1 %.
        let filter = SavitzkyGolay::new(25, 3).unwrap();
        assert!((filter.second_derivative_gain(20.0, 10_000.0) - 1.0).abs() < 0.01);
        assert!((filter.second_derivative_gain(long, 10_000.0) - FRAC).abs() < 1e-6);
    }

    const FRAC: f64 = std::f64::consts::FRAC_1_SQRT_2;

    #[test]
    fn refuses_too_few_samples_and_bad_shapes() {
        assert!(SavitzkyGolay::new(1, 3).is_err());
        assert!(SavitzkyGolay::new(5, 1).is_err());
        let f = SavitzkyGolay::new(5, 3).unwrap();
        assert!(f.apply(&[0.0; 10], 1e-3).is_err());
        assert!(SavitzkyGolay::for_window(1e4, f64::NAN).is_err());
    }
}
