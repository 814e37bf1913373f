//! The command line's [`Progress`] sink: bars on stderr (only on a terminal), notes printed on
//! stderr as the command printed them before, and Ctrl-C (after [`crate::interrupt::catch`])
//! as the request to stop.

use std::sync::Mutex;

use sandjumper_output::Progress;

/// Progress bars and notes on stderr; cancelled once Ctrl-C has been caught.
#[derive(Default)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    /// No bar yet.
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
        if let Ok(mut b) = self.bar.lock()
            && let Some(old) = b.replace(bar)
        {
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
        if let Ok(mut b) = self.bar.lock()
            && let Some(bar) = b.take()
        {
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
