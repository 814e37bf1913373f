//! Firmware placeholder; built only for thumbv7em-none-eabihf.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("sandjumper-firmware builds only for --target thumbv7em-none-eabihf");
}
