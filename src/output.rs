//! Files vista writes appear whole or not at all. Each is written to a
//! temporary file in its own folder and renamed over its final name once
//! complete: a reader never sees half a file, a full disk leaves the previous
//! contents in place, and a failure removes the temporary. A [`FileSet`]
//! (a render's outputs) renames nothing until every member was written, and
//! creates its folder only then.
//!
//! Write faults can be injected ([`faults`]) so every error path is walked on
//! a disk that never fills: the output layer's twin of
//! [`crate::gpu::fault::FaultInjector`].
//!
//! The data is not fsynced: the rename makes a file visible whole, and a
//! full disk is reported by `write` itself on the file systems vista targets
//! (ext4, xfs and tmpfs reserve blocks at write time); durability across a
//! power cut is the caller's.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::Mutex;

/// A file could not be written; the message names it. The I/O error is
/// part of the message, not a `source()`, so error chains say it once.
#[derive(Debug, thiserror::Error)]
#[error("writing {}: {error}", path.display())]
pub struct OutputError {
    pub path: PathBuf,
    pub error: io::Error,
}

impl OutputError {
    fn new(path: &Path, error: io::Error) -> Self {
        OutputError { path: path.to_path_buf(), error }
    }
}

const OFF: u64 = u64::MAX;

/// Counts file writes; the armed one fails part-way with "no space left on
/// device", after writing half of its first buffer (so there is a partial
/// temporary to clean up).
/// Armed for a folder, it counts only writes under that folder, so tests
/// writing elsewhere in the same process are not hit.
pub struct WriteFaults {
    writes: AtomicU64,
    fail_at: AtomicU64,
    under: Mutex<Option<PathBuf>>,
}

static FAULTS: WriteFaults =
    WriteFaults { writes: AtomicU64::new(0), fail_at: AtomicU64::new(OFF), under: Mutex::new(None) };

/// The process's write-fault injector (disarmed unless armed).
pub fn faults() -> &'static WriteFaults {
    &FAULTS
}

impl WriteFaults {
    /// Files written so far (each temporary counts once).
    pub fn count(&self) -> u64 {
        self.writes.load(Relaxed)
    }

    /// The file write `n` writes from now (0: the next) fails.
    pub fn fail_write_in(&self, n: u64) {
        *self.under.lock().unwrap_or_else(|p| p.into_inner()) = None;
        self.fail_at.store(self.writes.load(Relaxed) + n, Relaxed);
    }

    /// The `n`th write from now under `dir` fails; writes elsewhere are
    /// neither counted nor failed until it is disarmed.
    pub fn fail_write_under_in(&self, dir: &Path, n: u64) {
        *self.under.lock().unwrap_or_else(|p| p.into_inner()) = Some(dir.to_path_buf());
        self.fail_at.store(self.writes.load(Relaxed) + n, Relaxed);
    }

    pub fn disarm(&self) {
        self.fail_at.store(OFF, Relaxed);
        *self.under.lock().unwrap_or_else(|p| p.into_inner()) = None;
    }

    fn hit(&self, path: &Path) -> bool {
        if self.fail_at.load(Relaxed) == OFF {
            self.writes.fetch_add(1, Relaxed);
            return false;
        }
        let under = self.under.lock().unwrap_or_else(|p| p.into_inner());
        if under.as_ref().is_some_and(|d| !path.starts_with(d)) {
            return false;
        }
        let n = self.writes.fetch_add(1, Relaxed);
        self.fail_at.compare_exchange(n, OFF, Relaxed, Relaxed).is_ok()
    }
}

/// A writer that fails like a full disk when armed.
pub struct OutputWriter {
    inner: BufWriter<File>,
    fail: bool,
}

impl Write for OutputWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.fail {
            self.inner.write_all(&buf[..buf.len() / 2])?;
            self.inner.flush()?;
            return Err(io::Error::from_raw_os_error(28)); // ENOSPC
        }
        self.inner.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

impl io::Seek for OutputWriter {
    fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
        self.inner.seek(pos)
    }
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// `.NAME.vista-tmp-PID-N` beside `path`: hidden, unique per process and
/// write, and recognisable by [`is_temporary`].
fn temporary_for(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
    let n = TEMP_COUNTER.fetch_add(1, Relaxed);
    path.with_file_name(format!(".{name}{TEMP_MARK}{}-{n}", std::process::id()))
}

const TEMP_MARK: &str = ".vista-tmp-";

/// Whether a file name is one of vista's temporaries (for tests and clean-up).
pub fn is_temporary(name: &str) -> bool {
    name.contains(TEMP_MARK)
}

/// Writes `path`'s temporary through `fill`; the temporary is removed on
/// any failure. The folder must exist.
fn write_temporary(
    path: &Path,
    fill: impl FnOnce(&mut OutputWriter) -> io::Result<()>,
) -> Result<PathBuf, OutputError> {
    let tmp = temporary_for(path);
    let result = File::create(&tmp).and_then(|file| {
        let mut w = OutputWriter { inner: BufWriter::new(file), fail: FAULTS.hit(path) };
        fill(&mut w)?;
        w.flush()?;
        w.inner.into_inner().map_err(|e| e.into_error())?;
        Ok(())
    });
    match result {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(OutputError::new(path, e))
        }
    }
}

