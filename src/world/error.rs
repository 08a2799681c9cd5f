use std::path::PathBuf;

use super::layout::NodeId;

/// Everything that can go wrong in the world module on bad input. Each
/// variant names the file or parameter at fault so a one-line message is
/// enough for the user.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("invalid world description: {0}")]
    InvalidDesc(String),
    #[error("file not found: {}", path.display())]
    FileNotFound { path: PathBuf },
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: corrupt or truncated file: {detail}", path.display())]
    Corrupt { path: PathBuf, detail: String },
    #[error("{}: expected {expected}, found {found}", path.display())]
    WrongPixelFormat { path: PathBuf, expected: &'static str, found: String },
    #[error("{}: image size {width}x{height} is zero or larger than {max}x{max}", path.display())]
    BadDimensions { path: PathBuf, width: u64, height: u64, max: u32 },
    #[error("{}: {count} heights are NaN or infinite", path.display())]
    NonFiniteHeights { path: PathBuf, count: usize },
    #[error("node {0} is not a valid node of this world")]
    InvalidNode(NodeId),
    #[error("the {roots} root nodes alone exceed the slot budget of {budget}")]
    BudgetTooSmall { roots: usize, budget: usize },
    #[error("invalid residency configuration: {0}")]
    InvalidConfig(String),
    #[error("cache file {}: {detail}", path.display())]
    CacheMiss { path: PathBuf, detail: String },
    #[error("loader worker failed while producing node {0}")]
    LoaderFailed(NodeId),
}

pub type Result<T> = std::result::Result<T, WorldError>;

impl WorldError {
    /// Maps an I/O error while opening `path` to the specific "missing file"
    /// variant when that is what happened.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        let path = path.into();
        if source.kind() == std::io::ErrorKind::NotFound {
            WorldError::FileNotFound { path }
        } else {
            WorldError::Io { path, source }
        }
    }

    pub(crate) fn corrupt(path: impl Into<PathBuf>, detail: impl ToString) -> Self {
        WorldError::Corrupt { path: path.into(), detail: detail.to_string() }
    }
}
