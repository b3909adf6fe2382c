//! Adds an rpath for the Embree library directory that `embree4-sys` found (its `links`
//! metadata, `DEP_EMBREE4_LIBDIR`), so the binary, tests and benches run without
//! `LD_LIBRARY_PATH` when Embree lives in a non-system prefix such as `.deps/embree4`.

use std::path::Path;

fn main() {
    println!("cargo:rerun-if-env-changed=DEP_EMBREE4_LIBDIR");
    if std::env::var_os("CARGO_FEATURE_EMBREE").is_none() {
        return;
    }
    let Some(dir) = std::env::var_os("DEP_EMBREE4_LIBDIR") else {
        return;
    };
    let dir = Path::new(&dir);
    let system =
        ["/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu"];
    if !system.iter().any(|s| dir == Path::new(s)) {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }
}
