#!/usr/bin/env bash
# Builds the virtual STM32F407 board: target/release/virtual-f407 (rustc 1.98.0, see
# rust-toolchain.toml). About 3 min cold on 2 cores.
set -euo pipefail
cd "$(dirname "$0")"
./patch-rigless.sh
cargo build --release --locked "$@"
