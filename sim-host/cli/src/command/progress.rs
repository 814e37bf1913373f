//! The command line's [`Progress`]: a bar (or a counter) on stderr per stage, shown only on
//! a terminal, and notes printed on stderr as they come.

use std::sync::Mutex;

use sandjumper_output::Progress;

/// Progress bars on stderr ([`super::progress_bar`], [`super::progress_counter`]); notes
/// go to stderr with `eprintln!`.
#[derive(Default)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    fn take(&self) -> Option<indicatif::ProgressBar> {
        self.bar.lock().map(|mut b| b.take()).unwrap_or(None)
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: Option<u64>) {
        if let Some(b) = self.take() {
            b.finish_and_clear();
        }
        let bar = match len {
            Some(n) => super::progress_bar(n, what),
            None => super::progress_counter(what),
        };
        if let Ok(mut b) = self.bar.lock() {
            *b = Some(bar);
        }
    }

    fn advance(&self, n: u64) {
        if let Ok(b) = self.bar.lock()
            && let Some(b) = b.as_ref()
        {
            b.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.take() {
            b.finish_and_clear();
        }
    }

    fn note(&self, line: &str) {
        match self.bar.lock().ok().and_then(|b| b.clone()) {
            Some(b) => b.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }
}

impl Drop for Bars {
    fn drop(&mut self) {
        if let Some(b) = self.take() {
            b.finish_and_clear();
        }
    }
}
