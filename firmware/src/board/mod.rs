//! Board facts: one module per board, selected by cargo feature.

#[cfg(feature = "board-f407")]
pub mod f407;
#[cfg(feature = "board-qemu")]
pub mod mps2_an386;
