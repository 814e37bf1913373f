//! The emulated board: QEMU `mps2-an386` (ARM MPS2 with the AN386 FPGA image, Cortex-M4F).
//!
//! No rig peripherals exist here: the encoder, current sense, drive and camera trigger are
//! replaced by the lockstep hardware-in-the-loop frames (see `app_qemu`). What the board does
//! provide:
//! - code RAM at 0x0000_0000 and data RAM at 0x2000_0000 (`firmware/mps2-an386.x`);
//! - SysTick clocked at the 25 MHz system clock, which under `-icount` advances with the
//!   instruction count: the tick-cost counter (`tick_cost`);
//! - CMSDK APB UART0 at 0x4000_4000 (QEMU's first `-serial`), the UART link variant.

/// CMSDK APB UART0 base address (AN386 application note; QEMU `hw/arm/mps2.c`).
pub const UART0_BASE: usize = 0x4000_4000;
