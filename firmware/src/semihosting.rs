//! ARM semihosting calls used by the emulated board (QEMU `-semihosting-config enable=on`):
//! open/read/write host files (the lockstep FIFOs), console text, the command line, and exit
//! with a status code.
//!
//! Every call traps into the emulator (`bkpt 0xAB`); on real hardware without a debugger this
//! would fault, which is why only the `board-qemu` build uses this module.

use cortex_m_semihosting::{nr, syscall, syscall1};

/// `SYS_EXIT_EXTENDED`: exit with a 32-bit status (QEMU returns it as its own exit status).
const SYS_EXIT_EXTENDED: usize = 0x20;
/// `ADP_Stopped_ApplicationExit`: the reason code for a normal application exit.
const ADP_STOPPED_APPLICATION_EXIT: usize = 0x2_0026;

/// A host file handle returned by `SYS_OPEN`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostFile(usize);

impl HostFile {
    /// The host's handle number.
    pub fn raw(self) -> usize {
        self.0
    }

    /// A handle number previously returned by [`HostFile::raw`].
    pub fn from_raw(handle: usize) -> Self {
        Self(handle)
    }
}

/// How to open a host file (semihosting `SYS_OPEN` modes).
#[derive(Clone, Copy, Debug)]
pub enum OpenMode {
    /// `"rb"`: read only.
    Read,
    /// `"wb"`: write only, created or truncated (a FIFO is simply opened for writing).
    Write,
}

/// Opens `path` on the host. A FIFO blocks here until the other side opens it.
pub fn open(path: &str, mode: OpenMode) -> Option<HostFile> {
    // SYS_OPEN wants a NUL-terminated string and its length without the NUL.
    let mut z = [0u8; 256];
    let bytes = path.as_bytes();
    if bytes.len() >= z.len() || bytes.contains(&0) {
        return None;
    }
    z[..bytes.len()].copy_from_slice(bytes);
    let mode = match mode {
        OpenMode::Read => nr::open::R_BINARY,
        OpenMode::Write => nr::open::W_TRUNC_BINARY,
    };
    // SAFETY: the argument block points at a live NUL-terminated buffer for the call's duration.
    let fd = unsafe { syscall(nr::OPEN, &[z.as_ptr() as usize, mode, bytes.len()]) };
    (fd as isize >= 0).then_some(HostFile(fd))
}

/// Reads up to `buf.len()` bytes; returns how many arrived (0 = end of file). A FIFO blocks
/// until at least one byte is available, then returns what is there. `None` on a host error.
pub fn read(file: HostFile, buf: &mut [u8]) -> Option<usize> {
    // SAFETY: the buffer outlives the call and its length is passed with it.
    let not_read = unsafe { syscall(nr::READ, &[file.0, buf.as_mut_ptr() as usize, buf.len()]) };
    (not_read <= buf.len()).then(|| buf.len() - not_read)
}

/// Writes all of `bytes`; `false` if the host could not take them (e.g. the reader is gone).
pub fn write_all(file: HostFile, bytes: &[u8]) -> bool {
    if bytes.is_empty() {
        return true;
    }
    // SAFETY: the buffer outlives the call and its length is passed with it.
    let not_written =
        unsafe { syscall(nr::WRITE, &[file.0, bytes.as_ptr() as usize, bytes.len()]) };
    not_written == 0
}

/// The command line QEMU passes (`-semihosting-config ...,arg=...`), space-separated, in `buf`.
pub fn command_line(buf: &mut [u8]) -> Option<&str> {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: the block names a live buffer; the host writes at most `buf.len()` bytes and
    // stores the length it wrote back into `block[1]`.
    let status = unsafe { syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status != 0 {
        return None;
    }
    let len = block[1].min(buf.len());
    core::str::from_utf8(&buf[..len]).ok()
}

/// Ends the emulation with `code` as QEMU's exit status.
pub fn exit(code: u32) -> ! {
    loop {
        // SAFETY: SYS_EXIT_EXTENDED reads the two-word block and does not return under QEMU.
        unsafe {
            syscall(
                SYS_EXIT_EXTENDED,
                &[ADP_STOPPED_APPLICATION_EXIT, code as usize],
            )
        };
    }
}
