//! Progress of a bake on stderr: a bar on a terminal, a plain line every
//! few seconds otherwise (a log or a pipe shows no bar, and a silent bake of
//! hours looks hung).

use std::io::IsTerminal as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// How [`super::bake_world`] reports progress on stderr.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    Hidden,
    /// An indicatif bar, for a terminal.
    Bar,
    /// A plain line at most every `every` (and none for a bake quicker than
    /// that), for logs and pipes where a bar would be noise or invisible.
    Lines {
        every: Duration,
    },
}

impl Progress {
    /// Interval of the plain lines when stderr is not a terminal.
    pub const LINE_INTERVAL: Duration = Duration::from_secs(5);

    /// A bar on a terminal, plain lines otherwise.
    pub fn auto() -> Self {
        if std::io::stderr().is_terminal() {
            Progress::Bar
        } else {
            Progress::Lines { every: Self::LINE_INTERVAL }
        }
    }
}

/// `true` is [`Progress::auto`], `false` hidden.
impl From<bool> for Progress {
    fn from(shown: bool) -> Self {
        if shown {
            Progress::auto()
        } else {
            Progress::Hidden
        }
    }
}

/// The reporter behind [`Progress`], shared by the bake threads.
pub enum Reporter {
    Bar(ProgressBar),
    Lines { total: u64, done: AtomicU64, start: Instant, every: Duration, next: Mutex<Duration>, what: Work },
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
    fn verb(self) -> &'static str {
        match self {
            Work::Nodes => "baked",
            Work::Frames => "rendered",
            Work::ErrorRoots => "error tree:",
        }
    }

    fn unit(self) -> &'static str {
        match self {
            Work::Nodes => "nodes",
            Work::Frames => "frames",
            Work::ErrorRoots => "roots",
        }
    }
}

impl Reporter {
    pub fn new(progress: Progress, total: u64, what: Work) -> Self {
        match progress {
            Progress::Hidden => Reporter::Bar(ProgressBar::hidden()),
            Progress::Bar => {
                let bar = ProgressBar::new(total);
                let template = format!("{{bar:40}} {{pos}}/{{len}} {} {{per_sec}} eta {{eta}}", what.unit());
                if let Ok(style) = ProgressStyle::with_template(&template) {
                    bar.set_style(style);
                }
                Reporter::Bar(bar)
            }
            Progress::Lines { every } => Reporter::Lines {
                total,
                done: AtomicU64::new(0),
                start: Instant::now(),
                every,
                next: Mutex::new(every),
                what,
            },
        }
    }

    pub fn inc(&self) {
        match self {
            Reporter::Bar(bar) => bar.inc(1),
            Reporter::Lines { total, done, start, every, next, what } => {
                let done = done.fetch_add(1, Ordering::Relaxed) + 1;
                let elapsed = start.elapsed();
                // Another thread printing now is enough: never wait for it.
                let Ok(mut next) = next.try_lock() else { return };
                if elapsed < *next {
                    return;
                }
                *next = elapsed + *every;
                let secs = elapsed.as_secs_f64().max(1e-9);
                let rate = done as f64 / secs;
                let eta = (total - done) as f64 / rate;
                let (verb, unit) = (what.verb(), what.unit());
                eprintln!(
                    "{verb} {done}/{total} {unit} ({:.1} %), {rate:.1} {unit}/s, eta {}",
                    100.0 * done as f64 / (*total).max(1) as f64,
                    super::plan::duration(eta)
                );
            }
        }
    }

    pub fn finish(&self) {
        if let Reporter::Bar(bar) = self {
            bar.finish();
        }
    }
}
