//! One jump of a sweep, driven as the sweep asks ([`SweepDrive`]): the stroke imposed exactly
//! (the paper's kinematic method) or through the software-in-the-loop rig, the core's
//! controller against the force-driven plant, measured the same way.

use std::borrow::Borrow;

use super::{Combination, JumpMetrics, SweepDrive, SweepOutcome, run_parallel};
use sandjumper_model::jump::{JumpSpec, simulate_jump};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::Params;
#[cfg(feature = "rig")]
use sandjumper_rig::hil::run::rig_config;
#[cfg(feature = "rig")]
use sandjumper_rig::hil::{HilSpec, RigModelConfig, SilLink, run_jump};

/// The metrics of combination `c` on `params`, driven by `drive`, the plant integrated at
/// relative tolerance `rtol`. Through SIL, a fault the controller latches fails the jump.
pub fn jump_metrics(
    drive: SweepDrive,
    params: &Params,
    c: &Combination,
    rtol: f64,
) -> Result<JumpMetrics, String> {
    let s = match drive {
        SweepDrive::Kinematic => {
            let js = JumpSpec {
                kind: c.kind,
                freq_hz: c.freq_hz,
                tau_s: c.tau_s,
                model: c.model,
            };
            let opts = SimOptions {
                rtol,
                ..SimOptions::default()
            };
            simulate_jump(params, &js, &opts)
                .map_err(|e| e.to_string())?
                .summary
        }
        #[cfg(not(feature = "rig"))]
        SweepDrive::Sil { .. } => return Err(crate::error::without_rig("a sweep through sil")),
        #[cfg(feature = "rig")]
        SweepDrive::Sil { gain_lowering } => {
            let o = run_jump(
                params,
                &sil_spec(c, gain_lowering, rtol),
                RigModelConfig::default(),
                &mut sil_link()?,
            )
            .map_err(|e| e.to_string())?;
            if let Some(f) = o.faults.first() {
                return Err(format!(
                    "the controller latched {} at tick {}",
                    f.code.name(),
                    f.tick
                ));
            }
            o.summary
        }
    };
    Ok(JumpMetrics {
        jump_height_m: s.jump_height_m,
        final_jump_height_m: s.final_jump_height_m,
        max_depth_m: s.max_depth_m,
        peak_added_mass_kg: s.peak_added_mass_kg,
        peak_motor_force_n: s.peak_motor_force_n,
    })
}

/// Run every combination on `threads` threads (calling `on_jump` after each),
/// driven by `drive` on the parameters `params_for` gives each, at relative tolerance `rtol`;
/// the rows name the drive. The result is in combination order.
pub fn run_driven<P, F>(
    combos: &[Combination],
    threads: usize,
    on_jump: &(dyn Fn() + Sync),
    drive: SweepDrive,
    rtol: f64,
    params_for: F,
) -> Result<SweepOutcome, String>
where
    P: Borrow<Params>,
    F: Fn(&Combination) -> Result<P, String> + Sync,
{
    let mut outcome = run_parallel(combos, threads, on_jump, |c| {
        jump_metrics(drive, params_for(c)?.borrow(), c, rtol)
    })?;
    for row in &mut outcome.rows {
        row.drive = drive.name();
    }
    Ok(outcome)
}

/// The loop's spec for combination `c` (the rig's gains, as `hil` uses them).
#[cfg(feature = "rig")]
pub fn sil_spec(c: &Combination, gain_lowering: Option<f64>, rtol: f64) -> HilSpec {
    let mut spec = HilSpec::new(c.kind, c.freq_hz, c.tau_s, c.model);
    spec.gain_lowering = gain_lowering.map(|f| HilSpec::gain_lowering_factor(f as f32));
    spec.rtol = rtol;
    spec
}

#[cfg(feature = "rig")]
fn sil_link() -> Result<SilLink, String> {
    SilLink::new(rig_config(&RigModelConfig::default())).map_err(|e| e.to_string())
}
