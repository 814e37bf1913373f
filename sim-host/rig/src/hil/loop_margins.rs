//! Stability margins of the motor's position loop on the rig, from the loop's linear model.
//!
//! The loop, as the core runs it and the rig model closes it:
//!
//! - **controller** (`sandjumper-core`, one update per tick `T`): `kp e + kd (v_cmd - v_est)`
//!   plus the integral `I_n = ki T sum_{j<n} e_j`; `v_est` is the count difference per tick
//!   through the first-order low-pass of [`RigConfig::velocity_cutoff_hz`],
//!   `V(z) = alpha (1 - z^-1) / T / (1 - (1 - alpha) z^-1)`, `alpha = 1 - exp(-2 pi f_c T)`;
//! - **drive**: the force held over the tick (zero-order hold), then the first-order current
//!   lag `1 / (1 + tau s)`;
//! - **plant** from the motor force to `p = x_m - x_r`: the carriage `m_m` and the rod `m_r`,
//!   which hangs on the spring `k_s, c_s` to the foot:
//!   `P(s) = 1 / (m_m s^2) + 1 / (m_r s^2 + Z(s))`, with `Z = c_s s + k_s` when the foot stands
//!   (stance) and `Z = (c_s s + k_s) m_f s^2 / (m_f s^2 + c_s s + k_s)` when it flies.
//!
//! Below the rod's resonance on the spring (about 26 Hz) the drive moves the carriage against a
//! rod the spring holds; above it the rod is free and the drive sees the motor/rod reduced mass
//! `m_m m_r / (m_m + m_r)`, ten times lighter. The derivative gain sets the loop's crossover
//! there (`kd / mu`), where the tick, the current lag and the velocity filter take their phase:
//! that is what bounds `kd`. Ground forces act on the foot only (on the far side of the spring)
//! and are left out, as are saturation and encoder quantization.

use nalgebra::Complex;
use sandjumper_core::{Gains, RigConfig};

use sandjumper_model::params::{DriveParams, RobotParams};

/// Where the foot is while the loop runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FootSupport {
    /// The foot stands on the ground (stance, the delay of a delayed stutter).
    Standing,
    /// The foot flies with the robot.
    Flying,
}

/// A gain crossover of the loop (`|L| = 1`, falling or, past a resonance, rising).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossover {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Phase margin there: the angle from `L` to the critical point -1, degrees (0-180).
    pub phase_margin_deg: f64,
}

/// Margins of the loop over 0.1 Hz to the Nyquist frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopMargins {
    /// Every gain crossover, in order of frequency.
    pub crossovers: Vec<Crossover>,
    /// The smallest phase margin over the crossovers, degrees.
    pub phase_margin_deg: f64,
    /// The smallest gain margin over the phase crossings of -180 degrees where `|L| < 1`:
    /// how much the loop gain may rise before it oscillates, dB (`+inf`: none).
    pub gain_margin_db: f64,
    /// Frequency of that phase crossing, Hz (NaN: none).
    pub gain_margin_freq_hz: f64,
}

/// The loop's open-loop gain `L(j 2 pi f)` for gains `gains` (already scaled by any gain
/// lowering), the controller's fixed configuration `config`, the robot and its drive.
pub fn open_loop(
    freq_hz: f64,
    gains: &Gains,
    config: &RigConfig,
    robot: &RobotParams,
    drive: &DriveParams,
    foot: FootSupport,
) -> Complex<f64> {
    let tick_s = 1.0 / f64::from(config.tick_hz);
    let s = Complex::new(0.0, std::f64::consts::TAU * freq_hz);
    let z_inv = (-s * tick_s).exp();
    let one = Complex::new(1.0, 0.0);
    let alpha =
        1.0 - (-std::f64::consts::TAU * f64::from(config.velocity_cutoff_hz) * tick_s).exp();
    let velocity_filter = (one - z_inv) / tick_s * alpha / (one - z_inv * (1.0 - alpha));
    let integral = z_inv * tick_s / (one - z_inv);
    let controller = velocity_filter * f64::from(gains.kd_n_s_per_m)
        + f64::from(gains.kp_n_per_m)
        + integral * f64::from(gains.ki_n_per_m_s);
    let hold = (one - z_inv) / (s * tick_s);
    let lag = one / (one + s * drive.current_lag_s);
    let spring = s * robot.spring_damping_n_s_m + robot.spring_stiffness_n_m;
    let s2 = s * s;
    let rod_load = match foot {
        FootSupport::Standing => spring,
        FootSupport::Flying => {
            let foot_inertia = s2 * robot.foot_mass_kg;
            spring * foot_inertia / (foot_inertia + spring)
        }
    };
    let plant = one / (s2 * robot.motor_mass_kg) + one / (s2 * robot.rod_mass_kg + rod_load);
    controller * hold * lag * plant
}

