//! Text output of the emulated board: semihosting's console (`:tt`), which QEMU prints on its
//! own standard output. Used for boot messages, the self-test report and fault/panic reports;
//! never in the control path.

use crate::semihosting::{self, HostFile, OpenMode};
use core::fmt;
use core::sync::atomic::{AtomicUsize, Ordering};

/// The console's host handle + 1 (0 = not opened yet).
static CONSOLE: AtomicUsize = AtomicUsize::new(0);

/// Writes to the semihosting console; opens it on first use.
pub struct Console;

impl Console {
    fn file() -> Option<HostFile> {
        match CONSOLE.load(Ordering::Relaxed) {
            0 => {
                let file = semihosting::open(":tt", OpenMode::Write)?;
                CONSOLE.store(file.raw() + 1, Ordering::Relaxed);
                Some(file)
            }
            n => Some(HostFile::from_raw(n - 1)),
        }
    }
}

impl fmt::Write for Console {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let file = Self::file().ok_or(fmt::Error)?;
        semihosting::write_all(file, s.as_bytes())
            .then_some(())
            .ok_or(fmt::Error)
    }
}

/// `println!` to the semihosting console (errors ignored: there is nowhere else to say them).
macro_rules! console {
    ($($arg:tt)*) => {{
        use core::fmt::Write as _;
        let _ = writeln!($crate::console::Console, $($arg)*);
    }};
}
pub(crate) use console;
