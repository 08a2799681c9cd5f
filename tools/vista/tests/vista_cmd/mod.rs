//! The `vista` binary as the command-line tests run it: error trees are
//! cached in one folder under the build folder (`VISTA_CACHE`), shared by
//! every test process, so a world's tree is computed once per build, not
//! once per test, and the user's own cache is left alone.

use std::path::Path;
use std::process::Command;

pub fn vista_cmd() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vista"));
    c.env("VISTA_CACHE", Path::new(env!("CARGO_TARGET_TMPDIR")).join("vista-cache"));
    c
}
