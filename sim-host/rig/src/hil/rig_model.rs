//! The STA-1104 rig as the controller sees it: the force-driven [`Plant`] behind a drive
//! (DAC quantization, force constant, saturation at `F_peak`, current lag), a quantized encoder
//! (with optional seeded noise and plant-side fault injection) and a camera that takes a frame
//! on every rising edge of the trigger line.
//!
//! One control period per [`RigModel::sense`] / [`RigModel::actuate`] pair: the plant advances
//! exactly `1 / tick_hz` with the drive's force held (zero-order hold), its own event-located
//! integration inside the period.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use sandjumper_core::SensorFrame;
use sandjumper_model::error::SimError;
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::plant::{Plant, PlantState};

/// The drive's analog force command as the firmware writes it: a 12-bit DAC whose mid-point
/// code is zero force and whose `half_range_codes` either side reach `±full_scale_n`
/// (firmware `drive.rs`: 2048 = 0 N, 2047 codes per side, 300 N full scale = 0.147 N/code).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DacScaling {
    /// Force at full scale, N.
    pub full_scale_n: f64,
    /// Codes either side of the mid-point.
    pub half_range_codes: u16,
}

impl Default for DacScaling {
    fn default() -> Self {
        Self {
            full_scale_n: 300.0,
            half_range_codes: 2047,
        }
    }
}

impl DacScaling {
    /// Force per DAC code, N.
    pub fn newtons_per_code(&self) -> f64 {
        self.full_scale_n / f64::from(self.half_range_codes)
    }

    /// The force the drive actually receives for a command: rounded to the nearest code
    /// (half away from zero), saturated at full scale; NaN is zero force.
    pub fn quantize(&self, force_n: f64) -> f64 {
        if force_n.is_nan() {
            return 0.0;
        }
        let half = f64::from(self.half_range_codes);
        let codes = (force_n / self.full_scale_n * half)
            .clamp(-half, half)
            .round();
        codes * self.newtons_per_code()
    }
}

/// Fixed facts of the simulated rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigModelConfig {
    /// Control rate, Hz: the plant advances `1 / tick_hz` per frame.
    pub tick_hz: u32,
    /// Encoder resolution, m per count (default 1 um). Count 0 is `p = 0`.
    pub metres_per_count: f64,
    /// Standard deviation of the encoder noise, counts (0: none).
    pub encoder_noise_counts: f64,
    /// Seed of the encoder noise.
    pub noise_seed: u64,
    /// The DAC between the controller and the drive.
    pub dac: DacScaling,
}

impl Default for RigModelConfig {
    fn default() -> Self {
        Self {
            tick_hz: 10_000,
            metres_per_count: 1e-6,
            encoder_noise_counts: 0.0,
            noise_seed: 1,
            dac: DacScaling::default(),
        }
    }
}

/// A camera frame: taken on a rising edge of the trigger line.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CameraFrame {
    /// Frame number (0, 1, ... in order of the rising edges the camera saw).
    pub frame: u32,
    /// Index of the control period whose actuator frame raised the line.
    pub period: u64,
    /// Plant time of the exposure, s.
    pub t_s: f64,
    /// Rod height above its rest height, m (what the camera tracks).
    pub rod_height_m: f64,
}

/// Plant-side fault injection on the encoder signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EncoderInjection {
    /// The encoder reading stops changing (a cable fault, a stuck counter).
    Frozen,
    /// The reading jumps by this many counts and stays offset (noise burst, a slipping scale).
    Jump { counts: i64 },
}

/// The simulated rig: plant, drive, encoder and camera.
#[derive(Debug)]
pub struct RigModel {
    plant: Plant,
    config: RigModelConfig,
    period_s: f64,
    rng: StdRng,
    frozen_count: Option<i64>,
    encoder_offset: i64,
    trigger_was_high: bool,
    frames: Vec<CameraFrame>,
    period: u64,
    rod_rest_m: f64,
    rod_heights: Vec<f64>,
    applied_command_n: f64,
    state: PlantState,
    /// The bed apparatus's inputs sent with every sensor frame (None: no apparatus).
    pub bed: Option<sandjumper_core::bed::BedInputs>,
}

