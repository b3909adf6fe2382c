//! Helpers shared by the integration tests; a test file uses them with `mod common;`.

use std::path::{Path, PathBuf};

/// The shared real assets (`../shared/assets`: monastery, duck, teddy, soccer ball, jenga
/// block), or `None` with a note when this checkout does not have them. CI has them; users'
/// checkouts do not, so tests that need them skip.
pub fn shared_assets() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets");
    if dir.join("monastery.glb").is_file() && dir.join("duck.glb").is_file() {
        Some(dir)
    } else {
        eprintln!("skipped: {} is absent", dir.display());
        None
    }
}
