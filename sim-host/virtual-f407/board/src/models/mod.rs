//! What rigless's STM32F427 lacks and the rig's firmware uses, written against rigless's
//! `Device` API: one model per peripheral, each opening with what it covers and leaves out.

pub mod basic_timer;
pub mod dac;
pub mod otg_fs;
