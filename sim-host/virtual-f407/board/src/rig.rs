//! What the rig wires to the board's pins (firmware `board/f407.rs` and docs/firmware.md's
//! wiring table): the drive's force input on the DAC (channel 1, PA4) through the offset and
//! gain stage (0 V -> -300 N, 1.65 V -> 0 N, 3.3 V -> +300 N) gated by its enable (PE7), the
//! linear encoder into TIM2, the motor current monitor on PA1 (ADC1 channel 1), the bed's lift
//! limit switches (PE12 up, PE13 down: closed to ground at the limit), the emergency stop's
//! normally-closed loop on its own connector (PE14: to ground while released, or through a
//! jumper plug; open when pressed, broken or unplugged), the harness's presence line (PE15: to
//! ground while the apparatus is connected), the bed-height sensor (PA2, ADC2
//! channel 2), and the outputs the bed apparatus reads: blower (DAC channel 2), shaker (PC6,
//! TIM3 CH1), lift enable and direction (PE10, PE11), camera trigger (PE9), tick heartbeat (PE8).

use rigless::device::Level;
use rigless::soc::stm32f427::Stm32f427;
use rigless::soc::stm32f427::peripherals::adc::Channel as AdcChannel;
use rigless::soc::stm32f427::peripherals::gpio::Pin;
use rigless::time::VirtualNanos;
use sandjumper_model::error::SimError;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::plant::{Plant, PlantState};

use crate::board::F407;
use crate::models::dac::VDDA_V;

pub use crate::pins::{PORT_A, PORT_B, PORT_C, PORT_D, PORT_E, high};

/// The enable gate's monostable period, ns (docs/firmware.md: a 74HC123 with ~1 ms).
pub const MONOSTABLE_NS: u64 = 1_000_000;

/// Drive force at the DAC's full scale, N (the drive's peak force).
pub const DRIVE_FULL_SCALE_N: f64 = 300.0;
/// The encoder's resolution, m per count.
pub const METRES_PER_COUNT: f64 = 1e-6;

/// What is connected to the bed apparatus's harness inputs (PE12, PE13, PE15, PA2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BedWiring {
    /// Nothing: PE12, PE13 and PE15 float (their pull-ups read high), PA2 floats (0 V here).
    Unwired,
    /// The apparatus's harness, which ties the presence line PE15 to ground.
    Connected {
        /// The lift's upper limit switch closed.
        lift_up_limit: bool,
        /// The lift's lower limit switch closed.
        lift_down_limit: bool,
    },
    /// The apparatus's harness with its presence link (PE15) broken: the lift down, PE15
    /// floating.
    BrokenPresenceLink,
}

impl BedWiring {
    /// The apparatus at rest, ready to jump.
    pub const READY: Self = Self::Connected {
        lift_up_limit: false,
        lift_down_limit: true,
    };
}

/// The emergency stop's loop on its own connector (PE14 to ground).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmergencyStopLoop {
    /// Closed: the stop released (its normally-closed contact), or a jumper plug on the
    /// connector: PE14 at ground.
    Closed,
    /// Open: the stop pressed, a wire broken, or nothing plugged in: PE14 floats (its pull-up
    /// reads high).
    Open,
}

/// The outputs the board drives now, as the rig reads them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs {
    /// DAC channel 1, V.
    pub force_dac_v: f64,
    /// The force the drive is commanded with (zero while its gated enable is low), N.
    pub force_n: f64,
    /// PE7.
    pub drive_enable: bool,
    /// The enable the drive sees: PE7 through the external retriggerable monostable the tick
    /// heartbeat (PE8) keeps triggered (docs/firmware.md: ~1 ms, [`MONOSTABLE_NS`]); a halted
    /// or locked-up core stops the heartbeat and the gate closes.
    pub drive_gated: bool,
    /// PE8.
    pub heartbeat: bool,
    /// PE9.
    pub camera_trigger: bool,
    /// PE10.
    pub lift_enable: bool,
    /// The enable the lift motor sees: PE10 through the same monostable as the drive's.
    pub lift_gated: bool,
    /// PE11.
    pub lift_up: bool,
    /// DAC channel 2, V.
    pub blower_dac_v: f64,
    /// TIM3 CH1's PWM duty on PC6 (the shaker's), 0-1 (0 when not a running PWM).
    pub shaker_duty: f64,
    /// PD12 (green, running).
    pub led_running: bool,
    /// PD14 (red, fault).
    pub led_fault: bool,
}

impl Outputs {
    /// The whole safe state as the firmware drives it: drive enable (PE7) low, the bed's
    /// actuators off (blower below 10 mV, lift disabled, shaker duty zero).
    pub fn drive_and_lift_safe(&self) -> bool {
        !self.drive_enable
            && !self.lift_enable
            && self.blower_dac_v < 0.01
            && self.shaker_duty == 0.0
    }
}

