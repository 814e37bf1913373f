//! `sandjumper-core`: the `no_std` core shared by the firmware and the host.
#![no_std]
