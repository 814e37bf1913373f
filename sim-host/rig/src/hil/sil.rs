//! Software in the loop: the core's control loop ([`Rig`]) in this process, driven exactly as
//! the firmware drives it (`firmware/src/app_qemu.rs`): a valid frame feeds the watchdog
//! (`note_frame_ok`), a corrupted one is rejected by the real frame decoder and counted
//! (`note_frame_rejected`), a sensor frame runs one [`Rig::lockstep`] tick.
//!
//! The emulated firmware in lockstep has no clock of its own; SIL stands in for a rig that
//! keeps time, as the F407 does: each period without a sensor frame is reported to the core
//! ([`Rig::lockstep_silent_period`]), which latches `LinkLost` after
//! `RigConfig::lockstep_timeout_ticks` of them, and the force is zero.

use super::link::{LinkError, LinkReport, RigLink, corrupted_sensor_frame, reply_or_rejected};
use sandjumper_core::protocol::FaultReport;
use sandjumper_core::rig::DEFAULT_SAMPLE_QUEUE;
use sandjumper_core::{
    ActuatorFrame, Command, FaultCode, FrameDecoder, HostMessage, Reply, Rig, RigConfig,
    SampleRecord, SensorFrame, TickTiming,
};

/// The core's control loop in-process.
#[derive(Debug)]
pub struct SilLink {
    rig: Rig<DEFAULT_SAMPLE_QUEUE>,
    decoder: FrameDecoder,
    samples: Vec<SampleRecord>,
    faults: Vec<FaultReport>,
}

impl SilLink {
    /// A rig with `config` in Idle.
    pub fn new(config: RigConfig) -> Result<Self, LinkError> {
        let rig = Rig::new(config).map_err(|e| LinkError::Io {
            what: "rig configuration".into(),
            message: e.to_string(),
        })?;
        Ok(Self {
            rig,
            decoder: FrameDecoder::new(),
            samples: Vec::new(),
            faults: Vec::new(),
        })
    }

    /// Periods without a sensor frame before `LinkLost` (at least 1): the core's
    /// `lockstep_timeout_ticks`. Call before the session starts (the rig is rebuilt).
    pub fn with_link_timeout(mut self, periods: u32) -> Result<Self, LinkError> {
        let config = RigConfig {
            lockstep_timeout_ticks: periods.max(1),
            ..*self.rig.config()
        };
        self.rig = Rig::new(config).map_err(|e| LinkError::Io {
            what: "rig configuration".into(),
            message: e.to_string(),
        })?;
        Ok(self)
    }

    /// The core's rig (for tests).
    pub fn rig(&self) -> &Rig<DEFAULT_SAMPLE_QUEUE> {
        &self.rig
    }

    fn collect(&mut self, fault_before: Option<FaultCode>) {
        while let Some(r) = self.rig.samples().pop() {
            self.samples.push(r);
        }
        if let (None, Some(code)) = (fault_before, self.rig.fault()) {
            self.faults.push(FaultReport {
                code,
                tick: self.rig.status().fault_tick,
            });
        }
    }
}

impl RigLink for SilLink {
    fn name(&self) -> String {
        "sil".into()
    }

    fn command(&mut self, command: &Command) -> Result<Reply, LinkError> {
        let before = self.rig.fault();
        self.rig.note_frame_ok();
        let result = self.rig.handle(command).map_err(|e| (&e).into());
        self.collect(before);
        reply_or_rejected(command, result)
    }

    fn exchange(&mut self, frame: &SensorFrame) -> Result<ActuatorFrame, LinkError> {
        let before = self.rig.fault();
        self.rig.note_frame_ok();
        let out = self.rig.lockstep(frame, TickTiming::Unknown);
        self.collect(before);
        Ok(out)
    }

    fn send_corrupted(&mut self, frame: &SensorFrame) -> Result<(), LinkError> {
        let before = self.rig.fault();
        for byte in corrupted_sensor_frame(frame) {
            match self.decoder.push::<HostMessage>(byte) {
                Some(Err(_)) => self.rig.note_frame_rejected(),
                Some(Ok(_)) => {
                    return Err(LinkError::Protocol(
                        "a corrupted frame passed the decoder".into(),
                    ));
                }
                None => {}
            }
        }
        self.collect(before);
        Ok(())
    }

    fn silent_period(&mut self) -> Result<Option<ActuatorFrame>, LinkError> {
        let before = self.rig.fault();
        let lost = self.rig.lockstep_silent_period();
        self.collect(before);
        if !lost {
            return Ok(None);
        }
        let status = self.rig.status();
        Ok(Some(ActuatorFrame {
            frame: u32::MAX,
            force_n: 0.0,
            trigger: false,
            drive_enabled: status.state.drive_enabled(),
            camera_frame: None,
            state: status.state,
            fault: status.fault,
            bed: status.bed.outputs,
        }))
    }

    fn take_samples(&mut self) -> Vec<SampleRecord> {
        std::mem::take(&mut self.samples)
    }

    fn take_faults(&mut self) -> Vec<FaultReport> {
        std::mem::take(&mut self.faults)
    }

    fn finish(&mut self) -> Result<LinkReport, LinkError> {
        let status = self.rig.status();
        Ok(LinkReport {
            final_status: Some(status),
            max_tick_instructions: None,
            exit_code: None,
            host_frames_rejected: 0,
            simulated_jump_height_m: None,
            board_realtime_factor: None,
        })
    }
}