/// TIM3 channel 1's PWM duty (the shaker), read off the timer as a scope would see its pin.
fn shaker_duty(part: &mut Stm32f427) -> f64 {
    let (tim, regs) = part.timer(1);
    match tim.pulse(
        rigless::soc::st::tim::Channel::new(1).expect("channel 1"),
        regs,
    ) {
        Some(p) if p.period.0 > 0 => p.width.0 as f64 / p.period.0 as f64,
        _ => 0.0,
    }
}

/// Reads the board's outputs.
pub fn outputs(mcu: &mut F407) -> Outputs {
    let part = &mut mcu.part;
    let drive_enable = high(part, PORT_E, 7);
    mcu.dac.tim7_trgo_ns = mcu.tim7.last_trgo_ns;
    let force_dac_v = mcu.dac.volts(0);
    let half = VDDA_V / 2.0;
    let force_n = if drive_enable {
        (force_dac_v - half) / half * DRIVE_FULL_SCALE_N
    } else {
        0.0
    };
    Outputs {
        force_dac_v,
        force_n,
        drive_enable,
        drive_gated: drive_enable,
        heartbeat: high(part, PORT_E, 8),
        camera_trigger: high(part, PORT_E, 9),
        lift_enable: high(part, PORT_E, 10),
        lift_gated: high(part, PORT_E, 10),
        lift_up: high(part, PORT_E, 11),
        blower_dac_v: mcu.dac.volts(1),
        shaker_duty: shaker_duty(part),
        led_running: high(part, PORT_D, 12),
        led_fault: high(part, PORT_D, 14),
    }
}

/// Drives the bed apparatus's inputs and the emergency stop's loop.
pub fn drive_bed_inputs(
    part: &mut Stm32f427,
    at: VirtualNanos,
    wiring: BedWiring,
    emergency_stop: EmergencyStopLoop,
    height_mv: u32,
) {
    let closed = |c: bool| if c { Some(Level::Low) } else { None };
    let (up, down, present) = match wiring {
        BedWiring::Unwired => (None, None, None),
        BedWiring::BrokenPresenceLink => (None, Some(Level::Low), None),
        BedWiring::Connected {
            lift_up_limit,
            lift_down_limit,
        } => (
            closed(lift_up_limit),
            closed(lift_down_limit),
            Some(Level::Low),
        ),
    };
    let stop = closed(emergency_stop == EmergencyStopLoop::Closed);
    for (pin, level) in [12u8, 13, 14, 15]
        .into_iter()
        .zip([up, down, stop, present])
    {
        part.drive_port(at, PORT_E, |gpio, regs, cx| {
            gpio.drive(Pin::new(pin).expect("pin"), level, regs, cx)
        });
    }
    let height = if wiring == BedWiring::Unwired {
        0
    } else {
        height_mv
    };
    part.adc[1].set_input(AdcChannel::new(2).expect("channel 2"), height);
}

/// The motor current monitor on PA1: +-10 V for +-10 A, divided to 0..3.3 V about 1.65 V.
pub fn drive_current_sense(part: &mut Stm32f427, current_a: f64) {
    let mv = (1650.0 + current_a / 10.0 * 1650.0).clamp(0.0, 3300.0);
    part.adc[0].set_input(AdcChannel::new(1).expect("channel 1"), mv.round() as u32);
}

/// The robot on its sand (or hard ground): the plant the drive's force moves.
#[derive(Debug)]
pub struct Robot {
    plant: Plant,
    state: PlantState,
}

impl Robot {
    /// The robot at rest with the motor at `p0_m` (the encoder's zero is where the carriage is
    /// at power-up: see [`Robot::count`]).
    pub fn new(params: &Params, model: ModelName, p0_m: f64) -> Result<Self, SimError> {
        let opts = sandjumper_model::options::SimOptions {
            rtol: 1e-6,
            ..Default::default()
        };
        let plant = Plant::new(params, model, p0_m, &opts)?;
        let state = plant.state();
        Ok(Self { plant, state })
    }

    /// Advance `dt_s` with the drive commanded to `force_n` (through its current loop).
    pub fn advance(&mut self, dt_s: f64, force_n: f64) -> Result<(), SimError> {
        let k_f = self.plant.drive().force_constant_n_a;
        self.plant.advance_current(dt_s, force_n / k_f)?;
        self.state = self.plant.state();
        Ok(())
    }

    /// The plant's state.
    pub fn state(&self) -> PlantState {
        self.state
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The motor current now, A.
    pub fn current_a(&self) -> f64 {
        let k_f = self.plant.drive().force_constant_n_a;
        if k_f > 0.0 { self.state.f_m / k_f } else { 0.0 }
    }
}
