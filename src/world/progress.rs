//! Progress of long work (a bake, the error tree) for whoever shows it:
//! a callback a tool turns into a bar, or a plain line on stderr every few
//! seconds (a log or a pipe shows no bar, and a silent bake of hours looks
//! hung). The library draws no bar itself.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What progress is reported after each unit of work: how many are done of
/// how many, of what; `finished` once the work ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProgressEvent {
    pub done: u64,
    pub total: u64,
    pub what: Work,
    pub finished: bool,
}

/// Called from the working threads, in any order.
pub type ProgressFn = Arc<dyn Fn(ProgressEvent) + Send + Sync>;

/// How [`super::bake_world`] and the error tree report progress.
#[derive(Clone)]
pub enum Progress {
    Hidden,
    /// A plain line on stderr at most every `every` (and none for work
    /// quicker than that).
    Lines {
        every: Duration,
    },
    /// Each event to the caller (a tool's progress bar).
    Callback(ProgressFn),
}

impl Progress {
    /// Interval of the plain lines.
    pub const LINE_INTERVAL: Duration = Duration::from_secs(5);

    pub fn is_hidden(&self) -> bool {
        matches!(self, Progress::Hidden)
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Progress::Hidden => f.write_str("Hidden"),
            Progress::Lines { every } => write!(f, "Lines {{ every: {every:?} }}"),
            Progress::Callback(_) => f.write_str("Callback"),
        }
    }
}

/// `true`: plain lines every [`Progress::LINE_INTERVAL`]; `false` hidden.
impl From<bool> for Progress {
    fn from(shown: bool) -> Self {
        if shown {
            Progress::Lines { every: Self::LINE_INTERVAL }
        } else {
            Progress::Hidden
        }
    }
}

/// What a [`Reporter`] counts, for its lines and bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// Nodes baked.
    Nodes,
    /// Frames rendered (`vista render --frames`).
    Frames,
    /// Roots of the error tree computed or read.
    ErrorRoots,
}

impl Work {
    pub fn verb(self) -> &'static str {
        match self {
            Work::Nodes => "baked",
            Work::Frames => "rendered",
            Work::ErrorRoots => "error tree:",
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            Work::Nodes => "nodes",
            Work::Frames => "frames",
            Work::ErrorRoots => "roots",
        }
    }
}

/// The reporter behind a [`Progress`], shared by the working threads.
pub struct Reporter {
    progress: Progress,
    total: u64,
    what: Work,
    done: AtomicU64,
    start: Instant,
    /// When the next plain line is due.
    next: Mutex<Duration>,
}

impl Reporter {
    pub fn new(progress: Progress, total: u64, what: Work) -> Self {
        let every = match &progress {
            Progress::Lines { every } => *every,
            _ => Duration::ZERO,
        };
        Reporter { progress, total, what, done: AtomicU64::new(0), start: Instant::now(), next: Mutex::new(every) }
    }

    pub fn inc(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        let (total, what) = (self.total, self.what);
        match &self.progress {
            Progress::Hidden => {}
            Progress::Callback(f) => f(ProgressEvent { done, total, what, finished: false }),
            Progress::Lines { every } => {
                let elapsed = self.start.elapsed();
                // Another thread printing now is enough: never wait for it.
                let Ok(mut next) = self.next.try_lock() else { return };
                if elapsed < *next {
                    return;
                }
                *next = elapsed + *every;
                let secs = elapsed.as_secs_f64().max(1e-9);
                let rate = done as f64 / secs;
                let eta = total.saturating_sub(done) as f64 / rate;
                let (verb, unit) = (what.verb(), what.unit());
                eprintln!(
                    "{verb} {done}/{total} {unit} ({:.1} %), {rate:.1} {unit}/s, eta {}",
                    100.0 * done as f64 / total.max(1) as f64,
                    super::plan::duration(eta)
                );
            }
        }
    }

    pub fn finish(&self) {
        if let Progress::Callback(f) = &self.progress {
            let done = self.done.load(Ordering::Relaxed);
            f(ProgressEvent { done, total: self.total, what: self.what, finished: true });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_callback_hears_every_unit_and_the_end() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let log = seen.clone();
        let progress = Progress::Callback(Arc::new(move |e| log.lock().unwrap().push((e.done, e.finished))));
        let r = Reporter::new(progress, 3, Work::Nodes);
        (0..3).for_each(|_| r.inc());
        r.finish();
        assert_eq!(*seen.lock().unwrap(), [(1, false), (2, false), (3, false), (3, true)]);
    }
}
