//! Adaptive Dormand-Prince 5(4) with dense output and event location.
//!
//! The step is the classic DOPRI5 tableau (FSAL), error control with the weighted max norm
//! `max_i |err_i| / (atol + rtol s_i)` (as MATLAB's ode45) and a PI step-size controller. The
//! scale `s_i` of the relative part is `max(|y0_i - o_i|, |y1_i - o_i|)` at the step's ends,
//! measured from an origin `o` ([`DormandPrince::origin`]); for the components marked in
//! [`DormandPrince::scale_by_largest`] it is the largest such value reached so far in the run
//! (Gear's `YMAX`, DIFSUB 1971): a component that oscillates about zero is then held to `rtol`
//! of its amplitude rather than of its value at the step, which tightens at every crossing.
//! Dense output is the standard 4th-order continuous extension of Dormand-Prince
//! (Hairer, Norsett & Wanner, `dopri5` `contd5`). Events are located on the dense output
//! by the Illinois variant of regula falsi. Deterministic: no clocks, no randomness.

use crate::fastmath::{cubic, exp2_in_range, exponent_and_fraction, log2_approx};
use core::array::from_fn;
use nalgebra::SVector;

/// Dense output of one accepted step: `y(t)` for `t` in `[t0, t0 + h]`.
#[derive(Clone, Copy, Debug)]
pub struct DenseStep<const N: usize> {
    /// Start of the step, s.
    pub t0: f64,
    /// End of the step, s (exactly the requested limit when the step was cut to it).
    pub t1: f64,
    h: f64,
    rc: [[f64; N]; 5],
    /// `rc[0] + rc[1]`: the state at `t1` (the continuous extension's value there).
    end: [f64; N],
}

/// The dense output at one time: components evaluated on demand.
#[derive(Clone, Copy, Debug)]
pub struct DensePoint<'a, const N: usize> {
    step: &'a DenseStep<N>,
    /// `(theta, 1 - theta)` inside the step; `None` at or after its end.
    theta: Option<(f64, f64)>,
}

impl<const N: usize> DensePoint<'_, N> {
    /// Component `i` of the state.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        let s = self.step;
        match self.theta {
            None => s.end[i],
            Some((th, th1)) => {
                s.rc[0][i]
                    + (s.rc[1][i] + (s.rc[2][i] + (s.rc[3][i] + s.rc[4][i] * th1) * th) * th1) * th
            }
        }
    }

    /// The whole state.
    #[inline]
    pub fn state(&self) -> SVector<f64, N> {
        SVector::from_fn(|i, _| self.get(i))
    }
}

impl<const N: usize> DenseStep<N> {
    /// The dense output at `t` (4th-order continuous extension; exact at both ends).
    #[inline]
    pub fn at(&self, t: f64) -> DensePoint<'_, N> {
        let theta = if t >= self.t1 {
            None
        } else {
            let th = (t - self.t0) / self.h;
            Some((th, 1.0 - th))
        };
        DensePoint { step: self, theta }
    }

    /// State at `t` (4th-order continuous extension; exact at both ends).
    #[inline]
    pub fn eval(&self, t: f64) -> SVector<f64, N> {
        self.at(t).state()
    }

    /// State at the end of the step.
    #[inline]
    pub fn end_state(&self) -> SVector<f64, N> {
        SVector::from(self.end)
    }
}

/// Why a step could not be taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepFailure {
    /// The step size fell below the resolution of `t`.
    StepSizeTooSmall {
        /// Time, s.
        t: f64,
        /// Step, s.
        h: f64,
    },
    /// The right-hand side or the state became NaN/infinite.
    NonFinite {
        /// Time, s.
        t: f64,
    },
}

// Dormand-Prince 5(4) tableau.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output coefficients (contd5).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Number of distinct stage times of a step: `t0 + c_i h` for `c = 0, 1/5, 3/10, 4/5, 8/9, 1`
/// (the seventh stage, FSAL, is at the step's end like the sixth).
pub const STAGE_TIMES: usize = 6;

/// Index into the stage times of the stage evaluating the step's end (the sixth stage and the
/// FSAL stage share it).
pub const END_STAGE: usize = STAGE_TIMES - 1;

