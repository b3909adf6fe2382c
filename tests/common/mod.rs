//! Helpers and fixtures shared by the integration tests; a test module uses them with
//! `use crate::common;`. Some serve only tests compiled with a feature (Embree, OIDN), so a
//! build without it leaves them unused (hence the `allow`).
//!
//! - [`animated`]: a small animated glTF (a rigid-body bake) built by hand;
//! - [`cli`]: the `dormant` binary, running it, reading what it writes;
//! - [`scenes`]: the scene fixtures (shipped scenes, `tests/data/`, [`scenes::BOXES`]);
//! - [`scene_errors`]: parsing scene text and expecting an error that names file, field, line;
//! - [`render`]: rendering a scene description in process;
//! - [`images`]: reading rendered images and comparing them;
//! - [`encoding`]: base64 and the trajectory checksum (also used by `tests/fuzz_harness`).

#![allow(dead_code)]

pub mod animated;
pub mod cli;
pub mod encoding;
pub mod images;
pub mod render;
pub mod scene_errors;
pub mod scenes;

use std::path::{Path, PathBuf};

/// `path` (relative to the repository root) under the repository root.
pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The shared real assets (`../shared/assets`: monastery, duck, teddy, soccer ball, jenga
/// block), or `None` with a note when this checkout does not have them. CI has them; users'
/// checkouts do not, so tests that need them skip.
pub fn shared_assets() -> Option<PathBuf> {
    let dir = repo("../shared/assets");
    if dir.join("monastery.glb").is_file() && dir.join("duck.glb").is_file() {
        Some(dir)
    } else {
        eprintln!("skipped: {} is absent", dir.display());
        None
    }
}
