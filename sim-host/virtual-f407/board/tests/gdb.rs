//! GDB on the virtual board (`virtual-f407 --gdb ADDR`): Debian's `gdb-multiarch` connects to the
//! running F407 release binary, breaks in the control tick's handler (TIM7), reads a register and
//! memory, and lets the board run on. Skipped without `gdb-multiarch` (failing under CI, which
//! installs it).

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

mod common;

/// Whether `gdb-multiarch` runs here.
fn gdb_here() -> bool {
    let ok = Command::new("gdb-multiarch")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        let msg = "skipped: no gdb-multiarch (apt-get install gdb-multiarch)";
        if std::env::var_os("CI").is_some() {
            panic!("{msg}; under CI the GDB test must run");
        }
        eprintln!("{msg}");
    }
    ok
}

/// The board on `elf` with `args`, serving GDB on a free port and waiting for it: the process,
/// its stderr (past the first line) and the address served.
fn board_with_gdb(
    elf: &std::path::Path,
    args: &[&str],
) -> (
    std::process::Child,
    BufReader<std::process::ChildStderr>,
    String,
) {
    let mut board = Command::new(env!("CARGO_BIN_EXE_virtual-f407"))
        .arg("--elf")
        .arg(elf)
        .args(["--gdb", "127.0.0.1:0", "--gdb-wait"])
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the board starts");
    let mut stderr = BufReader::new(board.stderr.take().expect("its stderr"));
    let mut first = String::new();
    stderr.read_line(&mut first).expect("its first line");
    // "virtual-f407: GDB server on 127.0.0.1:PORT: gdb-multiarch ...".
    let addr = first
        .strip_prefix("virtual-f407: GDB server on ")
        .and_then(|rest| rest.split_once(": "))
        .map(|(addr, _)| addr.to_string())
        .unwrap_or_else(|| panic!("no GDB address in {first:?}"));
    (board, stderr, addr)
}

/// Runs `gdb` against the board to their ends: what GDB said (stdout and stderr) and the rest
/// of the board's stderr, the board's exit checked.
fn debugged_to_the_end(
    mut gdb: Command,
    mut board: std::process::Child,
    mut stderr: BufReader<std::process::ChildStderr>,
) -> (String, String) {
    let gdb = gdb.output().expect("gdb-multiarch runs");
    let said =
        String::from_utf8_lossy(&gdb.stdout).into_owned() + &String::from_utf8_lossy(&gdb.stderr);
    let status = board.wait().expect("the board ends");
    let mut rest = String::new();
    let _ = std::io::Read::read_to_string(&mut stderr, &mut rest);
    assert!(status.success(), "the board: {status}\n{rest}\ngdb: {said}");
    (said, rest)
}

/// RM0090 6.2.7: with the clock security system on, a stopped crystal sets `RCC_CIR.CSSF`, and
/// "the NMI is executed indefinitely unless the CSS interrupt pending bit is cleared" (`CSSC`).
/// The firmware's NMI handler never returns (it stops the rig and waits for the watchdog), so
/// GDB makes it return: a `BX LR` (EXC_RETURN in LR at the handler's first instruction) placed
/// in RAM below the stack and run. With `CSSF` still set the core takes the NMI again at once;
/// once GDB has written `CSSC`, the same return goes back to the interrupted code for good.
/// Fails with the NMI a one-shot pulse (the board's model before issue 51: one entry) and with
/// the input left high after `CSSC` (a third entry).
#[test]
fn the_clock_security_nmi_stays_pending_until_cssc() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    if !gdb_here() {
        return;
    }
    let (board, stderr, addr) = board_with_gdb(&elf, &["--ms", "150", "--crystal-stops-at", "100"]);
    // BX LR (0x4770), 256 bytes below the handler's stack pointer, run from there.
    let bx_lr = [
        "set {unsigned short}($sp - 256) = 0x4770",
        "set $pc = $sp - 256",
    ];
    let mut gdb = Command::new("gdb-multiarch");
    gdb.args(["-batch", "-nx"])
        .args(["-ex", &format!("target remote {addr}")])
        // C's casts for the raw memory writes below (the ELF's language is Rust).
        .args(["-ex", "set language c"])
        .args(["-ex", "break *NonMaskableInt"])
        .args(["-ex", "continue"]);
    // Returned with CSSF set: entered again.
    for step in bx_lr {
        gdb.args(["-ex", step]);
    }
    gdb.args(["-ex", "continue"])
        .args(["-ex", "print/x *(unsigned int *)0x4002380C"])
        // CSSC (RCC_CIR bit 23) clears CSSF; the return now goes back for good.
        .args(["-ex", "set *(unsigned int *)0x4002380C = 0x00800000"])
        .args(["-ex", "print/x *(unsigned int *)0x4002380C"]);
    for step in bx_lr {
        gdb.args(["-ex", step]);
    }
    gdb.args(["-ex", "continue"]).arg(&elf);
    let (said, _) = debugged_to_the_end(gdb, board, stderr);
    assert_eq!(
        said.matches("Breakpoint 1, ").count(),
        2,
        "the NMI entered twice (once more after a return with CSSF set), then not again: {said}"
    );
    // CSSF (bit 7) set before CSSC, clear after.
    let cir: Vec<u32> = said
        .lines()
        .filter_map(|l| {
            l.split_once(" = 0x")
                .and_then(|(_, v)| u32::from_str_radix(v.trim(), 16).ok())
        })
        .collect();
    assert_eq!(cir.len(), 2, "{said}");
    assert!(
        cir[0] & 0x80 != 0 && cir[1] & 0x80 == 0,
        "RCC_CIR {cir:x?}: {said}"
    );
    assert!(said.contains("exited normally"), "{said}");
}

#[test]
fn gdb_breaks_in_the_tick_and_reads_registers_and_memory() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    if !gdb_here() {
        return;
    }
    // Any free port; the core waits for the debugger; 50 virtual ms once it runs free.
    let (board, stderr, addr) = board_with_gdb(&elf, &["--ms", "50"]);
    let mut gdb = Command::new("gdb-multiarch");
    gdb.args(["-batch", "-nx"])
        .args(["-ex", &format!("target remote {addr}")])
        .args(["-ex", "break TIM7"])
        .args(["-ex", "continue"])
        .args(["-ex", "info symbol $pc"])
        .args(["-ex", "stepi"])
        .args(["-ex", "info symbol $pc"])
        .args(["-ex", "x/s &defmt_rtt::_SEGGER_RTT"])
        .args(["-ex", "continue"])
        .args(["-ex", "info symbol $pc"])
        .args(["-ex", "delete"])
        .args(["-ex", "continue"])
        .arg(&elf);
    let (said, rest) = debugged_to_the_end(gdb, board, stderr);
    // The breakpoint in the tick's handler was hit, twice (the tick goes on between), and a
    // step moved the core on inside it.
    assert_eq!(said.matches("Breakpoint 1, ").count(), 2, "{said}");
    let in_tim7 = said
        .lines()
        .filter(|l| l.contains(" in section .text") && l.starts_with("TIM7 + "))
        .count();
    assert_eq!(
        in_tim7, 3,
        "the program counter in TIM7 at each stop: {said}"
    );
    // Memory through the debugger: the RTT control block's id, as the firmware wrote it.
    assert!(said.contains("<_SEGGER_RTT>:\t\"SEGGER RTT\""), "{said}");
    // Let go, the board ran to its end and booted as always.
    assert!(said.contains("exited normally"), "{said}");
    assert!(rest.contains("sandjumper firmware: STM32F407"), "{rest}");
}
