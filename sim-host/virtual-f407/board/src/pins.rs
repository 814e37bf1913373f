//! The F407's GPIO ports as the board's models and the rig read them: port indices and a
//! pin's electrical level.

use rigless::device::Level;
use rigless::soc::stm32f427::Stm32f427;
use rigless::soc::stm32f427::peripherals::gpio::Pin;

/// Port indices (rigless's `PORTS` order).
pub const PORT_A: usize = 0;
/// Port B.
pub const PORT_B: usize = 1;
/// Port C.
pub const PORT_C: usize = 2;
/// Port D.
pub const PORT_D: usize = 3;
/// Port E.
pub const PORT_E: usize = 4;

/// `pin` of port `port` reads high (its electrical level: driven, or its pull).
pub fn high(part: &mut Stm32f427, port: usize, pin: u8) -> bool {
    let (gpio, regs) = part.port(port);
    gpio.level(Pin::new(pin).expect("pin 0..15"), regs) == Level::High
}
