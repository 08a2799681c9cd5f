//! Files vista writes appear whole or not at all, and are on the disk when
//! vista says they are. Each is written to a temporary file in its own
//! folder, fsynced, and renamed over its final name; then the folder is
//! fsynced, so the rename itself survives a power cut. A reader never sees
//! half a file; a full disk, a quota or a network disk's late error (NFS,
//! CephFS and EFS often report one only at `fsync`) leaves the previous
//! contents in place, removes the temporary and names the file. A
//! [`FileSet`] (a render's outputs) renames nothing until every member was
//! written and fsynced, and puts the old files back if a rename fails.
//!
//! A file's `close` is checked too (the standard library's drop ignores
//! what it says): the fsync before it reports a deferred write error on
//! most disks, but NFS may still report one at `close`.
//!
//! Faults can be injected at each step ([`faults`]).

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

mod faults;
mod file_set;

pub use faults::{arm_from_env, faults, Step, WriteFaults};
pub use file_set::FileSet;

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
            return Err(io::Error::from_raw_os_error(Step::Write.errno()));
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

/// Whether a file name is one of vista's temporaries (for tests and
/// clean-up), or an old file a crashed [`FileSet::commit`] left aside.
pub fn is_temporary(name: &str) -> bool {
    name.contains(TEMP_MARK) || name.contains(".vista-old-")
}

/// Writes and fsyncs `path`'s temporary through `fill`; the temporary is
/// removed on any failure. The folder must exist.
fn write_temporary(
    path: &Path,
    fill: impl FnOnce(&mut OutputWriter) -> io::Result<()>,
) -> Result<PathBuf, OutputError> {
    let tmp = temporary_for(path);
    let result = File::create(&tmp).and_then(|file| {
        let mut w = OutputWriter { inner: BufWriter::new(file), fail: faults().hit(Step::Write, path) };
        fill(&mut w)?;
        w.flush()?;
        let file = w.inner.into_inner().map_err(|e| e.into_error())?;
        faults().check(Step::Sync, path)?;
        file.sync_all()?;
        close(file, path)
    });
    match result {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(OutputError::new(path, e))
        }
    }
}

/// Closes `file` and says what `close` reported. On Linux the descriptor
/// is gone even when close reports EINTR, which carries no data error.
fn close(file: File, path: &Path) -> io::Result<()> {
    faults().check(Step::Close, path)?;
    #[cfg(unix)]
    {
        use std::os::fd::IntoRawFd;
        let fd = file.into_raw_fd();
        // SAFETY: `fd` was just released by its only owner: it is open, and
        // nothing else closes it.
        if unsafe { libc::close(fd) } != 0 {
            let e = io::Error::last_os_error();
            return if e.raw_os_error() == Some(libc::EINTR) { Ok(()) } else { Err(e) };
        }
    }
    #[cfg(not(unix))]
    drop(file);
    Ok(())
}

/// Renames `from` over `to`; `to` names the file in the error.
fn rename_over(from: &Path, to: &Path) -> io::Result<()> {
    faults().check(Step::Rename, to)?;
    std::fs::rename(from, to)
}

fn rename(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    rename_over(tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(tmp);
        OutputError::new(path, e)
    })
}

/// Fsyncs a folder, so the renames in it are durable. A file system that
/// cannot fsync a folder (EINVAL: some FUSE and network mounts) makes each
/// rename durable itself: nothing more can be asked of it.
fn sync_dir(dir: &Path) -> Result<(), OutputError> {
    let synced = faults().check(Step::Sync, dir).and_then(|()| File::open(dir)?.sync_all());
    match synced {
        Err(e) if e.raw_os_error() == Some(22) => Ok(()),
        other => other.map_err(|e| OutputError::new(dir, e)),
    }
}

/// The folder a file is in (`.` for a bare name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes `path` whole or not at all through `fill` (which may also seek).
pub fn write_with(path: &Path, fill: impl FnOnce(&mut OutputWriter) -> io::Result<()>) -> Result<(), OutputError> {
    let tmp = write_temporary(path, fill)?;
    rename(&tmp, path)?;
    sync_dir(parent_of(path))
}

/// Writes `bytes` to `path` whole only if no file is there: the claim of a
/// folder that several processes may race for (a hard link fails when the
/// name exists, atomically, where a check then a write would not). Returns
/// false, writing nothing, when `path` exists.
pub fn write_new(path: &Path, bytes: &[u8]) -> Result<bool, OutputError> {
    let tmp = write_temporary(path, |w| w.write_all(bytes))?;
    let linked = faults().check(Step::Rename, path).and_then(|()| std::fs::hard_link(&tmp, path));
    let _ = std::fs::remove_file(&tmp);
    match linked {
        Ok(()) => sync_dir(parent_of(path)).map(|()| true),
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(OutputError::new(path, e)),
    }
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

        // A quota that only fsync reports, at each file and at the folder,
        // a network disk's error at each file's close, and a rename
        // failing at each member: the old set stays whole.
        for (step, ops) in [(Step::Sync, 4), (Step::Close, 3), (Step::Rename, 5)] {
            for k in 0..ops {
                faults().fail_in(step, Some(&dir), k);
                let mut set = FileSet::new(&out);
                let r = set.add("x.json", b"new x").and_then(|()| set.add("z.exr", b"new z"));
                let r = r.and_then(|()| set.add("y.png", b"new y")).and_then(|()| set.commit());
                let e = r.expect_err(&format!("{step:?} {k}"));
                assert_eq!(e.error.raw_os_error(), Some(step.errno()), "{step:?} {k}: {e}");
                assert_eq!(names(&out), ["x.json", "y.png"], "{step:?} {k}");
                assert_eq!(std::fs::read(out.join("x.json")).unwrap(), b"1", "{step:?} {k}");
                assert_eq!(std::fs::read(out.join("y.png")).unwrap(), b"2", "{step:?} {k}");
            }
        }
        faults().disarm();
        let _ = std::fs::remove_dir_all(&dir);
    }
}
