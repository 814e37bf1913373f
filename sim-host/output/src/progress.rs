//! How a long library call reports how far it has got, says what a user should read, and
//! learns that its caller wants it to stop: the one sink the command line (progress bars on
//! stderr, Ctrl-C), the Python module (a callback, `KeyboardInterrupt`) and a Rust user's
//! own code hand to every `run`.
//!
//! A call never prints: what the command line printed on stderr while a run went on
//! (warnings, "resuming from ...") goes to [`Progress::note`].

/// The sink a `run(&request, progress)` reports to. Every method has a do-nothing default,
/// so a caller implements only what it shows. `Sync`: a call may report from worker threads.
pub trait Progress: Sync {
    /// A stage of `len` steps (`None`: not known in advance) called `what` ("runs",
    /// "pairs", "evaluations") begins; it replaces the stage before it.
    fn start(&self, what: &str, len: Option<u64>) {
        let _ = (what, len);
    }
    /// `n` more steps of the current stage are done.
    fn advance(&self, n: u64) {
        let _ = n;
    }
    /// The current stage is over.
    fn finish(&self) {}
    /// A line for the user while the run goes on (the command line prints it on stderr).
    fn note(&self, line: &str) {
        let _ = line;
    }
    /// Whether the caller asked the call to stop (Ctrl-C). A call checks it between steps
    /// and, where it can, ends as its own documented interrupted outcome or error.
    fn cancelled(&self) -> bool {
        false
    }
}

/// Where a note goes that has no call's [`Progress`] at hand (an output folder that names
/// the partial output a killed run left beside it): nowhere until a face sets it
/// ([`set_note_sink`]); the command line prints it on stderr.
static NOTE_SINK: std::sync::OnceLock<fn(&str)> = std::sync::OnceLock::new();

/// Send the process's notes (see [`note`]) to `sink`, once; later calls are ignored.
pub fn set_note_sink(sink: fn(&str)) {
    let _ = NOTE_SINK.set(sink);
}

/// A note for the user from code that has no [`Progress`] to hand: given to the sink
/// [`set_note_sink`] set, dropped if none was set.
pub fn note(line: &str) {
    if let Some(sink) = NOTE_SINK.get() {
        sink(line);
    }
}

/// Reports nothing and never asks to stop: for tests, examples and callers that only want
/// the outcome.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}

/// Whose fault a failed call is: the caller's input (the command line's exit status 2) or
/// the program and its environment (exit status 1). Every library error says which, so a
/// face maps it without reading its message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blame {
    /// The request, a file it names or its environment was not what the call allows.
    Input,
    /// The call failed after accepting its input (a bug, a full disk, a crashed child).
    Internal,
}

/// A library error that says whose fault it is (see [`Blame`]).
pub trait Blamed: std::error::Error {
    /// Whose fault the error is.
    fn blame(&self) -> Blame;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    struct Count(AtomicU64);
    impl Progress for Count {
        fn advance(&self, n: u64) {
            self.0.fetch_add(n, Ordering::Relaxed);
        }
    }

    #[test]
    fn a_sink_counts_only_what_it_implements_and_the_defaults_never_cancel() {
        let c = Count(AtomicU64::new(0));
        let p: &dyn Progress = &c;
        p.start("runs", Some(3));
        p.advance(2);
        p.advance(1);
        p.note("ignored");
        p.finish();
        assert_eq!(c.0.load(Ordering::Relaxed), 3);
        assert!(!p.cancelled());
        assert!(!Silent.cancelled());
    }
}
