//! Position controller for the motor: PD on position error, acceleration feedforward, optional
//! integral with anti-windup, saturation at the drive limit, and the gain schedule used for
//! gain-lowering damping.
//!
//! Once per control tick:
//!
//! ```text
//! e   = p_cmd - p                      (m)
//! u   = m_ff a_cmd + s_p kp e + s_d kd (v_cmd - v_est) + I       (N)
//! F   = clamp(u, -F_max, F_max)
//! I  += s_p ki e dt    unless u is saturated and e pushes it further (conditional
//!                      integration), then I is clamped to +-integral_limit_n
//! ```
//!
//! `s_p`, `s_d` are the gain-schedule factors (1 outside the delay). The integral state is
//! stored in newtons (already multiplied by `ki`), so changing gains never steps the force:
//! gain changes are bumpless by construction, and the schedule itself is C2-smooth.
//!
//! `v_est` comes from [`VelocityEstimator`]: encoder count differences times
//! `metres_per_count * tick_hz`, through a first-order low-pass
//! `v += alpha (v_raw - v)`, `alpha = 1 - exp(-2 pi f_c / tick_hz)` (default `f_c` 2 kHz, see
//! [`RigConfig::velocity_cutoff_hz`](crate::RigConfig::velocity_cutoff_hz)).

use crate::config_error::{ConfigError, field as check};

/// Controller gains (part of a jump's configuration).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gains {
    /// Proportional gain, N/m.
    pub kp_n_per_m: f32,
    /// Derivative gain on the velocity error, N s/m.
    pub kd_n_s_per_m: f32,
    /// Integral gain, N/(m s); 0 disables the integrator.
    pub ki_n_per_m_s: f32,
    /// Anti-windup clamp on the integral term, N.
    pub integral_limit_n: f32,
    /// Acceleration feedforward mass, kg (`F_ff = m * a_cmd`).
    pub feedforward_mass_kg: f32,
}

impl Default for Gains {
    /// Chosen defaults: a ~50 Hz position loop on the motor/rod reduced mass
    /// (`m_m m_r / (m_m + m_r)` = 0.1125 kg), critically damped, no integrator, feedforward with
    /// the reduced mass.
    fn default() -> Self {
        Self {
            kp_n_per_m: 11_000.0,
            kd_n_s_per_m: 70.0,
            ki_n_per_m_s: 0.0,
            integral_limit_n: 20.0,
            feedforward_mass_kg: 0.1125,
        }
    }
}

impl Gains {
    /// All finite and non-negative (kp up to 1e7 N/m, kd up to 1e5 N s/m, ki up to 1e9).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let nonneg = |v: f32, max: f32| v.is_finite() && (0.0..=max).contains(&v);
        check(
            "kp_n_per_m",
            self.kp_n_per_m,
            nonneg(self.kp_n_per_m, 1e7),
            "0..=1e7 N/m",
        )?;
        check(
            "kd_n_s_per_m",
            self.kd_n_s_per_m,
            nonneg(self.kd_n_s_per_m, 1e5),
            "0..=1e5 N s/m",
        )?;
        check(
            "ki_n_per_m_s",
            self.ki_n_per_m_s,
            nonneg(self.ki_n_per_m_s, 1e9),
            "0..=1e9 N/(m s)",
        )?;
        check(
            "integral_limit_n",
            self.integral_limit_n,
            nonneg(self.integral_limit_n, 1e4),
            "0..=1e4 N",
        )?;
        check(
            "feedforward_mass_kg",
            self.feedforward_mass_kg,
            nonneg(self.feedforward_mass_kg, 100.0),
            "0..=100 kg",
        )
    }
}

/// Gain-lowering damping: during a delayed stutter's delay, scale the position gains down by
/// `kp_factor` (and the velocity gain by `kd_factor`), with smooth ramps of `ramp_s` at both
/// ends so the gains are back to full when the push-off starts.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GainLowering {
    /// Factor on kp (and ki) in the middle of the delay, `0 < f <= 1`.
    pub kp_factor: f32,
    /// Factor on kd in the middle of the delay, `0 < f <= 1`.
    pub kd_factor: f32,
    /// Length of each ramp, s (`0 < ramp <= 2.5`); shortened to half the delay if longer.
    pub ramp_s: f32,
}

