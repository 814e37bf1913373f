//! Elementary functions for the integrator's hot path, where a libm call would sit on the
//! critical path of every stage: short polynomials on the small ranges that occur there,
//! falling back to the standard functions outside them. Each states its accuracy, and the
//! tests hold it to that.

/// `exp(-x)` for `x >= 0`. On `[0, 1]` (a control period up to one lag time constant, the
/// common case: 0.1 ms over 0.2 ms by default) the Taylor polynomial of degree 17 in Estrin's
/// form: truncation below `1/18! = 1.6e-16`, within a few ulps of `exp`, no call and a short
/// dependency chain (it sits on the critical path of every stage of every control period).
/// Beyond, `exp` itself.
#[inline]
pub fn exp_neg(x: f64) -> f64 {
    if !(0.0..=1.0).contains(&x) {
        return (-x).exp();
    }
    // 1/k! for k = 0..=17.
    const C: [f64; 18] = {
        let mut c = [1.0; 18];
        let mut k = 1;
        while k < 18 {
            c[k] = c[k - 1] / k as f64;
            k += 1;
        }
        c
    };
    let y = -x;
    let y2 = y * y;
    let y4 = y2 * y2;
    let y8 = y4 * y4;
    let y16 = y8 * y8;
    let p = |k: usize| C[k] + C[k + 1] * y;
    let q0 = p(0) + p(2) * y2;
    let q1 = p(4) + p(6) * y2;
    let q2 = p(8) + p(10) * y2;
    let q3 = p(12) + p(14) * y2;
    let r0 = q0 + q1 * y4;
    let r1 = q2 + q3 * y4;
    (r0 + r1 * y8) + p(16) * y16
}

/// Largest `|x|` [`sincos_small`] accepts, rad.
pub const SINCOS_SMALL_MAX_RAD: f64 = 0.125;

/// `(sin x, cos x)` for `|x| <= SINCOS_SMALL_MAX_RAD` (an angle increment inside one
/// integration step): Taylor polynomials of degree 11 (sin) and 12 (cos), truncation below
/// `x^13/13! = 3e-24` and `x^14/14! = 2e-25`, so within an ulp or two of `sin`/`cos`. Outside
/// the range, `sin_cos` itself.
#[inline]
pub fn sincos_small(x: f64) -> (f64, f64) {
    // NaN goes to `sin_cos` too.
    if x.abs() > SINCOS_SMALL_MAX_RAD || x.is_nan() {
        return x.sin_cos();
    }
    sincos_small_poly(x)
}

/// The polynomials of [`sincos_small`], without the range check.
#[inline(always)]
fn sincos_small_poly(x: f64) -> (f64, f64) {
    let x2 = x * x;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    // sin x = x (1 - x^2/3! + x^4/5! - ..), cos x = 1 - x^2/2! + x^4/4! - ..; Estrin in x^2.
    const S: [f64; 6] = [
        1.0,
        -1.0 / 6.0,
        1.0 / 120.0,
        -1.0 / 5040.0,
        1.0 / 362_880.0,
        -1.0 / 39_916_800.0,
    ];
    const C: [f64; 7] = [
        1.0,
        -0.5,
        1.0 / 24.0,
        -1.0 / 720.0,
        1.0 / 40_320.0,
        -1.0 / 3_628_800.0,
        1.0 / 479_001_600.0,
    ];
    let s = (S[0] + S[1] * x2) + (S[2] + S[3] * x2) * x4 + (S[4] + S[5] * x2) * x8;
    let c = (C[0] + C[1] * x2) + (C[2] + C[3] * x2) * x4 + (C[4] + C[5] * x2 + C[6] * x4) * x8;
    (x * s, c)
}