impl RigModel {
    /// The rig at rest with the motor at `initial_p_m` (the trajectory's start position).
    pub fn new(
        params: &Params,
        model: ModelName,
        initial_p_m: f64,
        config: RigModelConfig,
        opts: &SimOptions,
    ) -> Result<Self, SimError> {
        let bad = |field: &'static str, value: f64, allowed: &str| SimError::InvalidInput {
            field,
            value: value.to_string(),
            allowed: allowed.into(),
        };
        if !(1_000..=100_000).contains(&config.tick_hz) {
            return Err(bad(
                "tick_hz",
                f64::from(config.tick_hz),
                "1000..=100000 Hz",
            ));
        }
        if !(config.metres_per_count > 0.0 && config.metres_per_count <= 1e-3) {
            return Err(bad(
                "metres_per_count",
                config.metres_per_count,
                "0 < m/count <= 1e-3",
            ));
        }
        if !(config.encoder_noise_counts.is_finite() && config.encoder_noise_counts >= 0.0) {
            return Err(bad(
                "encoder_noise_counts",
                config.encoder_noise_counts,
                ">= 0 counts",
            ));
        }
        if !(config.dac.full_scale_n > 0.0 && config.dac.half_range_codes > 0) {
            return Err(bad(
                "dac.full_scale_n",
                config.dac.full_scale_n,
                "> 0 N with >= 1 code",
            ));
        }
        let plant = Plant::new(params, model, initial_p_m, opts)?;
        let state = plant.state();
        let rod_rest_m = state.x_r;
        Ok(Self {
            plant,
            config,
            period_s: 1.0 / f64::from(config.tick_hz),
            rng: StdRng::seed_from_u64(config.noise_seed),
            frozen_count: None,
            encoder_offset: 0,
            bed: None,
            trigger_was_high: false,
            frames: Vec::new(),
            period: 0,
            rod_rest_m,
            rod_heights: Vec::new(),
            applied_command_n: 0.0,
            state,
        })
    }

    /// Tell the plant when the push-off half begins, s of plant time (see
    /// [`Plant::set_push_off_start`]).
    pub fn set_push_off_start(&mut self, push_off_start_s: f64) {
        self.plant.set_push_off_start(push_off_start_s);
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The plant's state now.
    pub fn state(&self) -> PlantState {
        self.state
    }

    /// The configuration.
    pub fn config(&self) -> &RigModelConfig {
        &self.config
    }

    /// Control period, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Control periods simulated so far.
    pub fn periods(&self) -> u64 {
        self.period
    }

    /// Rod height above its rest height now, m.
    pub fn rod_height_m(&self) -> f64 {
        self.state.x_r - self.rod_rest_m
    }

    /// Rod height above rest at the start of every period so far (index = period), m: what
    /// the simulated camera renders its exposures from.
    pub fn rod_height_history(&self) -> &[f64] {
        &self.rod_heights
    }

    /// Camera frames taken so far.
    pub fn camera_frames(&self) -> &[CameraFrame] {
        &self.frames
    }

    /// The force the drive is commanded with now (after the DAC), N.
    pub fn drive_command_n(&self) -> f64 {
        self.applied_command_n
    }

    /// Inject an encoder fault from now on.
    pub fn inject(&mut self, injection: EncoderInjection) {
        match injection {
            EncoderInjection::Frozen => self.frozen_count = Some(self.true_count()),
            EncoderInjection::Jump { counts } => self.encoder_offset += counts,
        }
    }

    fn true_count(&self) -> i64 {
        (self.state.p / self.config.metres_per_count).round() as i64
    }

    fn noise_counts(&mut self) -> i64 {
        let sigma = self.config.encoder_noise_counts;
        if sigma == 0.0 {
            return 0;
        }
        // Box-Muller: one standard normal from two uniforms in (0, 1].
        let u1: f64 = 1.0 - self.rng.random::<f64>();
        let u2: f64 = self.rng.random::<f64>();
        let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        (sigma * z).round() as i64
    }

    /// The encoder count the controller reads now (quantized, noisy, injected faults applied).
    pub fn encoder_count(&mut self) -> i64 {
        let count = match self.frozen_count {
            Some(c) => c,
            None => self.true_count() + self.noise_counts(),
        };
        count + self.encoder_offset
    }

    /// The sensor frame for this period: the encoder as a wrapping 32-bit hardware counter and
    /// the motor current (drive force over `K_f`).
    pub fn sense(&mut self, frame: u32) -> SensorFrame {
        let count = self.encoder_count();
        let k_f = self.plant.drive().force_constant_n_a;
        let current_a = (k_f > 0.0).then(|| (self.state.f_m / k_f) as f32);
        SensorFrame {
            frame,
            encoder_count: count as i32 as u32,
            current_a,
            overrun: false,
            bed: self.bed,
        }
    }

    /// Apply the controller's outputs for one period and advance the plant by it: the force
    /// command goes through the DAC (zero if the drive is disabled) and the drive (force
    /// constant, `F_peak`, current lag); a rising edge of the trigger takes a camera frame.
    pub fn actuate(
        &mut self,
        force_cmd_n: f64,
        drive_enabled: bool,
        trigger: bool,
    ) -> Result<(), SimError> {
        let command = if drive_enabled {
            self.config.dac.quantize(force_cmd_n)
        } else {
            0.0
        };
        self.applied_command_n = command;
        if trigger && !self.trigger_was_high {
            self.frames.push(CameraFrame {
                frame: self.frames.len() as u32,
                period: self.period,
                t_s: self.state.t_s,
                rod_height_m: self.state.x_r - self.rod_rest_m,
            });
        }
        self.trigger_was_high = trigger;
        self.rod_heights.push(self.rod_height_m());
        let k_f = self.plant.drive().force_constant_n_a;
        self.plant.advance_current(self.period_s, command / k_f)?;
        self.period += 1;
        self.state = self.plant.state();
        Ok(())
    }

    /// Advance one period with the drive holding its last command (no actuator frame arrived).
    pub fn hold(&mut self) -> Result<(), SimError> {
        self.rod_heights.push(self.rod_height_m());
        let k_f = self.plant.drive().force_constant_n_a;
        self.plant
            .advance_current(self.period_s, self.applied_command_n / k_f)?;
        self.period += 1;
        self.state = self.plant.state();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dac_matches_the_firmware_scaling() {
        let dac = DacScaling::default();
        assert_eq!(dac.quantize(0.0), 0.0);
        assert_eq!(dac.quantize(1e9), 300.0);
        assert_eq!(dac.quantize(-1e9), -300.0);
        assert_eq!(dac.quantize(f64::NAN), 0.0);
        let step = dac.newtons_per_code();
        assert!((step - 0.146_555).abs() < 1e-5);
        for i in 0..1000 {
            let f = -290.0 + 0.581 * i as f64;
            assert!((dac.quantize(f) - f).abs() <= step / 2.0 + 1e-12, "{f}");
        }
    }

    #[test]
    fn encoder_is_quantized_and_injections_apply() {
        let params = Params::preset(0.57).unwrap();
        let mut rig = RigModel::new(
            &params,
            ModelName::Hard,
            -0.01875,
            RigModelConfig::default(),
            &SimOptions::default(),
        )
        .unwrap();
        assert_eq!(rig.encoder_count(), -18_750);
        rig.inject(EncoderInjection::Jump { counts: 5000 });
        assert_eq!(rig.encoder_count(), -13_750);
        let f = rig.sense(7);
        assert_eq!(f.frame, 7);
        assert_eq!(f.encoder_count as i32, -13_750);
    }
}