/// The right-hand side `y' = f(t, y)` of [`DormandPrince::step`].
///
/// Before the stages of each attempted step, [`stage_times`](Self::stage_times) names their
/// times, so a right-hand side with a part that depends on time alone (a prescribed stroke,
/// a held motor force) can evaluate it for all stages at once; `eval` then says which stage
/// it is. Any `FnMut(f64, &SVector) -> SVector` closure is a right-hand side without that.
pub trait Rhs<const N: usize> {
    /// The stages of the next attempted step are at `times` (`t0 + c_i h`, in order; the
    /// last is the step's end, shared by the sixth and the FSAL stage).
    #[inline]
    fn stage_times(&mut self, times: &[f64; STAGE_TIMES]) {
        let _ = times;
    }
    /// `y'` at `t`, the time of stage `stage` (an index into the last
    /// [`stage_times`](Self::stage_times)), or not a stage of the current step when
    /// `stage >= STAGE_TIMES` (the first stage of a step without FSAL).
    fn eval(&mut self, stage: usize, t: f64, y: &SVector<f64, N>) -> SVector<f64, N>;
}

impl<const N: usize, F: FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>> Rhs<N> for F {
    #[inline]
    fn eval(&mut self, _stage: usize, t: f64, y: &SVector<f64, N>) -> SVector<f64, N> {
        self(t, y)
    }
}

/// `log2 0.9`: the controller's safety factor.
const LOG2_SAFETY: f64 = -0.152_003_093_445_049_97;
/// `log2 0.2`: the most a rejected step shrinks.
const LOG2_FAC_MIN: f64 = 1.0 - core::f64::consts::LOG2_10;
/// The smallest previous error the PI controller remembers (Hairer's `facold`).
const ERR_OLD_MIN: f64 = 1e-4;

/// The Dormand-Prince 5(4) stepper: tolerances, current step size, FSAL stage, counters.
#[derive(Clone, Debug)]
pub struct DormandPrince<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Largest step, s.
    pub max_step: f64,
    /// Origin of the relative tolerance: component `i` is weighted by
    /// `atol + rtol |y_i - origin_i|` (at the step's ends). Set it before the first step.
    pub origin: SVector<f64, N>,
    /// Components whose relative tolerance is taken of the largest `|y_i - origin_i|`
    /// reached so far in the run instead (Gear's `YMAX`).
    pub scale_by_largest: [bool; N],
    /// Largest `|y_i - origin_i|` at the accepted step ends so far.
    reached: [f64; N],
    h: f64,
    fsal: Option<[f64; N]>,
    /// Dense output of the last accepted step.
    dense: DenseStep<N>,
    /// `err_old^beta` of the PI controller.
    err_old_power: f64,
    /// Right-hand-side evaluations so far.
    pub rhs_evaluations: u64,
    /// Accepted steps so far.
    pub accepted: u64,
    /// Rejected steps so far.
    pub rejected: u64,
}

impl<const N: usize> DormandPrince<N> {
    /// A stepper with the given tolerances and largest step; first step `initial_step`.
    pub fn new(rtol: f64, atol: f64, max_step: f64, initial_step: f64) -> Self {
        Self {
            rtol,
            atol,
            max_step,
            origin: SVector::zeros(),
            scale_by_largest: [false; N],
            reached: [0.0; N],
            h: initial_step.min(max_step),
            fsal: None,
            dense: DenseStep {
                t0: 0.0,
                t1: 0.0,
                h: 0.0,
                rc: [[0.0; N]; 5],
                end: [0.0; N],
            },
            err_old_power: remembered_error_power(ERR_OLD_MIN),
            rhs_evaluations: 0,
            accepted: 0,
            rejected: 0,
        }
    }

    /// Forget the last stage (the right-hand side changed: a mode switch or a breakpoint).
    pub fn discontinuity(&mut self) {
        self.fsal = None;
    }

