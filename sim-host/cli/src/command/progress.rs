//! The command line's [`Progress`]: a library call's stages drawn as indicatif bars on stderr
//! (shown only on a terminal), its notes printed there, Ctrl-C read from [`crate::interrupt`].

use std::sync::{Mutex, MutexGuard, PoisonError};

use sandjumper_output::Progress;

use super::{progress_bar, progress_counter};

/// Progress bars and notes on stderr; [`Progress::cancelled`] is Ctrl-C once the command has
/// called [`crate::interrupt::catch`].
#[derive(Debug)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
    notes: bool,
    held: Option<Mutex<Vec<String>>>,
}

impl Default for Bars {
    fn default() -> Self {
        Self::new()
    }
}

impl Bars {
    /// Bars, and notes printed.
    pub fn new() -> Self {
        Self {
            bar: Mutex::new(None),
            notes: true,
            held: None,
        }
    }

    /// Bars, and the notes held back until [`Bars::release`]: an analysis prints `wrote DIR`
    /// (or its result) before its notes.
    pub fn holding() -> Self {
        Self {
            held: Some(Mutex::default()),
            ..Self::new()
        }
    }

    /// `wrote DIR` on stderr for the folder written (if any), then the held notes.
    pub fn release(&self, written: Option<&std::path::Path>) {
        if let Some(dir) = written {
            eprintln!("wrote {}", dir.display());
        }
        let held = self
            .held
            .as_ref()
            .map(|h| std::mem::take(&mut *h.lock().unwrap_or_else(PoisonError::into_inner)));
        for line in held.into_iter().flatten() {
            eprintln!("{line}");
        }
    }

    /// With `notes` false the notes are not printed (`--json`: stderr stays quiet but for the
    /// bars on a terminal).
    pub fn with_notes(self, notes: bool) -> Self {
        Self { notes, ..self }
    }

    fn current(&self) -> MutexGuard<'_, Option<indicatif::ProgressBar>> {
        self.bar.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Run `f` (which prints) with the current bar out of the way.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        let bar = self.current().clone();
        match bar {
            Some(b) => b.suspend(f),
            None => f(),
        }
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: Option<u64>) {
        let bar = match len {
            Some(n) => progress_bar(n, what),
            None => progress_counter(what),
        };
        if let Some(old) = self.current().replace(bar) {
            old.finish_and_clear();
        }
    }

    fn advance(&self, n: u64) {
        if let Some(b) = self.current().as_ref() {
            b.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.current().take() {
            b.finish_and_clear();
        }
    }

    fn note(&self, line: &str) {
        if let Some(held) = &self.held {
            held.lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push(line.to_string());
        } else if self.notes {
            self.suspend(|| eprintln!("{line}"));
        }
    }

    fn cancelled(&self) -> bool {
        crate::interrupt::interrupted()
    }
}