impl GainLowering {
    /// Factors in `(0, 1]`, ramp in `(0, 2.5]` s.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let factor = |v: f32| v > 0.0 && v <= 1.0;
        check(
            "kp_factor",
            self.kp_factor,
            factor(self.kp_factor),
            "0 < factor <= 1",
        )?;
        check(
            "kd_factor",
            self.kd_factor,
            factor(self.kd_factor),
            "0 < factor <= 1",
        )?;
        check(
            "ramp_s",
            self.ramp_s,
            self.ramp_s > 0.0 && self.ramp_s <= 2.5,
            "0 < ramp <= 2.5 s",
        )
    }
}

/// Gain factors for one tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GainScale {
    /// Factor on kp and ki.
    pub position: f32,
    /// Factor on kd.
    pub velocity: f32,
}

impl GainScale {
    /// Full gains.
    pub const FULL: GainScale = GainScale {
        position: 1.0,
        velocity: 1.0,
    };
}

/// The gain schedule of one jump, in ticks since the trajectory start.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GainSchedule {
    n0: u32,
    n1: u32,
    ramp_ticks: u32,
    inv_ramp: f32,
    low: GainScale,
}

/// `6x^5 - 15x^4 + 10x^3`: 0 -> 1 with zero first and second derivatives at both ends.
#[inline]
fn smootherstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (x * (x * 6.0 - 15.0) + 10.0)
}

impl GainSchedule {
    /// Lower the gains inside the delay `[n0, n1)` (ticks since the start).
    pub fn new(lowering: &GainLowering, n0: u32, n1: u32, tick_hz: u32) -> Self {
        let half = (n1.saturating_sub(n0)) / 2;
        let ramp_ticks = ((lowering.ramp_s * tick_hz as f32) as u32).clamp(1, half.max(1));
        Self {
            n0,
            n1,
            ramp_ticks,
            inv_ramp: 1.0 / ramp_ticks as f32,
            low: GainScale {
                position: lowering.kp_factor,
                velocity: lowering.kd_factor,
            },
        }
    }

    /// Factors at tick `n`: 1 outside the delay, ramping smoothly to the low factors within
    /// `ramp` of the delay's start and back to 1 by its end.
    #[inline]
    pub fn scale(&self, n: u32) -> GainScale {
        if n < self.n0 || n >= self.n1 {
            return GainScale::FULL;
        }
        let from_start = n - self.n0;
        let to_end = self.n1 - n;
        let k = from_start.min(to_end);
        if k >= self.ramp_ticks {
            return self.low;
        }
        let depth = smootherstep(k as f32 * self.inv_ramp);
        GainScale {
            position: 1.0 - (1.0 - self.low.position) * depth,
            velocity: 1.0 - (1.0 - self.low.velocity) * depth,
        }
    }
}

/// Velocity from encoder count differences through a first-order low-pass.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VelocityEstimator {
    counts_to_m_s: f32,
    alpha: f32,
    v: f32,
}

impl VelocityEstimator {
    /// `cutoff_hz` below `tick_hz / 2` (checked by the configuration).
    pub fn new(metres_per_count: f32, tick_hz: u32, cutoff_hz: f32) -> Self {
        let alpha = 1.0 - libm::exp(-core::f64::consts::TAU * cutoff_hz as f64 / tick_hz as f64);
        Self {
            counts_to_m_s: metres_per_count * tick_hz as f32,
            alpha: alpha as f32,
            v: 0.0,
        }
    }

    /// Forget the state.
    pub fn reset(&mut self) {
        self.v = 0.0;
    }

    /// Feed one tick's count difference; returns the filtered velocity, m/s.
    #[inline]
    pub fn update(&mut self, delta_counts: i32) -> f32 {
        let raw = delta_counts as f32 * self.counts_to_m_s;
        self.v += self.alpha * (raw - self.v);
        self.v
    }

    /// The current estimate, m/s.
    pub fn velocity_m_s(&self) -> f32 {
        self.v
    }
}

/// What the controller produced on one tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlOutput {
    /// Force command after saturation, N.
    pub force_n: f32,
    /// Position error `p_cmd - p`, m.
    pub error_m: f32,
    /// The unsaturated command exceeded the drive limit.
    pub saturated: bool,
    /// The integrator is held (conditional integration) or at its clamp.
    pub integrator_held: bool,
}

/// PD + feedforward (+ I) position controller.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PositionController {
    gains: Gains,
    drive_limit_n: f32,
    dt_s: f32,
    integral_n: f32,
}

