//! The bed apparatus as the campaign drives it (blower, shaker, height sensor), and its
//! simulated twin for `--link sil|pil`.
//!
//! Simulated bed: fluidizing resets phi to `fluidized_phi` plus Gaussian scatter; each
//! compaction dose `D` (shaker-seconds times duty) raises it along
//! `phi = phi_0 + gain ln(1 + D_total / dose_scale)`, capped at `max_phi` (each dose does
//! less than the last); a height reading is `m / (rho A phi)` plus Gaussian noise. Seeded:
//! the same seed gives the same bed.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use super::file::SimulatedBedSettings;

/// What bed preparation needs from an apparatus.
pub trait BedApparatus {
    /// Fluidize: blower at `volts` for `seconds`, then off.
    fn fluidize(&mut self, volts: f64, seconds: f64) -> Result<(), String>;
    /// Compact: shaker at `duty` for `seconds`, then off.
    fn compact(&mut self, duty: f64, seconds: f64) -> Result<(), String>;
    /// Wait, s.
    fn settle(&mut self, seconds: f64) -> Result<(), String>;
    /// One bed-height reading, m.
    fn read_height_m(&mut self) -> Result<f64, String>;
}

/// The simulated bed.
pub struct SimulatedBed {
    s: SimulatedBedSettings,
    /// Bed constants: grain mass, kg; density, kg/m^3; area, m^2.
    m_rho_a: (f64, f64, f64),
    rng: rand::rngs::StdRng,
    phi0: f64,
    dose: f64,
    /// Simulated time spent, s.
    pub elapsed_s: f64,
}

impl SimulatedBed {
    /// A bed of `mass_kg` of grains of `density_kg_m3` over `area_m2`, seeded.
    pub fn new(
        s: &SimulatedBedSettings,
        mass_kg: f64,
        density_kg_m3: f64,
        area_m2: f64,
        seed: u64,
    ) -> Self {
        Self {
            s: s.clone(),
            m_rho_a: (mass_kg, density_kg_m3, area_m2),
            rng: rand::rngs::StdRng::seed_from_u64(seed),
            phi0: s.fluidized_phi,
            dose: 0.0,
            elapsed_s: 0.0,
        }
    }

    /// The bed's true packing fraction now.
    pub fn phi(&self) -> f64 {
        (self.phi0 + self.s.compaction_gain * (1.0 + self.dose / self.s.dose_scale_s).ln())
            .min(self.s.max_phi)
    }

    fn normal(&mut self, sd: f64) -> f64 {
        Normal::new(0.0, sd.max(0.0)).map_or(0.0, |n| n.sample(&mut self.rng))
    }
}

impl BedApparatus for SimulatedBed {
    fn fluidize(&mut self, _volts: f64, seconds: f64) -> Result<(), String> {
        self.phi0 = self.s.fluidized_phi + self.normal(self.s.fluidized_scatter);
        self.dose = 0.0;
        self.elapsed_s += seconds;
        Ok(())
    }

    fn compact(&mut self, duty: f64, seconds: f64) -> Result<(), String> {
        self.dose += duty * seconds;
        self.elapsed_s += seconds;
        Ok(())
    }

    fn settle(&mut self, seconds: f64) -> Result<(), String> {
        self.elapsed_s += seconds;
        Ok(())
    }

    fn read_height_m(&mut self) -> Result<f64, String> {
        let (m, rho, a) = self.m_rho_a;
        let h = m / (rho * a * self.phi());
        Ok(h + self.normal(self.s.height_noise_m))
    }
}
