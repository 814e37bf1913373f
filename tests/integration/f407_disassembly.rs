//! The STM32F407 image, read from its disassembly (the board itself is not here):
//! - the HardFault entry drops the drive using registers only before it touches the stack (a
//!   stack overflow leaves the stack pointer below RAM, and a push there locks the core up
//!   with the enable line high);
//! - the panic handler masks interrupts before anything else (the control tick must not
//!   preempt it and re-enable the drive);
//! - nothing the control tick calls logs (defmt over RTT in blocking mode would stall the tick
//!   with the drive on when the buffer is full or the probe has gone).
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
    let elf = Path::new(env!("CARGO_MANIFEST_DIR")).join(sandjumper_rig::firmware_image::F407_ELF);
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

/// Every function the code starting at `root` can call, by name (demangled), from the whole
/// image's disassembly: direct calls and branches to other functions, not descending into
/// the panic path (`stop` names it; a panic makes the drive safe before it logs).
fn reachable(tool: &Path, elf: &Path, root: &str, stop: &[&str]) -> Vec<String> {
    let out = Command::new(tool)
        .args(["-d", "--no-show-raw-insn", "-C"])
        .arg(elf)
        .output()
        .expect("llvm-objdump runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let mut calls: std::collections::HashMap<String, Vec<String>> = Default::default();
    let mut current = String::new();
    for line in text.lines() {
        // `0800040c <name>:` starts a function.
        if let Some(rest) = line.strip_suffix(">:")
            && let Some((_, name)) = rest.split_once(" <")
        {
            current = name.to_string();
            continue;
        }
        let Some((_, insn)) = line.split_once(':') else {
            continue;
        };
        let insn = insn.trim();
        let mnemonic = insn.split_whitespace().next().unwrap_or("");
        if !(mnemonic.starts_with("bl") || mnemonic.starts_with("b.") || mnemonic == "b") {
            continue;
        }
        if let Some((_, target)) = insn.split_once(" <")
            && let Some(target) = target.split('>').next()
            && !target.contains('+')
        {
            calls
                .entry(current.clone())
                .or_default()
                .push(target.to_string());
        }
    }
    let mut seen = vec![root.to_string()];
    let mut todo = vec![root.to_string()];
    while let Some(f) = todo.pop() {
        for g in calls.get(&f).into_iter().flatten() {
            if !seen.contains(g) && !stop.iter().any(|s| g.contains(s)) {
                seen.push(g.clone());
                todo.push(g.clone());
            }
        }
    }
    seen
}

#[test]
fn the_control_tick_and_the_usb_task_never_log() {
    let Some((tool, elf)) = setup() else { return };
    let stop = [
        "panic",
        "rust_begin_unwind",
        "unwrap_failed",
        "expect_failed",
    ];
    let from_tick = reachable(&tool, &elf, "TIM7", &stop);
    assert!(
        from_tick
            .iter()
            .any(|f| f.contains("Rig") && f.contains("tick")),
        "the call graph misses the core's tick: {from_tick:#?}"
    );
    let logging: Vec<&String> = from_tick.iter().filter(|f| f.contains("defmt")).collect();
    assert!(
        logging.is_empty(),
        "the control tick reaches defmt (a blocking RTT buffer would stall it): {logging:#?}"
    );
    // Nor does the USB link task: a defmt write masks every interrupt, the tick's included.
    let from_link = reachable(&tool, &elf, "OTG_FS", &stop);
    assert!(
        from_link.iter().any(|f| f.contains("usb_device")),
        "the call graph misses the USB stack: {from_link:#?}"
    );
    let logging: Vec<&String> = from_link.iter().filter(|f| f.contains("defmt")).collect();
    assert!(
        logging.is_empty(),
        "the USB link task reaches defmt (its critical section masks the tick): {logging:#?}"
    );
    // The checker sees logging where there is some: the clock security NMI's handler reports.
    let from_nmi = reachable(&tool, &elf, "NonMaskableInt", &stop);
    assert!(
        from_nmi.iter().any(|f| f.contains("defmt")),
        "{from_nmi:#?}"
    );
}

/// The control tick has no panic path at all (the brief: the firmware never panics in the control
/// path). Every function the tick's interrupt can reach, the panic machinery included: none of
/// it is `core::panicking`, a failed index, `unwrap` or `expect`. `f32::clamp` (it panics on a
/// bad limit, and pulled 16 KiB of float printing into the image) and indexing in the replay
/// table's evaluation and upload used to be there.
#[test]
fn the_control_tick_has_no_panic_path() {
    let Some((tool, elf)) = setup() else { return };
    let from_tick = reachable(&tool, &elf, "TIM7", &[]);
    assert!(
        from_tick
            .iter()
            .any(|f| f.contains("Rig") && f.contains("tick")),
        "the call graph misses the core's tick: {from_tick:#?}"
    );
    let panics: Vec<&String> = from_tick
        .iter()
        .filter(|f| {
            [
                "panic",
                "unwind",
                "unwrap_failed",
                "expect_failed",
                "index_fail",
                "len_mismatch",
            ]
            .iter()
            .any(|p| f.contains(p))
        })
        .collect();
    assert!(
        panics.is_empty(),
        "the control tick can panic through {panics:#?}"
    );
    // The checker sees panics where there are some: the USB link task (the USB crates index).
    let from_link = reachable(&tool, &elf, "OTG_FS", &[]);
    assert!(
        from_link.iter().any(|f| f.contains("panicking")),
        "{from_link:#?}"
    );
}