    /// Take one accepted step from `(t, y)`, never past `t_limit` (a step reaching it ends
    /// exactly on it). `f` is the right-hand side. The step's dense output is then
    /// [`dense`](Self::dense).
    ///
    /// The stages are combined component by component in plain arrays.
    pub fn step<F: Rhs<N>>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &SVector<f64, N>,
        t_limit: f64,
    ) -> Result<(), StepFailure> {
        let y0: [f64; N] = (*y).into();
        let k1 = match self.fsal {
            Some(k) => k,
            None => {
                self.rhs_evaluations += 1;
                f.eval(STAGE_TIMES, t, y).into()
            }
        };
        let min_h = 16.0 * f64::EPSILON * t.abs().max(1e-3);
        loop {
            let mut h = self.h.min(self.max_step);
            let remaining = t_limit - t;
            let mut t1 = t + h;
            if h >= remaining * (1.0 - 1e-12) {
                h = remaining;
                t1 = t_limit;
            } else if h > 0.5 * remaining {
                // Avoid a sliver step before the limit.
                h = 0.5 * remaining;
                t1 = t + h;
            }
            if h < min_h {
                return Err(StepFailure::StepSizeTooSmall { t, h });
            }
            let times = [t, t + C2 * h, t + C3 * h, t + C4 * h, t + C5 * h, t1];
            f.stage_times(&times);
            let mut rhs = |stage: usize, y: [f64; N]| -> [f64; N] {
                f.eval(stage, times[stage], &SVector::from(y)).into()
            };
            // Each stage state is the part already known (earlier stages) plus the newest
            // stage's term: only one multiply-add waits on the right-hand side just evaluated.
            let hk = |c: f64, k: &[f64; N]| -> [f64; N] { from_fn(|i| k[i] * (c * h)) };
            let add = |a: [f64; N], b: [f64; N]| -> [f64; N] { from_fn(|i| a[i] + b[i]) };
            let k2 = rhs(1, add(y0, hk(A21, &k1)));
            let base3 = add(y0, hk(A31, &k1));
            let k3 = rhs(2, add(base3, hk(A32, &k2)));
            let base4 = add(add(y0, hk(A41, &k1)), hk(A42, &k2));
            let k4 = rhs(3, add(base4, hk(A43, &k3)));
            let base5 = add(add(add(y0, hk(A51, &k1)), hk(A52, &k2)), hk(A53, &k3));
            let k5 = rhs(4, add(base5, hk(A54, &k4)));
            let base6 = add(
                add(add(add(y0, hk(A61, &k1)), hk(A62, &k2)), hk(A63, &k3)),
                hk(A64, &k4),
            );
            let k6 = rhs(END_STAGE, add(base6, hk(A65, &k5)));
            let base7 = add(
                add(add(add(y0, hk(A71, &k1)), hk(A73, &k3)), hk(A74, &k4)),
                hk(A75, &k5),
            );
            let y1 = add(base7, hk(A76, &k6));
            let err_base = add(
                add(add(add(hk(E1, &k1), hk(E3, &k3)), hk(E4, &k4)), hk(E5, &k5)),
                hk(E6, &k6),
            );
            let k7 = rhs(END_STAGE, y1);
            self.rhs_evaluations += 6;
            // Max norm over components (as MATLAB's ode45): every component meets its tolerance.
            let mut err: f64 = 0.0;
            let mut reached = self.reached;
            for i in 0..N {
                let err_i = err_base[i] + k7[i] * (E7 * h);
                let o = self.origin[i];
                let here = (y0[i] - o).abs().max((y1[i] - o).abs());
                reached[i] = reached[i].max(here);
                let scale = if self.scale_by_largest[i] {
                    reached[i]
                } else {
                    here
                };
                // The reciprocal of the weight is ready before the error (which waits on the
                // last stage): the division is off the step's critical path.
                let per_sk = 1.0 / (self.atol + self.rtol * scale);
                let ratio = (err_i * per_sk).abs();
                // NaN-propagating max (`f64::max` would drop a NaN component).
                if ratio.is_nan() || ratio > err {
                    err = ratio;
                }
            }
            if !err.is_finite() {
                self.rejected += 1;
                self.h = 0.1 * h;
                if !y1.iter().all(|v| v.is_finite()) && self.h < min_h {
                    return Err(StepFailure::NonFinite { t });
                }
                continue;
            }
            if err <= 1.0 {
                // PI controller: fac = 0.9 err^-(0.2 - 0.75 beta) err_old^beta, beta = 0.04, at
                // most 10. The error's power comes from its exponent (a table) and its mantissa
                // (a cubic): the shortest chain from this step's error to the next step's
                // stages, which all wait for it. The old error's power is for the next step's
                // controller, off that chain, by the same table-and-cubic form. With err <= 1
                // and err_old >= 1e-4 the factor is at least 0.9 * 1e-4^beta = 0.62, so the
                // lower clamp (0.2) cannot bind.
                let fac = (safety_times_error_power(err) * self.err_old_power).min(10.0);
                self.err_old_power = remembered_error_power(err);
                let h_next = h * fac;
                // A step cut short by t_limit keeps its own proposal for the next step.
                self.h = if t1 == t_limit {
                    self.h.max(h_next)
                } else {
                    h_next
                };
                self.fsal = Some(k7);
                self.reached = reached;
                self.accepted += 1;
                let d = &mut self.dense;
                d.t0 = t;
                d.t1 = t1;
                d.h = t1 - t;
                for i in 0..N {
                    let rc2 = y1[i] - y0[i];
                    let rc3 = k1[i] * h - rc2;
                    d.rc[0][i] = y0[i];
                    d.rc[1][i] = rc2;
                    d.rc[2][i] = rc3;
                    d.rc[3][i] = rc2 - k7[i] * h - rc3;
                    d.rc[4][i] = (k1[i] * D1
                        + k3[i] * D3
                        + k4[i] * D4
                        + k5[i] * D5
                        + k6[i] * D6
                        + k7[i] * D7)
                        * h;
                    d.end[i] = y0[i] + rc2;
                }
                return Ok(());
            }
            self.rejected += 1;
            self.h = h * exp2_in_range((LOG2_SAFETY - 0.2 * log2_approx(err)).max(LOG2_FAC_MIN));
        }
    }

    /// Dense output of the last accepted step.
    #[inline]
    pub fn dense(&self) -> &DenseStep<N> {
        &self.dense
    }
}

