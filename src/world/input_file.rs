//! Inputs must be regular files: opening a named pipe blocks until a writer
//! appears (a hang with no output), and a device or socket is never a
//! height map, scene or texture. Checked on the metadata, before any open.

use std::io;
use std::path::Path;

/// `Ok` for a regular file (symlinks followed); a missing file keeps its
/// `NotFound` error; anything else is `InvalidInput` saying what it is.
pub fn require_regular_file(path: &Path) -> io::Result<()> {
    let kind = std::fs::metadata(path)?.file_type();
    if kind.is_file() {
        return Ok(());
    }
    let what = if kind.is_dir() { "a folder" } else { special_kind(&kind) };
    Err(io::Error::new(io::ErrorKind::InvalidInput, format!("is {what}, not a regular file")))
}

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a named pipe (FIFO)"
    } else if kind.is_socket() {
        "a socket"
    } else if kind.is_block_device() || kind.is_char_device() {
        "a device"
    } else {
        "not a file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "not a file"
}

/// `rel` resolved against `base` (a scene's folder) and tidied lexically:
/// `scenes/../../data/map.png` prints as `../data/map.png`. No file system
/// access, so a missing file is still named as the user will look for it
/// (symlinks are not followed: `a/link/..` keeps its meaning only if `link`
/// is a folder, which is how every scene layout vista ships reads).
pub fn resolve_relative(base: &Path, rel: &Path) -> std::path::PathBuf {
    use std::path::Component;
    let joined = base.join(rel);
    let mut out: Vec<Component> = Vec::new();
    for c in joined.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            Component::ParentDir if matches!(out.last(), Some(Component::RootDir | Component::Prefix(_))) => {}
            other => out.push(other),
        }
    }
    if out.is_empty() {
        return ".".into();
    }
    out.iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_missing_files_are_told_apart() {
        let msg = |p: &str| require_regular_file(Path::new(p)).unwrap_err().to_string();
        assert!(msg("/dev/null").contains("a device"));
        assert!(msg("/").contains("a folder"));
        assert_eq!(require_regular_file(Path::new("/no/such/file")).unwrap_err().kind(), io::ErrorKind::NotFound);
        require_regular_file(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml").as_path()).unwrap();
    }

    #[test]
    fn relative_paths_are_tidied_without_touching_the_disk() {
        let r = |b: &str, p: &str| resolve_relative(Path::new(b), Path::new(p)).display().to_string();
        assert_eq!(r("scenes", "../../shared/data/m.png"), "../shared/data/m.png");
        assert_eq!(r("scenes", "./a/./b.png"), "scenes/a/b.png");
        assert_eq!(r("/x/scenes", "../../../m.png"), "/m.png");
        assert_eq!(r("scenes", "/abs/m.png"), "/abs/m.png");
        assert_eq!(r("", "m.png"), "m.png");
        assert_eq!(r("a", ".."), ".");
    }
}
