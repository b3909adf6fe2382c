//! Adds an rpath for the library directories that `embree4-sys` and `oidn-sys` found (their
//! `links` metadata, `DEP_EMBREE4_LIBDIR` and `DEP_OPENIMAGEDENOISE_LIBDIR`), so the binary,
//! tests and benches run without `LD_LIBRARY_PATH` when Embree or Open Image Denoise live in a
//! non-system prefix such as `.deps/embree4` or `.deps/oidn`.

use std::path::Path;

fn main() {
    for (feature, libdir) in [
        ("CARGO_FEATURE_EMBREE", "DEP_EMBREE4_LIBDIR"),
        ("CARGO_FEATURE_OIDN", "DEP_OPENIMAGEDENOISE_LIBDIR"),
    ] {
        println!("cargo:rerun-if-env-changed={libdir}");
        if std::env::var_os(feature).is_some() {
            add_rpath(std::env::var_os(libdir));
        }
    }
}

fn add_rpath(dir: Option<std::ffi::OsString>) {
    let Some(dir) = dir else {
        return;
    };
    let dir = Path::new(&dir);
    let system =
        ["/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu"];
    if !system.iter().any(|s| dir == Path::new(s)) {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }
}
