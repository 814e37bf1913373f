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

#[test]
fn gdb_breaks_in_the_tick_and_reads_registers_and_memory() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    if !gdb_here() {
        return;
    }
    // Any free port; the core waits for the debugger; 50 virtual ms once it runs free.
    let mut board = Command::new(env!("CARGO_BIN_EXE_virtual-f407"))
        .arg("--elf")
        .arg(&elf)
        .args(["--gdb", "127.0.0.1:0", "--gdb-wait", "--ms", "50"])
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
    let gdb = Command::new("gdb-multiarch")
        .args(["-batch", "-nx"])
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
        .arg(&elf)
        .output()
        .expect("gdb-multiarch runs");
    let said =
        String::from_utf8_lossy(&gdb.stdout).into_owned() + &String::from_utf8_lossy(&gdb.stderr);
    let status = board.wait().expect("the board ends");
    let mut rest = String::new();
    let _ = std::io::Read::read_to_string(&mut stderr, &mut rest);
    assert!(status.success(), "the board: {status}\n{rest}\ngdb: {said}");
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
