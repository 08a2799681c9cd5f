//! A render's outputs as one set: all new or all old. Members are written
//! and fsynced to temporaries as they are added; [`FileSet::commit`] then
//! moves each old file aside, renames the new one in, fsyncs the folder
//! and only then deletes the old ones. Any failure on the way puts every
//! old file back and removes every new one: a reader sees the previous
//! render whole, and the error names the file that failed.
//!
//! Not covered: a crash (power cut, kill -9) in the middle of the commit's
//! renames. The set is then mixed, and the old files sit beside it as
//! `.NAME.vista-old-PID-N` (a swap by one rename would need
//! `renameat2(RENAME_EXCHANGE)`, which the standard library does not offer).
//! The commit is a few renames, microseconds against the render's seconds.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering::Relaxed;

use super::{rename_over, sync_dir, write_temporary, OutputError, OutputWriter, TEMP_COUNTER};

/// Files that appear together: each is written to a temporary as it is
/// added; [`FileSet::commit`] renames them all. Dropped uncommitted, the set
/// removes its temporaries and the folder if it created it.
pub struct FileSet {
    dir: PathBuf,
    created_dir: bool,
    staged: Vec<(PathBuf, PathBuf)>,
}

/// One member published by a commit in progress, and its predecessor.
struct Published {
    path: PathBuf,
    old: Option<PathBuf>,
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

    /// Publishes every member at once (module docs): on an error, the
    /// folder holds exactly what it held before.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let staged = std::mem::take(&mut self.staged);
        let mut done: Vec<Published> = Vec::with_capacity(staged.len());
        let mut failed = None;
        for (i, (tmp, path)) in staged.iter().enumerate() {
            match publish(tmp, path) {
                Ok(p) => done.push(p),
                Err(e) => {
                    failed = Some((i, e));
                    break;
                }
            }
        }
        let failed = match failed {
            None => sync_dir(&self.dir).err().map(|e| (staged.len(), e)),
            some => some,
        };
        if let Some((i, e)) = failed {
            for (tmp, _) in &staged[i..] {
                let _ = std::fs::remove_file(tmp);
            }
            roll_back(done);
            let _ = sync_dir(&self.dir);
            return Err(e);
        }
        self.created_dir = false;
        for p in done {
            if let Some(old) = p.old {
                let _ = std::fs::remove_file(old);
            }
        }
        Ok(())
    }
}

/// Moves `path`'s old file aside (if any) and renames `tmp` over it.
fn publish(tmp: &Path, path: &Path) -> Result<Published, OutputError> {
    let old = if path.exists() {
        let aside = old_name(path);
        rename_over(path, &aside).map_err(|e| OutputError::new(path, e))?;
        Some(aside)
    } else {
        None
    };
    if let Err(e) = rename_over(tmp, path) {
        if let Some(aside) = &old {
            let _ = std::fs::rename(aside, path);
        }
        return Err(OutputError::new(path, e));
    }
    Ok(Published { path: path.to_path_buf(), old })
}

/// Undoes published members, last first: old files back, new ones gone.
fn roll_back(done: Vec<Published>) {
    for p in done.into_iter().rev() {
        match p.old {
            Some(old) => {
                let _ = std::fs::rename(old, &p.path);
            }
            None => {
                let _ = std::fs::remove_file(&p.path);
            }
        }
    }
}

/// `.NAME.vista-old-PID-N` beside `path`, where its old file waits for the
/// commit to finish.
fn old_name(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
    let n = TEMP_COUNTER.fetch_add(1, Relaxed);
    path.with_file_name(format!(".{name}.vista-old-{}-{n}", std::process::id()))
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
