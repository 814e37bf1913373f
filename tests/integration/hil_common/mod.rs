//! Shared helpers of the hardware-in-the-loop tests.
#![allow(dead_code)]

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::{ModelName, Params};
use sandjumper_rig::hil::run::rig_config;
use sandjumper_rig::hil::{HilOutcome, HilSpec, RigModelConfig, SilLink, run_jump};

/// Parameters at `phi`.
pub fn params(phi: f64) -> Params {
    Params::preset(phi).expect("preset")
}

/// One jump through SIL with the default rig model.
pub fn sil(params: &Params, spec: &HilSpec) -> HilOutcome {
    let config = RigModelConfig::default();
    let mut link = SilLink::new(rig_config(&config)).expect("rig config");
    run_jump(params, spec, config, &mut link).expect("SIL run")
}

/// The delayed stutter at 10 Hz with tau on `model`.
pub fn delayed(tau_s: f64, model: ModelName) -> HilSpec {
    HilSpec::new(JumpKind::DelayedStutter, 10.0, tau_s, model)
}

/// Half the peak-to-peak spring force over `[t0, t1]` (trajectory time), N.
pub fn spring_ringing_n(o: &HilOutcome, t0: f64, t1: f64) -> f64 {
    let f: Vec<f64> = o
        .trace
        .iter()
        .filter(|r| r.t_s >= t0 && r.t_s <= t1)
        .map(|r| r.spring_force_n)
        .collect();
    let max = f.iter().cloned().fold(f64::MIN, f64::max);
    let min = f.iter().cloned().fold(f64::MAX, f64::min);
    (max - min) / 2.0
}
