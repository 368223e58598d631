//! The `.rs` files below a folder, for the tests that read source code
//! (`tests/architecture.rs`, `tests/host/architecture.rs`).

use std::path::{Path, PathBuf};

/// Appends every `.rs` file below `dir` to `out`.
pub fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rs_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}
