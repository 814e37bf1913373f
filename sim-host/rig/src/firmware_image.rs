//! Which board a firmware ELF was built for, read from its header before anything boots or
//! flashes it: QEMU must not be handed the STM32F407 image (it locks up with a register
//! dump), nor probe-rs the emulated board's.
//!
//! The two builds differ where their code lives (the linker scripts `memory.x` and
//! `firmware/mps2-an386.x`): the F407 runs from flash at `0x0800_0000`, the emulated board
//! (QEMU mps2-an386) from code RAM at `0x0000_0000` (4 MiB). The ELF's entry point (the reset
//! handler) says which.

use std::fmt;
use std::path::{Path, PathBuf};

/// The build directory of the emulated board, relative to the workspace root: its own target
/// directory, so the two boards' builds (same binary name) never overwrite each other.
pub const EMULATED_TARGET_DIR: &str = "target/firmware";
/// The emulated board's ELF, relative to the workspace root (the default `--firmware` of
/// `hil --link pil` and `rig --link pil`).
pub const EMULATED_ELF: &str = "target/firmware/thumbv7em-none-eabihf/release/sandjumper-firmware";
/// The STM32F407 ELF, relative to the workspace root (the default of `rig flash`).
pub const F407_ELF: &str = "target/thumbv7em-none-eabihf/release/sandjumper-firmware";
/// The command that builds the emulated board's firmware into [`EMULATED_TARGET_DIR`].
pub const EMULATED_BUILD: &str = "cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf \
     --release --no-default-features --features board-qemu --target-dir target/firmware";
/// The command that builds the STM32F407 firmware.
pub const F407_BUILD: &str =
    "cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release";

/// A board the firmware is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Board {
    /// The rig board, STM32F407 (code in flash at 0x0800_0000).
    F407,
    /// The emulated board, QEMU mps2-an386 (code RAM at 0x0000_0000, 4 MiB).
    Emulated,
}

impl Board {
    /// The board whose code memory holds `entry`, if any.
    pub fn of_entry(entry: u32) -> Option<Board> {
        match entry {
            0x0000_0000..0x0040_0000 => Some(Board::Emulated),
            0x0800_0000..0x0810_0000 => Some(Board::F407),
            _ => None,
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Board::F407 => "the STM32F407 build (code in flash at 0x0800_0000)",
            Board::Emulated => "the emulated-board build (QEMU mps2-an386, code RAM at 0x0)",
        }
    }

    fn build_command(self) -> &'static str {
        match self {
            Board::F407 => F407_BUILD,
            Board::Emulated => EMULATED_BUILD,
        }
    }
}

/// A firmware file that cannot be used for the board asked for: the file, what it is, and the
/// command that builds the right one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageError {
    /// The file.
    pub path: PathBuf,
    /// What the file is (or why it cannot be read).
    pub found: String,
    /// The board it was meant for.
    pub wanted: Board,
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "firmware `{}` is {}; {} is needed: build it with `{}`{}",
            self.path.display(),
            self.found,
            self.wanted.describe(),
            self.wanted.build_command(),
            match self.wanted {
                Board::Emulated => format!(" (it lands in {EMULATED_ELF})"),
                Board::F407 => format!(" (it lands in {F407_ELF})"),
            }
        )
    }
}

impl std::error::Error for ImageError {}

/// Check that `path` is a 32-bit little-endian ARM ELF executable built for `wanted`.
pub fn check_elf(path: &Path, wanted: Board) -> Result<(), ImageError> {
    let fail = |found: String| ImageError {
        path: path.to_path_buf(),
        found,
        wanted,
    };
    let bytes = std::fs::read(path).map_err(|e| {
        fail(if e.kind() == std::io::ErrorKind::NotFound {
            "not found".into()
        } else {
            format!("unreadable ({e})")
        })
    })?;
    let entry = elf_entry(&bytes).map_err(fail)?;
    match Board::of_entry(entry) {
        Some(b) if b == wanted => Ok(()),
        Some(b) => Err(fail(b.describe().into())),
        None => Err(fail(format!(
            "an ARM ELF with its entry point at {entry:#010x}, in neither board's code memory"
        ))),
    }
}

/// The entry point of a 32-bit little-endian ARM executable ELF, or what the bytes are instead.
fn elf_entry(bytes: &[u8]) -> Result<u32, String> {
    const EM_ARM: u16 = 40;
    const ET_EXEC: u16 = 2;
    if bytes.len() < 52 || &bytes[..4] != b"\x7fELF" {
        return Err(format!("not an ELF file ({} bytes)", bytes.len()));
    }
    if bytes[4] != 1 || bytes[5] != 1 {
        return Err("an ELF file, but not 32-bit little-endian (not a Cortex-M image)".into());
    }
    let u16_at = |o: usize| u16::from_le_bytes([bytes[o], bytes[o + 1]]);
    let machine = u16_at(18);
    if machine != EM_ARM {
        return Err(format!(
            "an ELF file for machine {machine}, not ARM ({EM_ARM})"
        ));
    }
    if u16_at(16) != ET_EXEC {
        return Err("an ARM ELF file, but not an executable".into());
    }
    // The Thumb bit of the entry address is not part of the location.
    Ok(u32::from_le_bytes([bytes[24], bytes[25], bytes[26], bytes[27]]) & !1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(machine: u16, kind: u16, entry: u32) -> Vec<u8> {
        let mut b = vec![0u8; 64];
        b[..4].copy_from_slice(b"\x7fELF");
        b[4] = 1;
        b[5] = 1;
        b[16..18].copy_from_slice(&kind.to_le_bytes());
        b[18..20].copy_from_slice(&machine.to_le_bytes());
        b[24..28].copy_from_slice(&entry.to_le_bytes());
        b
    }

    #[test]
    fn entry_points_name_their_board() {
        assert_eq!(elf_entry(&header(40, 2, 0x0000_0401)), Ok(0x400));
        assert_eq!(Board::of_entry(0x400), Some(Board::Emulated));
        assert_eq!(Board::of_entry(0x0800_0189), Some(Board::F407));
        assert_eq!(Board::of_entry(0x2000_0000), None);
    }

    #[test]
    fn other_files_say_what_they_are() {
        assert!(elf_entry(b"hello").unwrap_err().contains("not an ELF"));
        assert!(
            elf_entry(&header(62, 2, 0))
                .unwrap_err()
                .contains("machine 62")
        );
        assert!(
            elf_entry(&header(40, 1, 0))
                .unwrap_err()
                .contains("not an executable")
        );
    }
}