/// `0.9 * 2^(0.17 i)` for `i = 0..64`: the controller's `0.9 err^-0.17` at `err = 2^-i`.
#[allow(clippy::excessive_precision)]
const SAFETY_TIMES_POWER_OF_TWO: [f64; 64] = [
    0.9,
    1.0125526362199284,
    1.139180934573252,
    1.2816451760373646,
    1.4419257796613199,
    1.6222508326994947,
    1.8251270636220525,
    2.053374688563163,
    2.3101666156132277,
    2.5990725519404934,
    2.924108626882448,
    3.289793220825842,
    3.7012097759618396,
    4.164077462059034,
    4.684830679590962,
    5.270708505404253,
    5.929855324326527,
    6.67143404561067,
    7.505753478056074,
    8.444411634469532,
    9.500456957564841,
    10.688569708529156,
    12.025266039768521,
    13.529127588681773,
    15.221059784083879,
    17.12458245603918,
    19.266156788920014,
    21.67555316271938,
    24.386264996040794,
    27.435974343665407,
    30.867075721045257,
    34.72726543749391,
    39.07020463049296,
    43.95626521806412,
    49.45336913881463,
    55.63793254607111,
    62.59592808150096,
    70.42407999506315,
    79.23120872484928,
    89.13974362804171,
    100.28742489171356,
    112.82921828201403,
    126.9394693489856,
    142.8143270329713,
    160.67447036356674,
    180.7681761554114,
    203.37477034536693,
    228.8085109486931,
    257.4229566118395,
    289.6158814898293,
    325.83480477076114,
    366.5832117142665,
    412.4275526836097,
    464.00511746613597,
    522.0328943443046,
    587.3175370687165,
    660.7665782856939,
    743.4010452991123,
    836.3696535402962,
    940.96477505175,
    1058.6404039652682,
    1191.0323687155137,
    1339.981071962399,
    1507.5570743337032,
];

/// `0.9 err^-(0.2 - 0.75 beta)` (the PI controller's error term with its safety factor) for
/// `0 <= err <= 1`, to about 1.2e-4 relative: `err = 2^-i m` with `m` in `[1, 2)`, the power of
/// `2^-i` from [`SAFETY_TIMES_POWER_OF_TWO`] and `m^-0.17` a cubic least-squares fit in `m - 1`.
/// No division, no branch, no `log2`/`exp2` round trip. Below `2^-63` (and at 0) it gives the
/// value at `2^-63`, about 1,700: past the controller's largest factor, 10, either way.
#[inline]
fn safety_times_error_power(err: f64) -> f64 {
    const M: [f64; 4] = [
        0.999_885_085_547_368_2,
        -0.166_073_760_447_089_5,
        0.076_678_414_548_524_46,
        -0.021_723_603_268_657_767,
    ];
    power_by_exponent_and_mantissa(&SAFETY_TIMES_POWER_OF_TWO, &M, err)
}

