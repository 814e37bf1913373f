//! The bed apparatus of a real board, driven over its link: the blower, the shaker and the
//! lift through `Command::Bed`, the limit switches and the bed-height sensor read from
//! `Status.bed`. The controller's interlocks apply; everything is switched off again on the
//! way out of each step, and on any error.

use std::time::{Duration, Instant};

use sandjumper_core::bed::{BedCommand, LiftMove};
use sandjumper_core::{Command, Status};

use super::bed::BedApparatus;
use super::file::HeightSensor;
use sandjumper_rig::hil::link::RigLink;
use sandjumper_rig::tool::session::query_status;

/// How often the board is polled while waiting (also feeds its watchdog), and the longest
/// single sleep.
const POLL: Duration = Duration::from_millis(50);

/// The board's apparatus.
pub struct BoardBed<'a> {
    link: &'a mut dyn RigLink,
    sensor: HeightSensor,
    lift_timeout: Duration,
}

impl<'a> BoardBed<'a> {
    /// The apparatus behind `link`.
    pub fn new(link: &'a mut dyn RigLink, sensor: HeightSensor, lift_timeout_s: f64) -> Self {
        Self {
            link,
            sensor,
            lift_timeout: Duration::from_secs_f64(lift_timeout_s),
        }
    }

    fn command(&mut self, c: BedCommand) -> Result<(), String> {
        self.link
            .command(&Command::Bed(c))
            .map(|_| ())
            .map_err(|e| format!("bed command {c:?}: {e}"))
    }

    fn status(&mut self) -> Result<Status, String> {
        let mut s = query_status(self.link).map_err(|e| format!("status: {e}"))?;
        // A board reads the apparatus from its first tick on; give a fresh one a moment.
        for _ in 0..10 {
            if s.bed.present {
                break;
            }
            std::thread::sleep(POLL);
            s = query_status(self.link).map_err(|e| format!("status: {e}"))?;
        }
        if !s.bed.present {
            return Err("the board reports no bed apparatus (its inputs were never read)".into());
        }
        if s.emergency_stop_pressed() {
            return Err(
                "the emergency stop is pressed (or its loop or the bed's harness is open)".into(),
            );
        }
        if s.bed.tripped {
            return Err("the bed apparatus tripped (a fault is latched)".into());
        }
        Ok(s)
    }

    /// Wait `seconds`, polling the board (an emergency stop ends the wait with an error).
    fn wait(&mut self, seconds: f64) -> Result<(), String> {
        let until = Instant::now() + Duration::from_secs_f64(seconds.max(0.0));
        loop {
            self.status()?;
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(());
            }
            std::thread::sleep(left.min(POLL));
        }
    }

    /// Move the lift `up` (out of the bed) or down, and wait for its limit switch.
    pub fn lift(&mut self, up: bool) -> Result<(), String> {
        let at = |s: &Status| {
            if up {
                s.bed.inputs.lift_up_limit
            } else {
                s.bed.inputs.lift_down_limit
            }
        };
        if at(&self.status()?) {
            return Ok(());
        }
        self.command(BedCommand::Lift(if up {
            LiftMove::Up
        } else {
            LiftMove::Down
        }))?;
        let until = Instant::now() + self.lift_timeout;
        loop {
            std::thread::sleep(POLL);
            if at(&self.status()?) {
                return Ok(());
            }
            if Instant::now() > until {
                let _ = self.command(BedCommand::Lift(LiftMove::Stop));
                return Err(format!(
                    "the lift did not reach its {} limit within {:.0} s",
                    if up { "upper" } else { "lower" },
                    self.lift_timeout.as_secs_f64()
                ));
            }
        }
    }

    /// Blower and shaker off (on the way out of an error too).
    pub fn all_off(&mut self) {
        let _ = self.command(BedCommand::Blower { volts: 0.0 });
        let _ = self.command(BedCommand::Shaker { duty: 0.0 });
        let _ = self.command(BedCommand::Lift(LiftMove::Stop));
    }

    fn with_off(&mut self, f: impl FnOnce(&mut Self) -> Result<(), String>) -> Result<(), String> {
        let r = f(self);
        if r.is_err() {
            self.all_off();
        }
        r
    }
}

impl BedApparatus for BoardBed<'_> {
    fn fluidize(&mut self, volts: f64, seconds: f64) -> Result<(), String> {
        self.with_off(|b| {
            b.lift(true)?;
            b.command(BedCommand::Blower {
                volts: volts as f32,
            })?;
            b.wait(seconds)?;
            b.command(BedCommand::Blower { volts: 0.0 })
        })
    }

    fn compact(&mut self, duty: f64, seconds: f64) -> Result<(), String> {
        self.with_off(|b| {
            b.lift(true)?;
            b.command(BedCommand::Shaker { duty: duty as f32 })?;
            b.wait(seconds)?;
            b.command(BedCommand::Shaker { duty: 0.0 })
        })
    }

    fn settle(&mut self, seconds: f64) -> Result<(), String> {
        self.with_off(|b| b.wait(seconds))
    }

    fn read_height_m(&mut self) -> Result<f64, String> {
        let s = self.status()?;
        Ok(self.sensor.height_at_zero_code_m
            + self.sensor.metres_per_code * f64::from(s.bed.inputs.height_raw))
    }
}
