//! The command line's [`Progress`] sink: a library call's stages drawn as progress bars on
//! stderr (only on a terminal, as [`progress_bar`] draws them), its notes printed there.

use std::sync::Mutex;

use sandjumper_output::Progress;

use super::{progress_bar, progress_counter};

/// Progress bars and notes on stderr.
#[derive(Debug)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
    notes: bool,
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
        }
    }

    /// With `notes` false the notes are not printed (`--json`: stderr stays quiet but for
    /// the bars on a terminal).
    pub fn with_notes(self, notes: bool) -> Self {
        Self { notes, ..self }
    }

    fn current(&self) -> std::sync::MutexGuard<'_, Option<indicatif::ProgressBar>> {
        self.bar
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
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
        if self.notes {
            eprintln!("{line}");
        }
    }
}