/// Phase margin of `l` on `|l| = 1`: its angle from the critical point -1, `180 - |arg l|`,
/// 0-180 degrees (the phase lag or lead that would put `l` on -1).
fn phase_margin_deg(l: Complex<f64>) -> f64 {
    180.0 - l.arg().to_degrees().abs()
}

/// The loop's margins, scanned on a logarithmic grid (2,000 points per decade) from 0.1 Hz to
/// just below the Nyquist frequency `tick_hz / 2`.
pub fn margins(
    gains: &Gains,
    config: &RigConfig,
    robot: &RobotParams,
    drive: &DriveParams,
    foot: FootSupport,
) -> LoopMargins {
    let l = |f: f64| open_loop(f, gains, config, robot, drive, foot);
    let (f_lo, f_hi) = (0.1_f64, 0.499 * f64::from(config.tick_hz));
    let points = (2000.0 * (f_hi / f_lo).log10()).ceil() as usize;
    let freq = |i: usize| f_lo * (f_hi / f_lo).powf(i as f64 / points as f64);
    let mut crossovers = Vec::new();
    let (mut gain_margin_db, mut gain_margin_freq_hz) = (f64::INFINITY, f64::NAN);
    // A bracketed crossing refined by bisection in log-frequency.
    let refine = |mut a: f64, mut b: f64, above: &dyn Fn(Complex<f64>) -> bool| {
        let side_a = above(l(a));
        for _ in 0..50 {
            let m = (a * b).sqrt();
            if above(l(m)) == side_a { a = m } else { b = m }
        }
        (a * b).sqrt()
    };
    let mut prev = (f_lo, l(f_lo));
    for i in 1..=points {
        let f = freq(i);
        let here = l(f);
        if (prev.1.norm() >= 1.0) != (here.norm() >= 1.0) {
            let fc = refine(prev.0, f, &|v| v.norm() >= 1.0);
            crossovers.push(Crossover {
                freq_hz: fc,
                phase_margin_deg: phase_margin_deg(l(fc)),
            });
        }
        // The phase crosses -180 degrees where the imaginary part changes sign on the
        // negative real axis.
        if (prev.1.im >= 0.0) != (here.im >= 0.0) && here.re < 0.0 {
            let fp = refine(prev.0, f, &|v| v.im >= 0.0);
            let margin = -20.0 * l(fp).norm().log10();
            // Crossings with |L| > 1 (the integrator's phase at low frequency) are not
            // reached by raising the gain.
            if margin > 0.0 && margin < gain_margin_db {
                gain_margin_db = margin;
                gain_margin_freq_hz = fp;
            }
        }
        prev = (f, here);
    }
    let phase_margin_deg = crossovers
        .iter()
        .map(|c| c.phase_margin_deg)
        .fold(f64::INFINITY, f64::min);
    LoopMargins {
        crossovers,
        phase_margin_deg,
        gain_margin_db,
        gain_margin_freq_hz,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_model::params::Params;

    fn robot_drive() -> (RobotParams, DriveParams) {
        let p = Params::preset(0.57).unwrap();
        (p.robot, p.drive)
    }

    #[test]
    fn a_pure_double_integrator_under_pd_has_the_textbook_margin() {
        // Without the tick, the lag, the filter and the spring: L = (kp + kd s) / (m s^2).
        // kp = m w0^2, kd = 2 zeta m w0 with zeta = 1: crossover where |L| = 1, phase margin
        // atan(kd w / kp); evaluated at a fast tick and cut-off so their phase is negligible.
        let (mut robot, mut drive) = robot_drive();
        robot.rod_mass_kg = 1e9; // the rod stands still: P = 1 / (m_m s^2)
        robot.spring_stiffness_n_m = 0.0;
        robot.spring_damping_n_s_m = 0.0;
        drive.current_lag_s = 0.0;
        let config = RigConfig {
            tick_hz: 10_000_000,
            velocity_cutoff_hz: 4_000_000.0,
            ..RigConfig::default()
        };
        let m = robot.motor_mass_kg;
        let w0 = std::f64::consts::TAU * 20.0;
        let gains = Gains {
            kp_n_per_m: (m * w0 * w0) as f32,
            kd_n_s_per_m: (2.0 * m * w0) as f32,
            ki_n_per_m_s: 0.0,
            integral_limit_n: 0.0,
            feedforward_mass_kg: 0.0,
        };
        let lm = margins(&gains, &config, &robot, &drive, FootSupport::Standing);
        // |L|^2 = (w0^4 + 4 w0^2 w^2) / w^4 = 1: (w / w0)^2 = 2 + sqrt(5).
        let w_c = w0 * (2.0 + 5f64.sqrt()).sqrt();
        let pm = (2.0 * w_c / w0).atan().to_degrees();
        assert_eq!(lm.crossovers.len(), 1);
        let c = lm.crossovers[0];
        assert!(
            (c.freq_hz / (w_c / std::f64::consts::TAU) - 1.0).abs() < 1e-4,
            "{c:?}"
        );
        assert!((c.phase_margin_deg - pm).abs() < 0.01, "{c:?} vs {pm}");
        // Only the discrete hold and filter, near the 5 MHz Nyquist frequency, reach -180 degrees.
        assert!(lm.gain_margin_db > 60.0, "{lm:?}");
    }

    #[test]
    fn delays_take_phase_at_the_crossover() {
        // The same loop with the rig's tick, lag and filter loses phase: the margin falls.
        let (robot, drive) = robot_drive();
        let gains = Gains::default();
        let ideal = RigConfig {
            tick_hz: 10_000_000,
            velocity_cutoff_hz: 4_000_000.0,
            ..RigConfig::default()
        };
        let mut no_lag = drive.clone();
        no_lag.current_lag_s = 0.0;
        let fast = margins(&gains, &ideal, &robot, &no_lag, FootSupport::Flying);
        let rig = margins(
            &gains,
            &RigConfig::default(),
            &robot,
            &drive,
            FootSupport::Flying,
        );
        assert!(
            rig.phase_margin_deg < fast.phase_margin_deg - 5.0,
            "{rig:?} vs {fast:?}"
        );
        assert!(rig.gain_margin_db.is_finite(), "{rig:?}");
    }
}

#[cfg(test)]
mod rig_tests {
    use super::*;
    use crate::hil::HilSpec;
    use sandjumper_model::params::Params;

    /// Least phase margin accepted for a gain set of the rig, degrees.
    const MIN_PHASE_MARGIN_DEG: f64 = 35.0;
    /// Least gain margin accepted, dB.
    const MIN_GAIN_MARGIN_DB: f64 = 8.0;

    fn rig_margins(gains: &Gains) -> [LoopMargins; 2] {
        let p = Params::preset(0.57).unwrap();
        [FootSupport::Standing, FootSupport::Flying]
            .map(|foot| margins(gains, &RigConfig::default(), &p.robot, &p.drive, foot))
    }

    fn robust(gains: &Gains) -> bool {
        rig_margins(gains).iter().all(|m| {
            m.phase_margin_deg >= MIN_PHASE_MARGIN_DEG && m.gain_margin_db >= MIN_GAIN_MARGIN_DB
        })
    }

    #[test]
    fn the_rig_gains_keep_their_margins_at_full_and_at_lowered_gain() {
        let p = Params::preset(0.57).unwrap();
        let full = HilSpec::rig_gains(&p.robot);
        let lowering = HilSpec::gain_lowering_factor(0.05);
        let lowered = Gains {
            kp_n_per_m: full.kp_n_per_m * lowering.kp_factor,
            ki_n_per_m_s: full.ki_n_per_m_s * lowering.kp_factor,
            kd_n_s_per_m: full.kd_n_s_per_m * lowering.kd_factor,
            ..full
        };
        for (what, g) in [("rig", full), ("rig lowered 0.05", lowered)] {
            let m = rig_margins(&g);
            eprintln!("{what}: {m:?}");
            assert!(robust(&g), "{what}: {m:?}");
        }
    }

    #[test]
    fn derivative_damping_chosen_on_the_carriage_leaves_no_margin() {
        // The first rig gains: zeta 0.7 on the carriage (kd = 2 0.7 sqrt(kp m_m)) behind a
        // 500 Hz velocity filter. Above the rod's resonance the drive sees the reduced mass,
        // ten times lighter: the loop crossed over near 470 Hz with a few degrees to spare
        // (it rang there in SIL, +-50 N after the start's feedforward step).
        let p = Params::preset(0.57).unwrap();
        let m_m = p.robot.motor_mass_kg;
        let g = HilSpec::rig_gains(&p.robot);
        let carriage = Gains {
            kd_n_s_per_m: (2.0 * 0.7 * (f64::from(g.kp_n_per_m) * m_m).sqrt()) as f32,
            ..g
        };
        let first = RigConfig {
            velocity_cutoff_hz: 500.0,
            ..RigConfig::default()
        };
        let m = margins(&carriage, &first, &p.robot, &p.drive, FootSupport::Standing);
        assert!(m.phase_margin_deg < 5.0 && m.gain_margin_db < 2.0, "{m:?}");
        let c = m.crossovers.last().unwrap();
        assert!((400.0..550.0).contains(&c.freq_hz), "{m:?}");
        // Either change alone is not enough: the faster filter with the carriage's damping,
        // or today's damping behind the 500 Hz filter.
        assert!(!robust(&carriage));
        let m = margins(&g, &first, &p.robot, &p.drive, FootSupport::Standing);
        assert!(m.phase_margin_deg < MIN_PHASE_MARGIN_DEG - 10.0, "{m:?}");
    }
}
