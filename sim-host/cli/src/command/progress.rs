//! The command line's [`Progress`]: indicatif bars on stderr (hidden off a terminal, as
//! [`super::progress_bar`] draws them) and notes printed on stderr.

use std::sync::Mutex;

use sandjumper_output::Progress;

/// Progress bars on stderr and notes as lines on stderr.
#[derive(Debug, Default)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    /// No stage started yet.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: Option<u64>) {
        let bar = match len {
            Some(n) => super::progress_bar(n, what),
            None => super::progress_counter(what),
        };
        if let Some(old) = self.bar.lock().map_or(None, |mut b| b.replace(bar)) {
            old.finish_and_clear();
        }
    }

    fn advance(&self, n: u64) {
        if let Ok(b) = self.bar.lock()
            && let Some(bar) = b.as_ref()
        {
            bar.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(bar) = self.bar.lock().map_or(None, |mut b| b.take()) {
            bar.finish_and_clear();
        }
    }

    fn note(&self, line: &str) {
        match self.bar.lock().ok().and_then(|b| b.clone()) {
            Some(bar) => bar.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    fn cancelled(&self) -> bool {
        crate::interrupt::interrupted()
    }
}
