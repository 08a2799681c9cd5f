//! Output paths checked before the work that fills them: a render or bake
//! that runs for minutes must not fail at the end on a path that was never
//! usable.

use std::path::Path;

use anyhow::Result;

/// A path the user gave is unusable: their input to fix (exit code 2).
fn refuse(message: String) -> Result<()> {
    Err(anyhow::Error::new(crate::InputError(message)))
}

/// Names that say "a file", given where vista wants a folder.
const FILE_EXTENSIONS: [&str; 9] = ["png", "exr", "jpg", "jpeg", "json", "tif", "tiff", "bmp", "toml"];

/// `path` (given as `option`) is a folder vista writes several files into:
/// it is created now, with its parents, and must be writable.
pub fn prepare_out_dir(path: &Path, option: &str, writes: &str) -> Result<()> {
    check_out_dir(path, option, writes)?;
    if let Err(e) = std::fs::create_dir_all(path) {
        return refuse(format!("{option} {}: cannot create the folder: {e}", path.display()));
    }
    Ok(())
}

/// As [`prepare_out_dir`], creating nothing: the folder, or the nearest
/// existing folder above it, must be writable. For outputs that appear
/// only once the work succeeded (`output::FileSet` creates the folder).
pub fn check_out_dir(path: &Path, option: &str, writes: &str) -> Result<()> {
    let shown = path.display();
    if !path.is_dir() {
        if let Some(file) = path.ancestors().find(|a| a.exists()).filter(|a| !a.is_dir()) {
            if file == path {
                return refuse(format!(
                    "{option} {shown} is a file; {option} takes a folder ({writes}): choose another {option}"
                ));
            }
            return refuse(format!(
                "{option} {shown}: {} is a file, not a folder: choose another {option}",
                file.display()
            ));
        }
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if let Some(ext) = ext.filter(|e| FILE_EXTENSIONS.contains(&e.as_str())) {
            return refuse(format!("{option} {shown} looks like a .{ext} file; {option} takes a folder ({writes})"));
        }
    }
    let existing = path.ancestors().find(|a| a.is_dir()).unwrap_or(Path::new("."));
    let existing = if existing.as_os_str().is_empty() { Path::new(".") } else { existing };
    writable(existing).or_else(|e| refuse(format!("{option} {shown} is not writable: {e}")))
}

/// Creating a file is the one test of writability that holds for every
/// user (root included) and file system.
fn writable(dir: &Path) -> std::io::Result<()> {
    let probe = dir.join(format!(".vista-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// `path` (given as `option`) is one file vista writes: not a folder, and
/// in a folder that exists.
pub fn check_out_file(path: &Path, option: &str) -> Result<()> {
    let shown = path.display();
    if path.is_dir() {
        return refuse(format!("{option} {shown} is a folder; {option} takes a file name"));
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        return refuse(format!("{option} {shown}: the folder {} does not exist", parent.display()));
    }
    writable(parent)
        .or_else(|e| refuse(format!("{option} {shown}: the folder {} is not writable: {e}", parent.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_in_the_way_and_file_names_are_refused() {
        let dir = std::env::temp_dir().join(format!("vista-out-path-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a");
        std::fs::write(&file, "x").unwrap();
        let msg = |r: Result<()>| format!("{:#}", r.unwrap_err());
        assert!(msg(prepare_out_dir(&file, "--out", "w")).contains("is a file"));
        assert!(msg(prepare_out_dir(&file.join("b"), "--out", "w")).contains("a is a file, not a folder"));
        assert!(msg(prepare_out_dir(&dir.join("shot.PNG"), "--out", "w")).contains(".png file"));
        assert!(!dir.join("shot.PNG").exists(), "nothing created for a refused path");
        check_out_dir(&dir.join("new/deep"), "--out", "w").unwrap();
        assert!(!dir.join("new").exists(), "checking creates nothing");
        prepare_out_dir(&dir.join("new/deep"), "--out", "w").unwrap();
        assert!(dir.join("new/deep").is_dir());
        assert!(msg(check_out_file(&dir, "--json")).contains("is a folder"));
        assert!(msg(check_out_file(&dir.join("none/t.json"), "--json")).contains("does not exist"));
        check_out_file(&dir.join("t.json"), "--json").unwrap();
        let _ = std::fs::remove_dir_all(&dir);
    }
}
