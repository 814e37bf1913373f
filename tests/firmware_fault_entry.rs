//! The STM32F407 image's fault paths, read from its disassembly (the board itself is not
//! here): the HardFault entry drops the drive using registers only before it touches the stack
//! (a stack overflow leaves the stack pointer below RAM, and a push there locks the core up
//! with the enable line high), and the panic handler masks interrupts before anything else
//! (the control tick must not preempt it and re-enable the drive).
//!
//! Needs the F407 release build and `llvm-objdump` (rustup's llvm-tools); skipped with a
//! message without them, except under CI (`.ci/run` builds and installs both first).

use std::path::{Path, PathBuf};
use std::process::Command;

fn skip_or_fail(why: &str) {
    assert!(std::env::var_os("CI").is_none(), "CI must have: {why}");
    eprintln!("SKIPPED: {why}");
}

fn objdump() -> Option<PathBuf> {
    let sysroot = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .ok()?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    let host = Command::new("rustc").args(["-vV"]).output().ok()?;
    let host = String::from_utf8_lossy(&host.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))?;
    let tool = sysroot.join(format!("lib/rustlib/{host}/bin/llvm-objdump"));
    tool.is_file().then_some(tool)
}

/// The instructions of `symbol` (mnemonic and operands, one per line).
fn disassemble(tool: &Path, elf: &Path, symbol: &str) -> Vec<String> {
    let out = Command::new(tool)
        .args(["-d", "--no-show-raw-insn"])
        .arg(format!("--disassemble-symbols={symbol}"))
        .arg(elf)
        .output()
        .expect("llvm-objdump runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (addr, rest) = l.split_once(':')?;
            u32::from_str_radix(addr.trim(), 16).ok()?;
            Some(rest.trim().to_string())
        })
        .collect()
}

fn setup() -> Option<(PathBuf, PathBuf)> {
    let elf =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(sandjumper_sim::rig::firmware_image::F407_ELF);
    if !elf.is_file() {
        skip_or_fail(&format!("the F407 image at {}", elf.display()));
        return None;
    }
    let Some(tool) = objdump() else {
        skip_or_fail("llvm-objdump (rustup component add llvm-tools)");
        return None;
    };
    Some((tool, elf))
}

#[test]
fn hard_fault_makes_the_drive_safe_with_registers_only() {
    let Some((tool, elf)) = setup() else { return };
    let code = disassemble(&tool, &elf, "HardFault");
    let until_stack = code
        .iter()
        .position(|i| i.starts_with("msr") && i.contains("msp"))
        .unwrap_or_else(|| panic!("HardFault never resets the stack pointer:\n{code:#?}"));
    let entry = &code[..until_stack];
    assert!(entry[0].starts_with("cpsid"), "{entry:#?}");
    for insn in entry {
        let mnemonic = insn.split_whitespace().next().unwrap_or("");
        let reads_msp = matches!(mnemonic, "mrs" | "msr");
        assert!(
            !matches!(mnemonic, "push" | "vpush" | "stmdb" | "bl" | "blx")
                && (reads_msp || !insn.contains("sp")),
            "`{insn}` uses the stack before it is valid:\n{entry:#?}"
        );
    }
    let stores = entry.iter().filter(|i| i.starts_with("str")).count();
    assert!(stores >= 2, "drive enable and DAC writes: {entry:#?}");
}

/// The (mangled) name of the symbol whose name contains `part`.
fn symbol_containing(tool: &Path, elf: &Path, part: &str) -> String {
    let nm = tool.with_file_name("llvm-nm");
    let out = Command::new(nm).arg(elf).output().expect("llvm-nm runs");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().nth(2))
        .find(|name| name.contains(part))
        .unwrap_or_else(|| panic!("no symbol with `{part}`"))
        .to_string()
}

#[test]
fn the_panic_handler_masks_interrupts_before_it_writes_a_register() {
    let Some((tool, elf)) = setup() else { return };
    let handler = symbol_containing(&tool, &elf, "rust_begin_unwind");
    let code = disassemble(&tool, &elf, &handler);
    let mask = code.iter().position(|i| i.starts_with("cpsid"));
    // The first store that is not to the stack: the drive enable (GPIOE BSRR).
    let first_write = code
        .iter()
        .position(|i| i.starts_with("str") && !i.contains("[sp"));
    assert!(
        matches!((mask, first_write), (Some(m), Some(w)) if m < w),
        "{code:#?}"
    );
}
