//! Write faults injected at each step an output takes, so every error path
//! is walked on a disk that never fails: the output layer's twin of
//! [`crate::gpu::fault::FaultInjector`]. The steps are where real disks
//! fail: `write` on a full local disk, `fsync` where a network disk (NFS,
//! CephFS, EFS) or a quota reports the same only when the data is flushed,
//! and the `rename` that makes a file (or a set of files) visible.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicU8, Ordering::Relaxed};
use std::sync::Mutex;

/// Where an injected fault strikes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Step {
    /// A file's data: fails part-way with "no space left on device", after
    /// writing half of its first buffer (a partial temporary to clean up).
    Write = 0,
    /// A file's (or a folder's) fsync: "disk quota exceeded".
    Sync = 1,
    /// A rename that publishes a file: "input/output error".
    Rename = 2,
    /// A file's close after its fsync: "input/output error" (NFS reports
    /// a deferred write error here when the fsync did not flush it all).
    Close = 3,
}

impl Step {
    /// The errno a fault at this step reports.
    pub(super) fn errno(self) -> i32 {
        match self {
            Step::Write => 28,               // ENOSPC
            Step::Sync => 122,               // EDQUOT
            Step::Rename | Step::Close => 5, // EIO
        }
    }
}

const OFF: u64 = u64::MAX;

/// Counts the operations of the armed step; the armed one fails. Armed for
/// a folder, it counts only operations under that folder, so tests writing
/// elsewhere in the same process are not hit.
pub struct WriteFaults {
    ops: [AtomicU64; 4],
    fail_at: AtomicU64,
    step: AtomicU8,
    under: Mutex<Option<PathBuf>>,
}

static FAULTS: WriteFaults = WriteFaults {
    ops: [AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)],
    fail_at: AtomicU64::new(OFF),
    step: AtomicU8::new(0),
    under: Mutex::new(None),
};

/// The process's write-fault injector (disarmed unless armed).
pub fn faults() -> &'static WriteFaults {
    &FAULTS
}

impl WriteFaults {
    /// Files written so far (each temporary counts once).
    pub fn count(&self) -> u64 {
        self.ops[Step::Write as usize].load(Relaxed)
    }

    /// The `n`th operation of `step` from now (0: the next) fails; with
    /// `under`, only operations under that folder count.
    pub fn fail_in(&self, step: Step, under: Option<&Path>, n: u64) {
        *self.under.lock().unwrap_or_else(|p| p.into_inner()) = under.map(Path::to_path_buf);
        self.step.store(step as u8, Relaxed);
        self.fail_at.store(self.ops[step as usize].load(Relaxed) + n, Relaxed);
    }

    /// The file write `n` writes from now (0: the next) fails.
    pub fn fail_write_in(&self, n: u64) {
        self.fail_in(Step::Write, None, n);
    }

    /// The `n`th write from now under `dir` fails.
    pub fn fail_write_under_in(&self, dir: &Path, n: u64) {
        self.fail_in(Step::Write, Some(dir), n);
    }

    pub fn disarm(&self) {
        self.fail_at.store(OFF, Relaxed);
        *self.under.lock().unwrap_or_else(|p| p.into_inner()) = None;
    }

    /// Counts one `step` on `path`; true when it is the one to fail.
    pub(super) fn hit(&self, step: Step, path: &Path) -> bool {
        let counter = &self.ops[step as usize];
        if self.fail_at.load(Relaxed) == OFF || self.step.load(Relaxed) != step as u8 {
            counter.fetch_add(1, Relaxed);
            return false;
        }
        let under = self.under.lock().unwrap_or_else(|p| p.into_inner());
        if under.as_ref().is_some_and(|d| !path.starts_with(d)) {
            return false;
        }
        let n = counter.fetch_add(1, Relaxed);
        self.fail_at.compare_exchange(n, OFF, Relaxed, Relaxed).is_ok()
    }

    /// The error `step` reports when `hit` says it fails.
    pub(super) fn check(&self, step: Step, path: &Path) -> std::io::Result<()> {
        if self.hit(step, path) {
            return Err(std::io::Error::from_raw_os_error(step.errno()));
        }
        Ok(())
    }
}

/// Arms the injector from the environment (the command line's tests walk
/// every failure path of a real run): `VISTA_FAIL_WRITE=N`,
/// `VISTA_FAIL_SYNC=N`, `VISTA_FAIL_CLOSE=N` or `VISTA_FAIL_RENAME=N`, the
/// Nth (from 0) such operation of the process fails. Returns the step
/// armed, if any.
pub fn arm_from_env(var: &dyn Fn(&str) -> Option<String>) -> Option<Step> {
    let steps = [
        ("VISTA_FAIL_WRITE", Step::Write),
        ("VISTA_FAIL_SYNC", Step::Sync),
        ("VISTA_FAIL_CLOSE", Step::Close),
        ("VISTA_FAIL_RENAME", Step::Rename),
    ];
    for (name, step) in steps {
        if let Some(n) = var(name).and_then(|v| v.parse().ok()) {
            faults().fail_in(step, None, n);
            return Some(step);
        }
    }
    None
}
