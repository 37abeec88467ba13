//! Progress on stderr, one type for every long command (run's noise ensembles, sweep, stress,
//! reproduce): a counter line `label: done/total unit, elapsed s, ETA s`, redrawn in place
//! and shown only when stderr is a terminal; for reproduce also a line per figure, always
//! shown (a log of the stages when stderr is a file).

use std::io::IsTerminal;
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

/// A progress report on stderr (see the module doc).
pub struct Progress {
    label: &'static str,
    unit: &'static str,
    started: Instant,
    count: Mutex<Count>,
    terminal: bool,
}

/// The current count (reproduce runs several, one after another).
struct Count {
    /// When it began: the ETA is the count's own rate.
    started: Instant,
    /// Whether a counter line is on the terminal, not yet ended by a newline.
    line_open: bool,
}

impl Progress {
    /// Counting `unit`s (e.g. "points") under `label` (e.g. "sweep"), from now.
    pub fn new(label: &'static str, unit: &'static str) -> Self {
        let now = Instant::now();
        let count = Mutex::new(Count { started: now, line_open: false });
        Self { label, unit, started: now, count, terminal: std::io::stderr().is_terminal() }
    }

    fn count(&self) -> MutexGuard<'_, Count> {
        // A worker that panicked while holding the lock left a valid Count.
        self.count.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// `done` of `total` finished: redraws the counter line; a finished count lets the next
    /// one's ETA start from here.
    pub fn update(&self, done: usize, total: usize) {
        let mut count = self.count();
        if self.terminal {
            let elapsed = self.started.elapsed().as_secs_f64();
            let eta = count.started.elapsed().as_secs_f64() / done.max(1) as f64
                * total.saturating_sub(done) as f64;
            eprint!(
                "\r\x1b[K{}: {done}/{total} {}, {elapsed:.0} s, ETA {eta:.0} s",
                self.label, self.unit
            );
            count.line_open = true;
        }
        if done >= total {
            count.started = Instant::now();
        }
    }

    /// Ends the counter line (it stays on the terminal); returns the seconds elapsed.
    pub fn finish(&self) -> f64 {
        let mut count = self.count();
        if count.line_open {
            eprintln!();
            count.line_open = false;
        }
        self.started.elapsed().as_secs_f64()
    }
}

impl crate::reproduce::Progress for Progress {
    /// A line per figure, replacing the counter line on a terminal; the next count starts here.
    fn stage(&self, index: usize, total: usize, what: &str) {
        let mut count = self.count();
        if count.line_open {
            eprint!("\r\x1b[K");
            count.line_open = false;
        }
        eprintln!(
            "{} [{index}/{total}] {:.0} s: {what}",
            self.label,
            self.started.elapsed().as_secs_f64()
        );
        count.started = Instant::now();
    }

    fn points(&self, done: usize, total: usize) {
        self.update(done, total);
    }
}
