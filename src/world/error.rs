use std::path::PathBuf;

use super::layout::NodeId;

/// Everything that can go wrong in the world module on bad input. Each
/// variant names the file or parameter at fault so a one-line message is
/// enough for the user.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("invalid world description: {0}")]
    InvalidDesc(String),
    /// The scene's `[vegetation]` table or the generator's folder.
    #[error("vegetation: {0}")]
    Vegetation(String),
    /// A stamp's placement, or what it does to the world's heights.
    #[error("{0}")]
    InvalidStamp(String),
    #[error("file not found: {}", path.display())]
    FileNotFound { path: PathBuf },
    /// The I/O error is part of the message, not a `source`: a chain
    /// printer would otherwise say it twice.
    #[error("cannot {action} {}: {error}", path.display())]
    Io { path: PathBuf, action: &'static str, error: std::io::Error },
    #[error("cannot create the folder {}: {} is a file, not a folder", path.display(), file.display())]
    FileInTheWay { path: PathBuf, file: PathBuf },
    #[error("{}: corrupt or truncated file: {detail}", path.display())]
    Corrupt { path: PathBuf, detail: String },
    #[error("{}: expected {expected}, found {found}", path.display())]
    WrongPixelFormat { path: PathBuf, expected: &'static str, found: String },
    #[error("{}: image size {width}x{height} is zero or larger than {max}x{max}", path.display())]
    BadDimensions { path: PathBuf, width: u64, height: u64, max: u32 },
    #[error("{}: every sample holds the no-data value {value}: the map has no ground to draw", path.display())]
    AllNoData { path: PathBuf, value: f64 },
    #[error("{}: {count} heights are NaN or infinite", path.display())]
    NonFiniteHeights { path: PathBuf, count: usize },
    #[error("{}: {count} heights lie beyond +-{limit:e} m (heights must be metres)", path.display())]
    HugeHeights { path: PathBuf, count: usize, limit: f32 },
    #[error("node {0} is not a valid node of this world")]
    InvalidNode(NodeId),
    #[error("the {roots} root nodes alone exceed the slot budget of {budget}")]
    BudgetTooSmall { roots: usize, budget: usize },
    #[error("invalid residency configuration: {0}")]
    InvalidConfig(String),
    #[error("cache file {}: {detail}", path.display())]
    CacheMiss { path: PathBuf, detail: String },
    /// The world is over a limit of its plan; the message names the option.
    #[error(transparent)]
    Plan(#[from] super::plan::PlanError),
    /// A shard bake's folder already holds a bake it must not mix with.
    #[error("{0}")]
    ForeignBake(String),
    #[error("loader worker failed while producing node {0}")]
    LoaderFailed(NodeId),
    /// A root is always resident; without it nothing draws where it lies.
    #[error("root node {node} could not be loaded ({attempts} attempts); last error: {cause}")]
    RootUnavailable { node: NodeId, attempts: u32, cause: String },
}

pub type Result<T> = std::result::Result<T, WorldError>;

impl WorldError {
    /// Maps an I/O error while opening `path` to the specific "missing file"
    /// variant when that is what happened.
    pub(crate) fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        let path = path.into();
        if error.kind() == std::io::ErrorKind::NotFound {
            WorldError::FileNotFound { path }
        } else {
            WorldError::Io { path, action: "read", error }
        }
    }

    pub(crate) fn io_write(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        WorldError::Io { path: path.into(), action: "write", error }
    }

    /// `create_dir_all(path)` failed: names the file standing where a
    /// folder is needed ("File exists" alone does not say which).
    pub(crate) fn create_dir(path: &std::path::Path, error: std::io::Error) -> Self {
        match path.ancestors().find(|a| a.exists()) {
            Some(file) if !file.is_dir() => {
                WorldError::FileInTheWay { path: path.to_path_buf(), file: file.to_path_buf() }
            }
            _ => WorldError::Io { path: path.to_path_buf(), action: "create the folder", error },
        }
    }

    pub(crate) fn corrupt(path: impl Into<PathBuf>, detail: impl ToString) -> Self {
        WorldError::Corrupt { path: path.into(), detail: detail.to_string() }
    }
}

#[cfg(test)]
mod tests {
    use crate::world::{GridSource, NodeCache, WorldDesc};
    use std::sync::Arc;

    #[test]
    fn a_file_where_the_cache_folder_goes_is_named_once() {
        let dir = std::env::temp_dir().join(format!("vista-error-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("afile");
        std::fs::write(&file, "x").unwrap();
        let source = Arc::new(GridSource::new(1, 1, vec![0.0], [10.0, 10.0]));
        for target in [file.clone(), file.join("sub")] {
            let Err(e) = NodeCache::new(&target, WorldDesc::default(), source.clone(), Vec::new()) else {
                panic!("{target:?}: a cache under a file");
            };
            let text = e.to_string();
            let expected =
                format!("cannot create the folder {}: {} is a file, not a folder", target.display(), file.display());
            assert_eq!(text, expected);
            assert!(std::error::Error::source(&e).is_none(), "no OS error to print a second time");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