/// A power of `x = 2^-i m` (`m` in `[1, 2)`) for `0 < x <= 1`: the power of `2^-i` from
/// `table[i]` (`i` clamped to the table) times the power of `m` from the cubic `mantissa`
/// in `m - 1`.
#[inline]
fn power_by_exponent_and_mantissa<const K: usize>(
    table: &[f64; K],
    mantissa: &[f64; 4],
    x: f64,
) -> f64 {
    let (e, t) = exponent_and_fraction(x);
    let minus_exponent = (-e).clamp(0, K as i64 - 1) as usize;
    table[minus_exponent] * cubic(mantissa, t)
}

/// `2^(-beta i)` for `i = 0..=14`, with Hairer's `beta` = 0.04 of the PI step-size controller:
/// its `err_old^beta` at `err_old = 2^-i` (`2^-14 < 1e-4`, the smallest error it remembers).
#[allow(clippy::excessive_precision)]
const POWER_OF_TWO_TO_BETA: [f64; 15] = [
    1.0,
    0.9726549474122855,
    0.9460576467255959,
    0.9201876506248751,
    0.8950250709279725,
    0.8705505632961241,
    0.8467453123625271,
    0.8235910172675731,
    0.8010698775896221,
    0.7791645796604999,
    0.757858283255199,
    0.7371346086455506,
    0.7169776240079136,
    0.6973718331752027,
    0.6783021637238359,
];

/// `max(err, 1e-4)^beta` for `err <= 1`, the PI controller's memory of an accepted step's
/// error, to about 3.5e-5 relative: the power of the exponent from [`POWER_OF_TWO_TO_BETA`],
/// `m^beta` of the mantissa `m` in `[1, 2)` a cubic least-squares fit in `m - 1`. No
/// `log2`/`exp2` round trip. (`err > 1` is never remembered: such a step is rejected.)
#[inline]
fn remembered_error_power(err: f64) -> f64 {
    const M: [f64; 4] = [
        1.000_034_780_401_279_5,
        0.039_239_497_432_078_545,
        -0.015_207_824_591_934_61,
        0.004_073_028_142_602_006,
    ];
    power_by_exponent_and_mantissa(&POWER_OF_TWO_TO_BETA, &M, err.max(ERR_OLD_MIN))
}

