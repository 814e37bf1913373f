//! Force-driven plant for hardware-in-the-loop: all three bodies integrated, the motor force
//! held constant over each control period (zero-order hold), events located inside.

use crate::error::SimError;
use crate::hybrid::GroundMode;
use crate::jump::{JumpSummary, SimOptions};
use crate::params::{DriveParams, ModelName, Params};

/// The motor drive of MODEL.md: `F_m = clamp(K_f i, -F_peak, F_peak)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorDrive {
    /// K_f, N/A.
    pub force_constant_n_a: f64,
    /// F_peak, N.
    pub peak_force_n: f64,
    /// First-order current lag time constant, s (0: none).
    pub current_lag_s: f64,
}

impl MotorDrive {
    /// The drive described by `drive`.
    pub fn new(drive: &DriveParams) -> Self {
        Self {
            force_constant_n_a: drive.force_constant_n_a,
            peak_force_n: drive.peak_force_n,
            current_lag_s: drive.current_lag_s,
        }
    }

    /// Commanded force for a current command, N: `clamp(K_f i, -F_peak, F_peak)`.
    pub fn force_n(&self, current_a: f64) -> f64 {
        (self.force_constant_n_a * current_a).clamp(-self.peak_force_n, self.peak_force_n)
    }
}

/// Snapshot of the plant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantState {
    /// Time, s.
    pub t_s: f64,
    /// Motor (carriage) height, m.
    pub x_m: f64,
    /// Rod height, m.
    pub x_r: f64,
    /// Foot height, m.
    pub x_f: f64,
    /// Motor velocity, m/s.
    pub v_m: f64,
    /// Rod velocity, m/s.
    pub v_r: f64,
    /// Foot velocity, m/s.
    pub v_f: f64,
    /// Motor position relative to the rod, p = x_m - x_r, m (what the encoder measures).
    pub p: f64,
    /// Spring force, N.
    pub f_s: f64,
    /// Ground force on the foot, N.
    pub f_gm: f64,
    /// Motor force actually applied (after clamp and lag), N.
    pub f_m: f64,
    /// Added mass, kg.
    pub m_a: f64,
    /// Ground mode.
    pub mode: GroundMode,
    /// Foot depth below the undisturbed surface, m (negative above it).
    pub depth_m: f64,
}

/// The force-driven plant.
#[derive(Clone, Debug)]
pub struct Plant {
    _private: (),
}

impl Plant {
    /// A plant at rest in static equilibrium with `p = initial_p_m`.
    pub fn new(
        params: &Params,
        model: ModelName,
        initial_p_m: f64,
        opts: &SimOptions,
    ) -> Result<Plant, SimError> {
        let _ = (params, model, initial_p_m, opts);
        Err(SimError::InvalidInput {
            field: "Plant",
            value: "not yet implemented".into(),
            allowed: "nothing yet".into(),
        })
    }

    /// Advance exactly `dt_s` with the commanded motor force held (zero-order hold).
    pub fn advance(&mut self, dt_s: f64, motor_force_n: f64) -> Result<(), SimError> {
        let _ = (dt_s, motor_force_n);
        Ok(())
    }

    /// Current state.
    pub fn state(&self) -> PlantState {
        unimplemented!()
    }

    /// Metrics of what has been simulated so far.
    pub fn summary(&self) -> JumpSummary {
        JumpSummary::default()
    }
}
