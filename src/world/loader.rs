//! Background node loading on a few worker threads. The caller never
//! blocks: it queues requests and polls for finished payloads.

use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use super::error::{Result, WorldError};
use super::layout::NodeId;
use super::payload::BakedNode;

/// Produces a node's payload: usually a cache read or a bake.
pub type LoadFn = dyn Fn(NodeId) -> Result<BakedNode> + Send + Sync;

/// A finished load, as `poll` reports it.
type Loaded = (NodeId, Result<BakedNode>);

/// A pool of loader threads fed through a FIFO queue.
pub struct Loader {
    jobs: Option<Sender<NodeId>>,
    results: Receiver<Loaded>,
    /// A result [`Self::wait`] received, for the next poll.
    early: Mutex<Vec<Loaded>>,
    /// Without workers: `request` loads at once, on the caller's thread.
    inline: Option<(Arc<LoadFn>, Sender<Loaded>)>,
    cancelled: Arc<Mutex<HashSet<NodeId>>>,
    shutdown: Arc<AtomicBool>,
    workers: Vec<JoinHandle<()>>,
}

impl Loader {
    /// `workers` threads running `load`; with 0, every request is loaded
    /// at once on the caller's thread (slower frames, but the same arrivals
    /// in the same frames on every run: golden images).
    /// Fails only if the OS refuses to start a thread.
    pub fn new(workers: usize, load: Arc<LoadFn>) -> Result<Self> {
        let (job_tx, job_rx) = channel::<NodeId>();
        let (res_tx, res_rx) = channel();
        let job_rx = Arc::new(Mutex::new(job_rx));
        let cancelled = Arc::new(Mutex::new(HashSet::new()));
        let shutdown = Arc::new(AtomicBool::new(false));
        let mut loader = Loader {
            jobs: Some(job_tx),
            results: res_rx,
            early: Mutex::new(Vec::new()),
            inline: (workers == 0).then(|| (Arc::clone(&load), res_tx.clone())),
            cancelled: Arc::clone(&cancelled),
            shutdown: Arc::clone(&shutdown),
            workers: Vec::new(),
        };
        for i in 0..workers {
            let ctx = WorkerCtx {
                jobs: Arc::clone(&job_rx),
                results: res_tx.clone(),
                load: Arc::clone(&load),
                cancelled: Arc::clone(&cancelled),
                shutdown: Arc::clone(&shutdown),
            };
            let not_started =
                |error| WorldError::Io { path: format!("loader thread {i}").into(), action: "start", error };
            let handle = std::thread::Builder::new()
                .name(format!("vista-loader-{i}"))
                .spawn(move || ctx.run())
                .map_err(not_started)?;
            loader.workers.push(handle);
        }
        Ok(loader)
    }

    /// Queues a load; never blocks.
    pub fn request(&self, id: NodeId) {
        if let Some((load, results)) = &self.inline {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load(id)))
                .unwrap_or(Err(WorldError::LoaderFailed(id)));
            let _ = results.send((id, result));
            return;
        }
        lock(&self.cancelled).remove(&id);
        if let Some(jobs) = &self.jobs {
            // Send only fails once every worker is gone, which poll reports.
            let _ = jobs.send(id);
        }
    }

    /// Asks workers to skip a queued load that is no longer wanted. A load
    /// already running still completes and is reported.
    pub fn cancel(&self, id: NodeId) {
        lock(&self.cancelled).insert(id);
    }

    /// Everything finished since the last poll; never blocks.
    pub fn poll(&self) -> Vec<(NodeId, Result<BakedNode>)> {
        let mut out = std::mem::take(&mut *lock(&self.early));
        out.extend(self.results.try_iter());
        out
    }

    /// Blocks until a load finishes (kept for the next [`Self::poll`]) or
    /// `timeout` passes; whether one did.
    pub fn wait(&self, timeout: std::time::Duration) -> bool {
        if !lock(&self.early).is_empty() {
            return true;
        }
        match self.results.recv_timeout(timeout) {
            Ok(loaded) => {
                lock(&self.early).push(loaded);
                true
            }
            Err(_) => false,
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panicking load function poisons nothing we rely on: the set stays
    // consistent, so recover the guard.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

struct WorkerCtx {
    jobs: Arc<Mutex<Receiver<NodeId>>>,
    results: Sender<(NodeId, Result<BakedNode>)>,
    load: Arc<LoadFn>,
    cancelled: Arc<Mutex<HashSet<NodeId>>>,
    shutdown: Arc<AtomicBool>,
}

impl WorkerCtx {
    fn run(self) {
        loop {
            let Ok(id) = lock(&self.jobs).recv() else {
                return;
            };
            if self.shutdown.load(Ordering::Relaxed) {
                return;
            }
            if lock(&self.cancelled).remove(&id) {
                continue;
            }
            // A panicking load must not take the worker down with it.
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (self.load)(id)))
                .unwrap_or(Err(WorldError::LoaderFailed(id)));
            if self.results.send((id, result)).is_err() {
                return;
            }
        }
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        // Queued jobs are skipped; running ones finish, then workers exit.
        self.shutdown.store(true, Ordering::Relaxed);
        self.jobs = None;
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}