/// First time in `(a, b]` where `g` turns positive, given `g(a) <= 0 < g(b)`, located to
/// `tol_s`: returns the right end of the final bracket, so `g(returned) > 0`.
pub fn locate_crossing<G: FnMut(f64) -> f64>(
    mut g: G,
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    tol_s: f64,
) -> f64 {
    let mut side = 0i8;
    for _ in 0..200 {
        if b - a <= tol_s {
            break;
        }
        // Illinois regula falsi, falling back to bisection when the secant is unhelpful.
        let mut m = (a * gb - b * ga) / (gb - ga);
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
        }
        let gm = g(m);
        if gm > 0.0 {
            b = m;
            gb = gm;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = m;
            ga = gm;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hairer's `beta` of the PI step-size controller (the tables hold its powers).
    const PI_BETA: f64 = 0.04;
    use nalgebra::Vector2;

    #[test]
    fn harmonic_oscillator_is_accurate_and_dense_output_matches() {
        let mut dp = DormandPrince::<2>::new(1e-10, 1e-12, 0.1, 1e-4);
        let mut f = |_t: f64, y: &Vector2<f64>| Vector2::new(y[1], -y[0]);
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
        let mut worst: f64 = 0.0;
        while t < 10.0 {
            dp.step(&mut f, t, &y, 10.0).unwrap();
            let s = dp.dense();
            for k in 1..4 {
                let tm = s.t0 + (s.t1 - s.t0) * k as f64 / 4.0;
                worst = worst.max((s.eval(tm)[0] - tm.cos()).abs());
            }
            t = s.t1;
            y = s.end_state();
        }
        assert_eq!(t, 10.0, "the last step lands exactly on the limit");
        assert!(
            (y[0] - 10f64.cos()).abs() < 1e-8,
            "end error {}",
            (y[0] - 10f64.cos()).abs()
        );
        assert!(worst < 1e-7, "dense output error {worst}");
    }

    #[test]
    fn a_step_with_a_nan_component_is_never_accepted() {
        // The second component turns NaN past t = 0.5: no accepted step may carry it.
        let mut dp = DormandPrince::<2>::new(1e-8, 1e-11, 0.1, 1e-3);
        let mut f =
            |t: f64, y: &Vector2<f64>| Vector2::new(y[1], if t > 0.5 { f64::NAN } else { -y[0] });
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
        loop {
            match dp.step(&mut f, t, &y, 1.0) {
                Ok(()) => {
                    let d = dp.dense();
                    y = d.end_state();
                    t = d.t1;
                    assert!(y.iter().all(|v| v.is_finite()), "accepted {y:?} at t = {t}");
                }
                Err(e) => {
                    assert!(t <= 0.5, "failed at {t}: {e:?}");
                    break;
                }
            }
        }
    }

    #[test]
    fn scaling_by_the_largest_value_reached_spares_steps_at_zero_crossings() {
        // x = cos t, v = -sin t: both cross zero every half period. With atol far below
        // rtol, a tolerance taken of the value at the step collapses near each crossing.
        let run = |largest: bool| {
            let mut dp = DormandPrince::<2>::new(1e-8, 1e-16, 0.1, 1e-4);
            dp.scale_by_largest = [largest; 2];
            let mut f = |_t: f64, y: &Vector2<f64>| Vector2::new(y[1], -y[0]);
            let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
            let mut worst: f64 = 0.0;
            while t < 20.0 {
                dp.step(&mut f, t, &y, 20.0).unwrap();
                t = dp.dense().t1;
                y = dp.dense().end_state();
                worst = worst
                    .max((y[0] - t.cos()).abs())
                    .max((y[1] + t.sin()).abs());
            }
            (dp.accepted + dp.rejected, worst)
        };
        let ((plain_steps, plain_err), (largest_steps, largest_err)) = (run(false), run(true));
        assert!(
            largest_steps * 10 < plain_steps * 9,
            "{largest_steps} steps vs {plain_steps}"
        );
        // Still held to rtol of the amplitude (global error over three periods).
        assert!(
            largest_err < 1e-7,
            "error {largest_err:e} (plain {plain_err:e})"
        );
    }

    #[test]
    fn the_controllers_error_power_is_within_its_bound() {
        let want = |err: f64| 0.9 * err.powf(-(0.2 - 0.75 * PI_BETA));
        for (i, v) in SAFETY_TIMES_POWER_OF_TWO.iter().enumerate() {
            let exact = want(2f64.powi(-(i as i32)));
            assert!(
                (v / exact - 1.0).abs() < 1e-15,
                "table entry {i}: {v} vs {exact}"
            );
        }
        let mut worst: f64 = 0.0;
        let mut err = 1.0;
        while err > 2f64.powi(-63) {
            worst = worst.max((safety_times_error_power(err) / want(err) - 1.0).abs());
            err *= 0.999_3;
        }
        assert!(worst < 1.2e-4 && worst > 0.0, "worst {worst:e}");
        // Tiny errors and zero give about the 2^-63 value: far past the largest factor, 10.
        for tiny in [0.0, 1e-300, 5e-324, 1e-20] {
            assert!(safety_times_error_power(tiny) > 1000.0, "{tiny:e}");
        }
    }

    #[test]
    fn the_remembered_error_power_is_within_its_bound() {
        let want = |err: f64| err.max(ERR_OLD_MIN).powf(PI_BETA);
        for (i, v) in POWER_OF_TWO_TO_BETA.iter().enumerate() {
            let exact = 2f64.powi(-(i as i32)).powf(PI_BETA);
            assert!(
                (v / exact - 1.0).abs() < 1e-15,
                "table entry {i}: {v} vs {exact}"
            );
        }
        let mut worst: f64 = 0.0;
        let mut err = 1.0;
        while err > 1e-6 {
            worst = worst.max((remembered_error_power(err) / want(err) - 1.0).abs());
            err *= 0.999_3;
        }
        assert!(worst < 3.6e-5 && worst > 0.0, "worst {worst:e}");
        // Below 1e-4 the error is remembered as 1e-4.
        for tiny in [0.0, 1e-300, 1e-9, 9.9e-5] {
            assert_eq!(
                remembered_error_power(tiny),
                remembered_error_power(ERR_OLD_MIN)
            );
        }
    }

    #[test]
    fn crossing_is_located_to_tolerance() {
        let root = 0.5f64.ln().abs(); // exp(-t) = 0.5
        let g = |t: f64| 0.5 - (-t).exp();
        let t = locate_crossing(g, 0.0, g(0.0), 2.0, g(2.0), 1e-13);
        assert!(t >= root && t - root < 1e-12, "t = {t}, root = {root}");
    }
}