/// [`sincos_small`] of `L` angles at once, lane by lane in one straight run (the compiler
/// vectorizes it): the same polynomials, so the same results. Lanes outside
/// `|x| <= SINCOS_SMALL_MAX_RAD` (or NaN) get `sin_cos` itself.
#[inline]
pub fn sincos_small_lanes<const L: usize>(x: [f64; L]) -> ([f64; L], [f64; L]) {
    let mut sin = [0.0; L];
    let mut cos = [0.0; L];
    if x.iter().all(|x| x.abs() <= SINCOS_SMALL_MAX_RAD) {
        for i in 0..L {
            (sin[i], cos[i]) = sincos_small_poly(x[i]);
        }
    } else {
        for i in 0..L {
            (sin[i], cos[i]) = sincos_small(x[i]);
        }
    }
    (sin, cos)
}

/// `log2 x` to about 1.2e-4 absolute, for the step-size controller: a factor that needs a
/// few digits (it is multiplied by a safety factor of 0.9 anyway), computed on every step, on
/// the step-to-step dependency chain (the next step's stages wait for it). The exponent from
/// the bits, and `log2(1 + t) = t q(t)` for the mantissa `1 + t` in `[1, 2)`, `q` a cubic
/// least-squares fit in Estrin's form: no division, no branch, a short dependency chain (the
/// atanh series it replaced needed a division and three times as long). Exact at powers of
/// two. `x` must be positive and normal (subnormals and zero give at most -1023, infinities
/// and NaN a meaningless finite value). No libm call.
#[inline]
pub fn log2_approx(x: f64) -> f64 {
    const Q: [f64; 4] = [
        1.438_638_025_900_792_7,
        -0.677_743_266_611_358,
        0.321_879_706_965_249_04,
        -0.082_860_698_276_896_64,
    ];
    let (e, t) = exponent_and_fraction(x);
    e as f64 + t * cubic(&Q, t)
}

/// `x = 2^e (1 + t)`: the unbiased exponent `e` and the mantissa's fraction `t` in `[0, 1)`,
/// read from the bits (exact; zero and subnormals give `e = -1023`, the sign is ignored).
#[inline]
pub fn exponent_and_fraction(x: f64) -> (i64, f64) {
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let t = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000) - 1.0;
    (e, t)
}

/// `c0 + c1 t + c2 t^2 + c3 t^3` in Estrin's form (three multiply-add levels deep, not four).
#[inline]
pub fn cubic(c: &[f64; 4], t: f64) -> f64 {
    (c[0] + c[1] * t) + (t * t) * (c[2] + c[3] * t)
}

/// `2^y` to about 1.2e-4 relative (see [`log2_approx`]); `y` is clamped to `[-1000, 1000]`
/// (NaN gives 1).
#[inline]
pub fn exp2_approx(y: f64) -> f64 {
    let y = if y.is_nan() {
        0.0
    } else {
        y.clamp(-1000.0, 1000.0)
    };
    exp2_in_range(y)
}

