//! Sine and cosine of an exactly known phase, in f32, without f64 or a library call.
//!
//! The phase is a fraction of a turn in fixed point (`u32`: `2^32` = one turn), computed from
//! the integer tick, so it is exact to `2^-32` turn. It is reduced exactly (integer
//! arithmetic) to the nearest quarter turn plus a remainder `|x| <= pi/4`, where short Taylor
//! polynomials are accurate to about one f32 ulp (truncation `< 2e-9` relative). Cost: about
//! 20 single-precision flops; no division, no table.
//!
//! (Why not `libm::sinf`/`cosf`: the musl-derived kernels compute in f64, which is
//! soft-float on a Cortex-M4F and costs several hundred instructions per call.)

use core::f32::consts::TAU;

/// One turn in `u32` fixed point, as f32 radians per unit.
const RAD_PER_UNIT: f32 = TAU / 4_294_967_296.0;

// Taylor coefficients (|x| <= pi/4: the first omitted terms are x^11/11! and x^12/12!).
const S3: f32 = -1.0 / 6.0;
const S5: f32 = 1.0 / 120.0;
const S7: f32 = -1.0 / 5040.0;
const S9: f32 = 1.0 / 362_880.0;
const C2: f32 = -0.5;
const C4: f32 = 1.0 / 24.0;
const C6: f32 = -1.0 / 720.0;
const C8: f32 = 1.0 / 40_320.0;
const C10: f32 = -1.0 / 3_628_800.0;

/// `(sin, cos)` of `2 pi * phase / 2^32`.
#[inline]
pub fn sin_cos_turns(phase: u32) -> (f32, f32) {
    // Nearest quarter turn and the signed remainder, both exact.
    let quarter = phase.wrapping_add(1 << 29) >> 30;
    let rem = phase.wrapping_sub(quarter << 30) as i32; // in [-2^29, 2^29)
    let x = rem as f32 * RAD_PER_UNIT;
    let x2 = x * x;
    let s = x + x * x2 * (S3 + x2 * (S5 + x2 * (S7 + x2 * S9)));
    let c = 1.0 + x2 * (C2 + x2 * (C4 + x2 * (C6 + x2 * (C8 + x2 * C10))));
    match quarter & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A fraction of a turn `turns` (any real) in `u64` fixed point (`2^64` = one turn), modulo 1.
/// Only used at construction time (f64 is fine there).
pub fn turns_to_fixed64(turns: f64) -> u64 {
    let frac = turns - libm::floor(turns);
    // frac in [0, 1): the product is < 2^64 except for rounding at the very top.
    let scaled = frac * 18_446_744_073_709_551_616.0;
    if scaled >= 18_446_744_073_709_551_615.0 {
        0
    } else {
        scaled as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_f64_sin_cos(phase in any::<u32>()) {
            let (s, c) = sin_cos_turns(phase);
            let a = phase as f64 / 4_294_967_296.0 * core::f64::consts::TAU;
            prop_assert!((s as f64 - libm::sin(a)).abs() < 2.5e-7, "sin {} vs {}", s, libm::sin(a));
            prop_assert!((c as f64 - libm::cos(a)).abs() < 2.5e-7, "cos {} vs {}", c, libm::cos(a));
        }
    }

    #[test]
    fn quarter_turns_are_exact() {
        assert_eq!(sin_cos_turns(0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(1 << 30), (1.0, -0.0));
        assert_eq!(sin_cos_turns(1 << 31), (-0.0, -1.0));
        assert_eq!(sin_cos_turns(3 << 30), (-1.0, 0.0));
    }

    #[test]
    fn fixed_point_turns() {
        assert_eq!(turns_to_fixed64(0.25), 1u64 << 62);
        assert_eq!(turns_to_fixed64(-0.25), 3u64 << 62);
        assert_eq!(turns_to_fixed64(7.0), 0);
    }
}
