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
}
