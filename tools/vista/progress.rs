//! The command line's progress: an indicatif bar on a terminal (the
//! library reports through a callback and draws none), plain lines every
//! few seconds otherwise.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal as _;
use std::sync::{Arc, Mutex};
use vista::world::{Progress, ProgressEvent};

/// A bar on a terminal, plain lines otherwise.
pub fn auto() -> Progress {
    if !std::io::stderr().is_terminal() {
        return Progress::Lines { every: Progress::LINE_INTERVAL };
    }
    // Made at the first event, when the total and the unit are known.
    let bar: Mutex<Option<ProgressBar>> = Mutex::new(None);
    Progress::Callback(Arc::new(move |e: ProgressEvent| {
        let mut bar = bar.lock().unwrap_or_else(|p| p.into_inner());
        let b = bar.get_or_insert_with(|| {
            let b = ProgressBar::new(e.total);
            let template = format!("{{bar:40}} {{pos}}/{{len}} {} {{per_sec}} eta {{eta}}", e.what.unit());
            if let Ok(style) = ProgressStyle::with_template(&template) {
                b.set_style(style);
            }
            b
        });
        b.set_position(e.done);
        if e.finished {
            b.finish();
        }
    }))
}