fn rename(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    std::fs::rename(tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(tmp);
        OutputError::new(path, e)
    })
}

/// Writes `path` whole or not at all through `fill` (which may also seek).
pub fn write_with(path: &Path, fill: impl FnOnce(&mut OutputWriter) -> io::Result<()>) -> Result<(), OutputError> {
    let tmp = write_temporary(path, fill)?;
    rename(&tmp, path)
}

/// Writes `bytes` to `path` whole or not at all.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_with(path, |w| w.write_all(bytes))
}

/// Encodes a PNG into `w`.
pub fn encode_png(
    w: &mut OutputWriter,
    data: &[u8],
    size: [u32; 2],
    colour: image::ExtendedColorType,
) -> io::Result<()> {
    image::write_buffer_with_format(w, data, size[0], size[1], colour, image::ImageFormat::Png).map_err(|e| match e {
        image::ImageError::IoError(e) => e,
        other => io::Error::other(other),
    })
}

/// Writes a PNG to `path` whole or not at all.
pub fn write_png(
    path: &Path,
    data: &[u8],
    size: [u32; 2],
    colour: image::ExtendedColorType,
) -> Result<(), OutputError> {
    write_with(path, |w| encode_png(w, data, size, colour))
}

/// Files that appear together: each is written to a temporary as it is
/// added; [`FileSet::commit`] renames them all. Dropped uncommitted, the set
/// removes its temporaries and the folder if it created it.
pub struct FileSet {
    dir: PathBuf,
    created_dir: bool,
    staged: Vec<(PathBuf, PathBuf)>,
}

impl FileSet {
    /// A set of files in `dir`, which is created (with its parents) when the
    /// first file is added.
    pub fn new(dir: &Path) -> Self {
        FileSet { dir: dir.to_path_buf(), created_dir: false, staged: Vec::new() }
    }

    /// Writes `name`'s temporary through `fill`.
    pub fn add_with(
        &mut self,
        name: &str,
        fill: impl FnOnce(&mut OutputWriter) -> io::Result<()>,
    ) -> Result<(), OutputError> {
        if !self.dir.is_dir() {
            std::fs::create_dir_all(&self.dir).map_err(|e| OutputError::new(&self.dir, e))?;
            self.created_dir = true;
        }
        let path = self.dir.join(name);
        let tmp = write_temporary(&path, fill)?;
        self.staged.push((tmp, path));
        Ok(())
    }

    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        self.add_with(name, |w| w.write_all(bytes))
    }

    /// Renames every temporary over its final name.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let staged = std::mem::take(&mut self.staged);
        self.created_dir = false;
        let mut pending = staged.iter();
        for (tmp, path) in pending.by_ref() {
            if let Err(e) = rename(tmp, path) {
                for (tmp, _) in pending {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(e);
            }
        }
        Ok(())
    }
}

impl Drop for FileSet {
    fn drop(&mut self) {
        for (tmp, _) in &self.staged {
            let _ = std::fs::remove_file(tmp);
        }
        if self.created_dir {
            // Only if empty: the folder held nothing of the user's.
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("vista-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = match std::fs::read_dir(dir) {
            Ok(rd) => rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect(),
            Err(_) => Vec::new(),
        };
        v.sort();
        v
    }

    // The injector is process-wide: one test arms it, in sequence.
    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary_and_a_set_appears_whole() {
        let dir = scratch("atomic");
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.json");
        write(&file, b"old").unwrap();
        faults().fail_write_under_in(&dir, 0);
        let e = write(&file, &[7u8; 10_000]).unwrap_err();
        assert_eq!(e.error.raw_os_error(), Some(28));
        assert!(e.to_string().starts_with(&format!("writing {}: ", file.display())), "{e}");
        assert_eq!(std::fs::read(&file).unwrap(), b"old");
        assert_eq!(names(&dir), ["a.json"]);

        // A set whose third file fails: nothing appears, the folder it
        // created is gone again.
        let out = dir.join("new/out");
        for failing in 0..3 {
            let mut set = FileSet::new(&out);
            faults().fail_write_under_in(&dir, failing);
            let r = (|| {
                for n in ["x.json", "y.png", "z.exr"] {
                    set.add(n, b"data")?;
                }
                Ok::<_, OutputError>(())
            })();
            assert!(r.is_err());
            drop(set);
            assert!(!out.exists(), "failing at file {failing} left {:?}", names(&out));
        }
        faults().disarm();
        let mut set = FileSet::new(&out);
        set.add("x.json", b"1").unwrap();
        set.add("y.png", b"2").unwrap();
        assert_eq!(names(&out).iter().filter(|n| !is_temporary(n)).count(), 0, "nothing before commit");
        set.commit().unwrap();
        assert_eq!(names(&out), ["x.json", "y.png"]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
