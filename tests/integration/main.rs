//! The integration tests of this crate, one test binary: one module per file (each file's
//! own doc says what it tests). One binary links once, where one binary per file linked
//! the whole dependency tree once per file; nextest still runs each test in its own process.

mod board_memory_map;
mod docs_links;
mod f407_disassembly;
mod firmware_qemu_smoke;
mod hil_camera;
mod hil_cli;
mod hil_common;
mod hil_event_times;
mod hil_faults;
mod hil_firmware_image;
mod hil_gain_lowering;
mod hil_sil_jumps;
mod pil_campaign;
mod pil_command_cost;
mod pil_loop;
mod readme_layout;
mod reproduction_numbers;
mod sweep_sil;
mod track_sil;
mod virtual_f407;
