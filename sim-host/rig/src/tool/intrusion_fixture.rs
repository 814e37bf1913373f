//! The slow-intrusion fixture as the controller sees it in lockstep: the clamped motor, the rod
//! with its foot and the sand of [`sandjumper_model::intrusion_rig::IntrusionRig`] behind the
//! rig's DAC (the force command quantized as the firmware's codes quantize it), one control
//! period per sensor and actuator frame.

use crate::hil::rig_model::RigModelConfig;
use sandjumper_core::{ActuatorFrame, SensorFrame};
use sandjumper_model::error::SimError;
use sandjumper_model::intrusion_rig::{IntrusionRig, SUBSTEP_S};
use sandjumper_model::params::{ModelName, Params};

use super::session::Fixture;

pub use sandjumper_model::intrusion_rig::{CONTACT_DAMPING_RATIO, CONTACT_STIFFNESS_N_M};

/// The fixture behind the rig's DAC.
#[derive(Debug)]
pub struct IntrusionFixture {
    rig: IntrusionRig,
    config: RigModelConfig,
}

impl IntrusionFixture {
    /// The foot resting on the surface (`p = surface_p_m`), motor force holding the rod.
    pub fn new(
        params: &Params,
        model: ModelName,
        surface_p_m: f64,
        config: RigModelConfig,
    ) -> Result<Self, SimError> {
        Ok(Self {
            rig: IntrusionRig::new(params, model, surface_p_m)?,
            config,
        })
    }

    /// Depth of the foot below the free surface now, m.
    pub fn depth_m(&self) -> f64 {
        self.rig.depth_m()
    }

    /// Moving mass (rod and foot), kg.
    pub fn moving_mass_kg(&self) -> f64 {
        self.rig.moving_mass_kg()
    }
}

impl Fixture for IntrusionFixture {
    fn sense(&mut self, frame: u32) -> SensorFrame {
        let count = (self.rig.position_m() / self.config.metres_per_count).round() as i64;
        SensorFrame {
            frame,
            encoder_count: count as i32 as u32,
            current_a: Some((self.rig.motor_force_n() / self.rig.force_constant_n_a()) as f32),
            overrun: false,
            bed: None,
        }
    }

    fn actuate(&mut self, out: &ActuatorFrame) -> Result<(), SimError> {
        let command_n = if out.drive_enabled {
            self.config.dac.quantize(f64::from(out.force_n))
        } else {
            0.0
        };
        let period_s = 1.0 / f64::from(self.config.tick_hz);
        let steps = (period_s / SUBSTEP_S).round().max(1.0) as u32;
        self.rig.advance_steps(steps, command_n)
    }
}
