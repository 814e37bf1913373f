//! The rig's STM32F407 firmware, the unmodified release ELF, on a virtual board in virtual time.
pub mod board;
pub mod core_clock;
pub mod encoder;
pub mod models;
pub mod pins;
pub mod rig;
pub mod rtt;
pub mod run;