/// `x` limited to `[-limit, limit]`. Unlike `f32::clamp` it has no panic path (that one panics
/// on a NaN or negative limit, and links `core::fmt`'s float printing into the control tick):
/// the limits are validated where they are set, and the tick must not be able to panic at all.
/// A NaN `x` stays NaN, as with `clamp`.
#[inline]
fn clamp_symmetric(x: f32, limit: f32) -> f32 {
    if x > limit {
        limit
    } else if x < -limit {
        -limit
    } else {
        x
    }
}

impl PositionController {
    /// `drive_limit_n`: saturation of the force command, N; `tick_hz`: control rate.
    pub fn new(gains: Gains, drive_limit_n: f32, tick_hz: u32) -> Self {
        Self {
            gains,
            drive_limit_n,
            dt_s: 1.0 / tick_hz as f32,
            integral_n: 0.0,
        }
    }

    /// Replace the gains (the integral term, in newtons, is kept: bumpless).
    pub fn set_gains(&mut self, gains: Gains) {
        self.gains = gains;
        self.integral_n = clamp_symmetric(self.integral_n, gains.integral_limit_n);
    }

    /// The gains in use.
    pub fn gains(&self) -> &Gains {
        &self.gains
    }

    /// The integral term, N.
    pub fn integral_n(&self) -> f32 {
        self.integral_n
    }

    /// Zero the integrator.
    pub fn reset(&mut self) {
        self.integral_n = 0.0;
    }