/// [`exp2_approx`] for `y` already known to be in `[-1000, 1000]` (a caller that clamps
/// anyway saves the second clamp on its dependency chain). Outside, meaningless.
/// `2^y = 2^n (1 + f p(f))` with `n` the nearest integer, `|f| <= 1/2`, `p` a quadratic
/// least-squares fit of the relative error: exact at integers.
#[inline]
pub fn exp2_in_range(y: f64) -> f64 {
    const P: [f64; 3] = [
        0.693_368_601_259_305_4,
        0.242_217_838_101_181_86,
        0.054_592_824_741_937_44,
    ];
    debug_assert!((-1000.0..=1000.0).contains(&y), "exp2_in_range({y})");
    // Nearest integer by adding and removing 1.5 * 2^52 (ties to even): two additions,
    // where `round` is a libm call on baseline x86-64.
    const ROUNDING: f64 = 6_755_399_441_055_744.0;
    let n = (y + ROUNDING) - ROUNDING;
    let f = y - n;
    let p = (P[0] + P[1] * f) + (f * f) * P[2];
    (1.0 + f * p) * f64::from_bits(((n as i64 + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_is_within_a_few_ulps_of_exp() {
        let mut worst: f64 = 0.0;
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            let rel = (exp_neg(x) / (-x).exp() - 1.0).abs();
            worst = worst.max(rel);
        }
        assert!(worst < 4.0 * f64::EPSILON, "worst relative error {worst:e}");
        for x in [1.5, 7.0, 800.0] {
            assert_eq!(exp_neg(x), (-x).exp());
        }
        assert_eq!(exp_neg(0.0), 1.0);
    }

    #[test]
    fn sincos_small_is_within_two_ulps_of_sin_cos() {
        let (mut worst_s, mut worst_c): (f64, f64) = (0.0, 0.0);
        let n = 200_000;
        for i in -n..=n {
            let x = SINCOS_SMALL_MAX_RAD * i as f64 / n as f64;
            let (s, c) = sincos_small(x);
            let (s_ref, c_ref) = x.sin_cos();
            worst_s = worst_s.max((s - s_ref).abs() / f64::EPSILON / s_ref.abs().max(1e-300));
            worst_c = worst_c.max((c - c_ref).abs() / f64::EPSILON);
        }
        assert!(worst_s <= 2.0, "sin: {worst_s} ulp");
        assert!(worst_c <= 2.0, "cos: {worst_c} ulp");
        assert_eq!(sincos_small(0.0), (0.0, 1.0));
        // Outside the range: the standard functions, exactly.
        for x in [0.2, -1.0, 3.0, f64::NAN] {
            let (s, c) = sincos_small(x);
            let (s_ref, c_ref) = x.sin_cos();
            assert!(
                s.to_bits() == s_ref.to_bits() && c.to_bits() == c_ref.to_bits(),
                "{x}"
            );
        }
    }

    #[test]
    fn sincos_small_lanes_equals_sincos_small_lane_by_lane() {
        let check = |x: [f64; 6]| {
            let (s, c) = sincos_small_lanes(x);
            for i in 0..6 {
                let (es, ec) = sincos_small(x[i]);
                assert_eq!(
                    (s[i].to_bits(), c[i].to_bits()),
                    (es.to_bits(), ec.to_bits()),
                    "lane {i} of {x:?}"
                );
            }
        };
        for j in 0..1000 {
            let base = -SINCOS_SMALL_MAX_RAD + 2.0 * SINCOS_SMALL_MAX_RAD * j as f64 / 1000.0;
            check(core::array::from_fn(|i| base * (1.0 - 0.15 * i as f64)));
        }
        // A lane out of range (or NaN) takes `sin_cos`, the others keep the polynomials.
        check([0.01, 0.02, 0.2, -0.03, 0.1, 0.125]);
        check([0.01, f64::NAN, 0.05, -0.03, 3.0, -0.125]);
    }

    #[test]
    fn log2_and_exp2_approximations_are_within_their_bounds() {
        let (mut worst_log, mut worst_exp): (f64, f64) = (0.0, 0.0);
        let mut x = 1e-300;
        while x < 1e300 {
            worst_log = worst_log.max((log2_approx(x) - x.log2()).abs());
            x *= 1.0007;
        }
        for i in -200_000..=200_000 {
            let y = i as f64 * 1e-4;
            worst_exp = worst_exp.max((exp2_approx(y) / y.exp2() - 1.0).abs());
        }
        assert!(worst_log < 1.2e-4, "log2: {worst_log:e}");
        assert!(worst_exp < 1.2e-4, "exp2: {worst_exp:e}");
        assert!(worst_log > 0.0 && worst_exp > 0.0, "compared something");
        assert_eq!(log2_approx(1.0), 0.0);
        assert_eq!(log2_approx(0.25), -2.0);
        // Monotone across a binade boundary (the controller's factor must not jump).
        let below_two = f64::from_bits(2f64.to_bits() - 1);
        assert!(log2_approx(below_two) <= 1.0 && log2_approx(2.0) == 1.0);
        assert_eq!(exp2_approx(0.0), 1.0);
        assert_eq!(exp2_approx(-3.0), 0.125);
        assert_eq!(exp2_approx(f64::NAN), 1.0);
        assert_eq!(exp2_approx(5000.0), 2f64.powi(1000));
    }
}
