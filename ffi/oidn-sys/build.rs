//! Finds the Open Image Denoise 2.x library to link and publishes its directory as `links`
//! metadata (`DEP_OPENIMAGEDENOISE_LIBDIR`) so dependents can add an rpath.
//!
//! Lookup order: `OIDN_DIR`, the project-local prefix made by `scripts/setup.sh`
//! (`.deps/oidn`), pkg-config (`OpenImageDenoise`), then the system paths. The bindings are
//! hand-written (OIDN's C API passes only handles, scalars and strings), so no headers are
//! needed; the library must be major version 2 (`libOpenImageDenoise.so.2`).

use std::env;
use std::path::{Path, PathBuf};

const HOW_TO_FIX: &str = "To fix: run `scripts/setup.sh` as root (Debian 12/13; installs OIDN 2.5.1 \
into .deps/oidn), or set OIDN_DIR to an OIDN 2.x prefix containing lib/libOpenImageDenoise.so, \
or build without denoising: `cargo build --no-default-features --features embree`.";

/// The library directory under `dir` that holds an OIDN 2 library, if any.
fn lib_dir(dir: &Path) -> Option<PathBuf> {
    ["lib", "lib64", "lib/x86_64-linux-gnu"]
        .iter()
        .map(|l| dir.join(l))
        .find(|l| l.join("libOpenImageDenoise.so").exists() && l.join("libOpenImageDenoise.so.2").exists())
}

fn find() -> (PathBuf, &'static str) {
    if let Some(dir) = env::var_os("OIDN_DIR") {
        let dir = PathBuf::from(dir);
        let found = lib_dir(&dir).unwrap_or_else(|| {
            panic!(
                "OIDN_DIR={} has no lib/libOpenImageDenoise.so with libOpenImageDenoise.so.2 (OIDN 2.x). {HOW_TO_FIX}",
                dir.display()
            )
        });
        return (found, "OIDN_DIR");
    }
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let local = manifest.join("../../.deps/oidn");
    let local = local.canonicalize().unwrap_or(local);
    println!("cargo:rerun-if-changed={}", local.join(".complete").display());
    if let Some(found) = lib_dir(&local) {
        return (found, "project-local prefix (.deps/oidn)");
    }
    if let Ok(lib) =
        pkg_config::Config::new().range_version("2.0".."3.0").cargo_metadata(false).probe("OpenImageDenoise")
    {
        if let Some(dir) = lib.link_paths.iter().find(|p| p.join("libOpenImageDenoise.so.2").exists()) {
            return (dir.clone(), "pkg-config");
        }
    }
    for sys in ["/usr", "/usr/local"] {
        if let Some(found) = lib_dir(Path::new(sys)) {
            return (found, "system paths");
        }
    }
    panic!(
        "Intel Open Image Denoise 2 was not found (looked at OIDN_DIR, .deps/oidn, pkg-config \
         OpenImageDenoise, /usr, /usr/local). {HOW_TO_FIX}"
    );
}

fn is_system_dir(dir: &Path) -> bool {
    ["/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu"]
        .iter()
        .any(|s| dir == Path::new(s))
}

fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    let (dir, origin) = find();
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-lib=dylib=OpenImageDenoise");
    // Metadata for dependents (DEP_OPENIMAGEDENOISE_LIBDIR): they add an rpath for it.
    println!("cargo:LIBDIR={}", dir.display());
    // This crate's own tests need the rpath too.
    if !is_system_dir(&dir) {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }
    println!("cargo:rustc-env=OIDN_SYS_LIB_DIR={}", dir.display());
    println!("cargo:rustc-env=OIDN_SYS_ORIGIN={origin}");
}
