//! Minimised windows: no frame is rendered or presented while the window
//! manager has the window minimised (or its surface has no size), and a
//! scripted flight's `minimise` line minimises it on purpose, to test that
//! the way back (a swapchain that may be out of date, targets kept) works.

use std::time::{Duration, Instant};

/// Redraws skipped while minimised before a scripted minimise restores the
/// window: enough that the window manager's state is seen to hold.
const SCRIPTED_SKIPS: u32 = 10;
/// How long a scripted minimise waits for the window manager to act; with
/// none running (a bare X server) nothing ever minimises the window.
const WINDOW_MANAGER_WAIT: Duration = Duration::from_secs(10);
/// The request is repeated this often meanwhile: a window manager that
/// started after it was sent never saw it.
const ASK_AGAIN: Duration = Duration::from_secs(1);
/// The pause of a skipped redraw, so a minimised window does not spin a core.
pub const SKIPPED_REDRAW_PAUSE: Duration = Duration::from_millis(20);

/// A `minimise` line of the flight, asked for at `frame`.
pub struct ScriptedMinimise {
    pub frame: u32,
    first_asked: Instant,
    asked: Instant,
    skipped: u32,
}

/// What a scripted minimise asks of the window this redraw.
#[derive(Debug, PartialEq, Eq)]
pub enum Step {
    Hold,
    /// Not minimised yet: ask the window manager again.
    Ask,
    /// Minimised long enough: restore the window.
    Restore,
    /// The window manager never minimised the window.
    GaveUp,
}

impl ScriptedMinimise {
    pub fn new(frame: u32, now: Instant) -> Self {
        ScriptedMinimise { frame, first_asked: now, asked: now, skipped: 0 }
    }

    /// One redraw, with the window `minimised` or not.
    pub fn step(&mut self, minimised: bool, now: Instant) -> Step {
        if minimised {
            self.skipped += 1;
            return if self.skipped >= SCRIPTED_SKIPS { Step::Restore } else { Step::Hold };
        }
        if self.skipped > 0 {
            return Step::Hold;
        }
        if now.duration_since(self.first_asked) > WINDOW_MANAGER_WAIT {
            return Step::GaveUp;
        }
        if now.duration_since(self.asked) > ASK_AGAIN {
            self.asked = now;
            return Step::Ask;
        }
        Step::Hold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scripted_minimise_restores_after_its_skips_or_gives_up_without_a_window_manager() {
        let t0 = Instant::now();
        let mut m = ScriptedMinimise::new(5, t0);
        assert_eq!(m.step(false, t0), Step::Hold, "the window manager has not acted yet");
        let later = t0 + ASK_AGAIN + Duration::from_millis(1);
        assert_eq!(m.step(false, later), Step::Ask);
        assert_eq!(m.step(false, later), Step::Hold, "asked again once a second");
        for _ in 1..SCRIPTED_SKIPS {
            assert_eq!(m.step(true, t0), Step::Hold);
        }
        assert_eq!(m.step(true, t0), Step::Restore);
        let mut never = ScriptedMinimise::new(5, t0);
        assert_eq!(never.step(false, t0 + WINDOW_MANAGER_WAIT + Duration::from_millis(1)), Step::GaveUp);
    }
}