    /// One control update.
    #[inline]
    pub fn update(
        &mut self,
        sp: &crate::profile::Setpoint,
        position_m: f32,
        velocity_m_s: f32,
        scale: GainScale,
    ) -> ControlOutput {
        let g = &self.gains;
        let error_m = sp.position_m - position_m;
        let u = g.feedforward_mass_kg * sp.accel_m_s2
            + scale.position * g.kp_n_per_m * error_m
            + scale.velocity * g.kd_n_s_per_m * (sp.velocity_m_s - velocity_m_s)
            + self.integral_n;
        let saturated = u.abs() > self.drive_limit_n;
        // Conditional integration: do not integrate further into saturation.
        let winding = saturated && (error_m > 0.0) == (u > 0.0);
        let mut integrator_held = winding;
        if !winding && g.ki_n_per_m_s > 0.0 {
            let next = self.integral_n + scale.position * g.ki_n_per_m_s * error_m * self.dt_s;
            let lim = g.integral_limit_n;
            integrator_held = next.abs() > lim;
            self.integral_n = clamp_symmetric(next, lim);
        }
        ControlOutput {
            force_n: clamp_symmetric(u, self.drive_limit_n),
            error_m,
            saturated,
            integrator_held,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::profile::Setpoint;
    use proptest::prelude::*;

    #[test]
    fn the_symmetric_clamp_limits_and_never_panics() {
        assert_eq!(clamp_symmetric(5.0, 2.0), 2.0);
        assert_eq!(clamp_symmetric(-5.0, 2.0), -2.0);
        assert_eq!(clamp_symmetric(1.5, 2.0), 1.5);
        assert!(clamp_symmetric(f32::NAN, 2.0).is_nan());
        // Limits `f32::clamp` panics on: the value comes through.
        assert_eq!(clamp_symmetric(1.0, f32::NAN), 1.0);
        assert_eq!(clamp_symmetric(0.5, -1.0), -1.0);
    }

    fn sp(p: f32) -> Setpoint {
        Setpoint {
            position_m: p,
            velocity_m_s: 0.0,
            accel_m_s2: 0.0,
        }
    }

    #[test]
    fn pd_plus_feedforward_and_saturation() {
        let g = Gains {
            kp_n_per_m: 1000.0,
            kd_n_s_per_m: 10.0,
            ki_n_per_m_s: 0.0,
            integral_limit_n: 0.0,
            feedforward_mass_kg: 0.5,
        };
        let mut c = PositionController::new(g, 300.0, 10_000);
        let s = Setpoint {
            position_m: 0.01,
            velocity_m_s: 0.2,
            accel_m_s2: 100.0,
        };
        let out = c.update(&s, 0.0, 0.1, GainScale::FULL);
        assert!((out.force_n - (50.0 + 10.0 + 1.0)).abs() < 1e-4);
        assert!(!out.saturated);
        let out = c.update(&sp(1.0), 0.0, 0.0, GainScale::FULL);
        assert_eq!(out.force_n, 300.0);
        assert!(out.saturated);
        let out = c.update(&sp(-1.0), 0.0, 0.0, GainScale::FULL);
        assert_eq!(out.force_n, -300.0);
    }

    proptest! {
        /// Whatever the inputs, the command never exceeds the drive limit and the integral never
        /// exceeds its clamp; a long saturation does not wind the integrator up beyond it.
        #[test]
        fn output_and_integral_bounded(
            errs in proptest::collection::vec(-0.05f32..0.05, 1..300),
            ki in 0.0f32..1e6,
            limit in 0.0f32..50.0,
        ) {
            let g = Gains { kp_n_per_m: 2e4, kd_n_s_per_m: 50.0, ki_n_per_m_s: ki, integral_limit_n: limit, feedforward_mass_kg: 0.1 };
            let mut c = PositionController::new(g, 300.0, 10_000);
            for e in errs {
                let out = c.update(&sp(e), 0.0, 0.0, GainScale::FULL);
                prop_assert!(out.force_n.abs() <= 300.0);
                prop_assert!(c.integral_n().abs() <= limit);
            }
        }
    }

    #[test]
    fn anti_windup_stops_integrating_into_saturation() {
        let g = Gains {
            kp_n_per_m: 1e5,
            kd_n_s_per_m: 0.0,
            ki_n_per_m_s: 1e5,
            integral_limit_n: 100.0,
            feedforward_mass_kg: 0.0,
        };
        let mut c = PositionController::new(g, 300.0, 10_000);
        // 0.01 m error: P alone asks 1000 N > 300 N, so the integrator must stay at 0.
        for _ in 0..1000 {
            let out = c.update(&sp(0.01), 0.0, 0.0, GainScale::FULL);
            assert!(out.saturated && out.integrator_held);
        }
        assert_eq!(c.integral_n(), 0.0);
        // Small error, not saturated: it integrates, up to the clamp.
        for _ in 0..200_000 {
            c.update(&sp(1e-4), 0.0, 0.0, GainScale::FULL);
        }
        assert_eq!(c.integral_n(), 100.0);
        // Saturated high (by the feedforward) while the error is negative: integrating back
        // out of saturation is allowed.
        c.set_gains(Gains {
            feedforward_mass_kg: 1.0,
            ..g
        });
        let before = c.integral_n();
        let s = Setpoint {
            position_m: -1e-4,
            velocity_m_s: 0.0,
            accel_m_s2: 1e4,
        };
        let out = c.update(&s, 0.0, 0.0, GainScale::FULL);
        assert!(out.saturated && out.force_n == 300.0);
        assert!(c.integral_n() < before);
    }

    #[test]
    fn gain_schedule_is_smooth_and_returns_to_full_before_push_off() {
        let low = GainLowering {
            kp_factor: 0.1,
            kd_factor: 0.5,
            ramp_s: 0.05,
        };
        let s = GainSchedule::new(&low, 500, 8000, 10_000);
        assert_eq!(s.scale(499), GainScale::FULL);
        assert_eq!(s.scale(500), GainScale::FULL);
        assert_eq!(
            s.scale(1000),
            GainScale {
                position: 0.1,
                velocity: 0.5
            }
        );
        assert_eq!(
            s.scale(4000),
            GainScale {
                position: 0.1,
                velocity: 0.5
            }
        );
        assert_eq!(s.scale(8000), GainScale::FULL);
        assert_eq!(
            s.scale(7999).position,
            1.0 - 0.9 * smootherstep(1.0 / 500.0)
        );
        // Bumpless: per-tick change bounded by the smootherstep's max slope (15/8 per ramp).
        let mut prev = s.scale(0).position;
        for n in 0..9000 {
            let now = s.scale(n).position;
            assert!((now - prev).abs() <= 0.9 * 1.875 / 500.0 + 1e-6, "n={n}");
            prev = now;
        }
    }

    #[test]
    fn gain_change_does_not_step_force_with_integral() {
        let g = Gains {
            kp_n_per_m: 1e4,
            kd_n_s_per_m: 0.0,
            ki_n_per_m_s: 1e5,
            integral_limit_n: 50.0,
            feedforward_mass_kg: 0.0,
        };
        let mut c = PositionController::new(g, 300.0, 10_000);
        for _ in 0..1000 {
            c.update(&sp(0.0), -0.001, 0.0, GainScale::FULL);
        }
        let i = c.integral_n();
        assert!(i > 1.0);
        // At zero error, switching ki leaves the force unchanged (integral stored in newtons).
        let f0 = c.update(&sp(0.0), 0.0, 0.0, GainScale::FULL).force_n;
        c.set_gains(Gains {
            ki_n_per_m_s: 1e3,
            ..g
        });
        let f1 = c.update(&sp(0.0), 0.0, 0.0, GainScale::FULL).force_n;
        assert_eq!(f0, f1);
    }

    #[test]
    fn velocity_filter_converges_to_count_rate() {
        let mut v = VelocityEstimator::new(1e-6, 10_000, 500.0);
        for _ in 0..200 {
            v.update(30);
        }
        assert!((v.velocity_m_s() - 0.3).abs() < 1e-4);
    }

    /// The field a refusal names.
    fn refused(r: Result<(), ConfigError>) -> Option<&'static str> {
        match r {
            Err(ConfigError::Field { what, .. }) => Some(what),
            _ => None,
        }
    }

    /// Each gain within its range passes, each just outside it (or not a number) is refused
    /// naming itself. Found by `cargo mutants` (the check replaced by `Ok(())` passed every
    /// test of the core).
    #[test]
    fn gains_are_checked_field_by_field() {
        assert_eq!(Gains::default().validate(), Ok(()));
        type Field = fn(&mut Gains) -> &mut f32;
        let limits: [(&str, f32, Field); 5] = [
            ("kp_n_per_m", 1e7, |g| &mut g.kp_n_per_m),
            ("kd_n_s_per_m", 1e5, |g| &mut g.kd_n_s_per_m),
            ("ki_n_per_m_s", 1e9, |g| &mut g.ki_n_per_m_s),
            ("integral_limit_n", 1e4, |g| &mut g.integral_limit_n),
            ("feedforward_mass_kg", 100.0, |g| &mut g.feedforward_mass_kg),
        ];
        for (name, max, field) in limits {
            for ok in [0.0, max] {
                let mut g = Gains::default();
                *field(&mut g) = ok;
                assert_eq!(g.validate(), Ok(()), "{name} = {ok}");
            }
            for bad in [-1e-3, max * 1.001, f32::NAN, f32::INFINITY] {
                let mut g = Gains::default();
                *field(&mut g) = bad;
                assert_eq!(refused(g.validate()), Some(name), "{name} = {bad}");
            }
        }
    }

    /// Factors in (0, 1], the ramp in (0, 2.5] s: each bound, either side. Found by `cargo
    /// mutants` (the check replaced by `Ok(())`, or a bound moved, passed every test).
    #[test]
    fn gain_lowering_is_checked_at_its_bounds() {
        let ok = GainLowering {
            kp_factor: 1.0,
            kd_factor: 1.0,
            ramp_s: 2.5,
        };
        assert_eq!(ok.validate(), Ok(()));
        let cases: [(&str, GainLowering); 6] = [
            (
                "kp_factor",
                GainLowering {
                    kp_factor: 0.0,
                    ..ok
                },
            ),
            (
                "kp_factor",
                GainLowering {
                    kp_factor: 1.001,
                    ..ok
                },
            ),
            (
                "kd_factor",
                GainLowering {
                    kd_factor: 0.0,
                    ..ok
                },
            ),
            (
                "kd_factor",
                GainLowering {
                    kd_factor: 1.001,
                    ..ok
                },
            ),
            ("ramp_s", GainLowering { ramp_s: 0.0, ..ok }),
            (
                "ramp_s",
                GainLowering {
                    ramp_s: 2.501,
                    ..ok
                },
            ),
        ];
        for (name, lowering) in cases {
            assert_eq!(refused(lowering.validate()), Some(name), "{lowering:?}");
        }
        let smallest = GainLowering {
            kp_factor: 1e-6,
            kd_factor: 1e-6,
            ramp_s: 1e-6,
        };
        assert_eq!(smallest.validate(), Ok(()));
    }

    /// Halfway through a ramp the factors are halfway between full and low (the smootherstep
    /// at one half is one half). Found by `cargo mutants` (the ramp's formula changed passed
    /// every test).
    #[test]
    fn halfway_through_the_ramp_the_gains_are_halfway_down() {
        let lowering = GainLowering {
            kp_factor: 0.2,
            kd_factor: 0.6,
            ramp_s: 0.01,
        };
        // A delay of 1,000 ticks from tick 100, ramps of 100 ticks at 10 kHz.
        let s = GainSchedule::new(&lowering, 100, 1100, 10_000);
        let half = s.scale(150);
        assert!((half.position - 0.6).abs() < 1e-6, "{half:?}");
        assert!((half.velocity - 0.8).abs() < 1e-6, "{half:?}");
        assert_eq!(s.scale(99), GainScale::FULL);
        assert_eq!(
            s.scale(600),
            GainScale {
                position: 0.2,
                velocity: 0.6
            }
        );
        assert_eq!(s.scale(1100), GainScale::FULL);
    }

    /// A reset forgets the filtered velocity (a new jump starts from rest). Found by `cargo
    /// mutants` (`reset` emptied passed every test).
    #[test]
    fn a_reset_velocity_estimator_starts_from_rest() {
        let mut v = VelocityEstimator::new(1e-5, 10_000, 200.0);
        for _ in 0..50 {
            v.update(10);
        }
        assert!(v.update(10) > 0.5, "moving at about 1 m/s");
        v.reset();
        let after = v.update(0);
        assert_eq!(after, 0.0, "from rest, no motion: {after}");
    }

    /// The integrator (the slow intrusion's controller runs with one): it sums `ki e dt` each
    /// tick into the force, is held at its limit (and says so), is not wound further into a
    /// saturated drive, and a reset zeroes it. Found by `cargo mutants` (the integrating terms
    /// changed, or `reset` emptied, passed every test: the jump's default gains have no
    /// integrator).
    #[test]
    fn the_integrator_sums_holds_at_its_limit_and_resets() {
        let gains = Gains {
            kp_n_per_m: 0.0,
            kd_n_s_per_m: 0.0,
            ki_n_per_m_s: 1000.0,
            integral_limit_n: 3.0,
            feedforward_mass_kg: 0.0,
        };
        let mut c = PositionController::new(gains, 300.0, 1000);
        // 1 mm of error: 1000 * 0.001 * 0.001 = 1 mN a tick.
        let mut last = c.update(&sp(0.001), 0.0, 0.0, GainScale::FULL);
        assert_eq!(
            last.force_n, 0.0,
            "the integral enters the force from the next tick"
        );
        for _ in 0..9 {
            last = c.update(&sp(0.001), 0.0, 0.0, GainScale::FULL);
        }
        assert!((c.integral_n() - 0.010).abs() < 1e-6, "{}", c.integral_n());
        assert!((last.force_n - 0.009).abs() < 1e-6, "{last:?}");
        assert!(!last.integrator_held && !last.saturated);
        // Half the position gain scales the integration too.
        let before = c.integral_n();
        c.update(
            &sp(0.001),
            0.0,
            0.0,
            GainScale {
                position: 0.5,
                velocity: 1.0,
            },
        );
        assert!((c.integral_n() - before - 0.0005).abs() < 1e-7);
        // A large error: held at 3 N, and said.
        for _ in 0..10 {
            last = c.update(&sp(1.0), 0.0, 0.0, GainScale::FULL);
        }
        assert_eq!(c.integral_n(), 3.0);
        assert!(last.integrator_held, "{last:?}");
        c.reset();
        assert_eq!(c.integral_n(), 0.0);
        // Saturated the same way as the error: not wound further.
        let strong = Gains {
            kp_n_per_m: 1e6,
            ..gains
        };
        let mut c = PositionController::new(strong, 300.0, 1000);
        let out = c.update(&sp(0.01), 0.0, 0.0, GainScale::FULL);
        assert!(out.saturated && out.integrator_held, "{out:?}");
        assert_eq!(out.force_n, 300.0);
        assert_eq!(c.integral_n(), 0.0);
        // Saturated against the error (the feedforward pushes the other way): it integrates.
        let mut c = PositionController::new(
            Gains {
                feedforward_mass_kg: 100.0,
                ..gains
            },
            300.0,
            1000,
        );
        let against = crate::profile::Setpoint {
            position_m: 0.001,
            velocity_m_s: 0.0,
            accel_m_s2: -100.0,
        };
        let out = c.update(&against, 0.0, 0.0, GainScale::FULL);
        assert!(out.saturated && !out.integrator_held, "{out:?}");
        assert!(c.integral_n() > 0.0);
    }
}
