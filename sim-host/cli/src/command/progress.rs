//! The command line's [`Progress`]: indicatif bars on stderr (on a terminal only) and notes
//! printed on stderr.

use std::sync::Mutex;

use sandjumper_output::Progress;

/// Progress bars on stderr, one stage at a time; notes as lines on stderr.
#[derive(Default)]
pub struct Bars {
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    fn with(&self, f: impl FnOnce(&mut Option<indicatif::ProgressBar>)) {
        if let Ok(mut bar) = self.bar.lock() {
            f(&mut bar);
        }
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: Option<u64>) {
        self.with(|bar| {
            if let Some(old) = bar.take() {
                old.finish_and_clear();
            }
            *bar = Some(match len {
                Some(n) => super::progress_bar(n, what),
                None => super::progress_counter(what),
            });
        });
    }

    fn advance(&self, n: u64) {
        self.with(|bar| {
            if let Some(b) = bar {
                b.inc(n);
            }
        });
    }

    fn finish(&self) {
        self.with(|bar| {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
        });
    }

    fn note(&self, line: &str) {
        self.with(|bar| match bar {
            Some(b) => b.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        });
    }
}
