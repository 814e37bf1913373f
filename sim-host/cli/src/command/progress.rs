//! The command line's [`Progress`]: indicatif bars on stderr (shown only on a terminal) and
//! notes printed on stderr; and a library error as the command line's error.

use std::sync::Mutex;

use sandjumper_output::{Blame, Blamed, CliError, EXIT_BAD_INPUT, EXIT_INTERNAL, Progress};

/// Progress bars and notes on stderr; Ctrl-C is read from [`crate::interrupt`].
#[derive(Default)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    /// Run `f` (which prints) with the current bar out of the way.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        let bar = self.bar.lock().unwrap_or_else(|e| e.into_inner()).clone();
        match bar {
            Some(b) => b.suspend(f),
            None => f(),
        }
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: Option<u64>) {
        let bar = match len {
            Some(n) => super::progress_bar(n, what),
            None => super::progress_counter(what),
        };
        if let Some(old) = self
            .bar
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .replace(bar)
        {
            old.finish_and_clear();
        }
    }

    fn advance(&self, n: u64) {
        if let Some(b) = &*self.bar.lock().unwrap_or_else(|e| e.into_inner()) {
            b.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }

    fn note(&self, line: &str) {
        self.suspend(|| eprintln!("{line}"));
    }

    fn cancelled(&self) -> bool {
        crate::interrupt::interrupted()
    }
}

/// A library error as the command line's message and exit status.
pub fn cli_error<E: Blamed>(e: E) -> CliError {
    CliError {
        message: e.to_string(),
        exit: match e.blame() {
            Blame::Input => EXIT_BAD_INPUT,
            Blame::Internal => EXIT_INTERNAL,
        },
    }
}
