//! Finds the Embree 4 that will be linked, generates bindings from *its* headers, and publishes
//! the library directory as `links` metadata (`DEP_EMBREE4_LIBDIR`) so dependents can add an
//! rpath.
//!
//! Lookup order: `EMBREE_DIR`, the project-local prefix made by `scripts/setup.sh`
//! (`.deps/embree4`), pkg-config (`embree4`), then the system paths.
//!
//! Headers and library must come from the same build configuration: `rtcore_config.h` records
//! options (instance arrays, instance levels) that change the size of `RTCHit`. Vendoring
//! headers is exactly the bug this crate exists to avoid (docs/embree.md).

use std::env;
use std::fs;
use std::path::{Path, PathBuf};

struct Embree {
    include_dir: PathBuf,
    lib_dir: Option<PathBuf>,
    origin: &'static str,
}

const HOW_TO_FIX: &str = "To fix: run `scripts/setup.sh` as root (Debian 12/13), \
or set EMBREE_DIR to an Embree 4 prefix containing include/embree4/rtcore.h and \
lib/libembree4.so, or build without Embree: `cargo build --no-default-features`.";

fn prefix(dir: &Path, origin: &'static str) -> Option<Embree> {
    let include_dir = dir.join("include");
    if !include_dir.join("embree4/rtcore.h").is_file() {
        return None;
    }
    let lib_dir = ["lib", "lib64", "lib/x86_64-linux-gnu"]
        .iter()
        .map(|l| dir.join(l))
        .find(|l| l.join("libembree4.so").exists())?;
    Some(Embree { include_dir, lib_dir: Some(lib_dir), origin })
}

fn find() -> Embree {
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        return prefix(&dir, "EMBREE_DIR").unwrap_or_else(|| {
            panic!(
                "EMBREE_DIR={} has no include/embree4/rtcore.h with lib/libembree4.so beside it. {HOW_TO_FIX}",
                dir.display()
            )
        });
    }
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let local = manifest.join("../.deps/embree4");
    let local = local.canonicalize().unwrap_or(local);
    println!("cargo:rerun-if-changed={}", local.join(".complete").display());
    if let Some(found) = prefix(&local, "project-local prefix (.deps/embree4)") {
        return found;
    }
    if let Ok(lib) = pkg_config::Config::new().atleast_version("4.0").cargo_metadata(false).probe("embree4") {
        if let Some(inc) = lib.include_paths.iter().find(|p| p.join("embree4/rtcore.h").is_file()) {
            return Embree {
                include_dir: inc.clone(),
                lib_dir: lib.link_paths.first().cloned(),
                origin: "pkg-config",
            };
        }
    }
    for sys in ["/usr", "/usr/local"] {
        if let Some(found) = prefix(Path::new(sys), "system paths") {
            return found;
        }
    }
    panic!("Embree 4 was not found (looked at EMBREE_DIR, .deps/embree4, pkg-config embree4, /usr, /usr/local). {HOW_TO_FIX}");
}

/// Reads `#define NAME value` from rtcore_config.h so a wrong major version fails with a clear
/// message before bindgen runs.
fn header_define(config: &str, name: &str) -> Option<u32> {
    config.lines().find_map(|line| {
        let mut words = line.split_whitespace();
        (words.next() == Some("#define") && words.next() == Some(name))
            .then(|| words.next()?.parse().ok())
            .flatten()
    })
}

fn main() {
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    let embree = find();
    let config_h = embree.include_dir.join("embree4/rtcore_config.h");
    println!("cargo:rerun-if-changed={}", config_h.display());
    let config = fs::read_to_string(&config_h)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}. {HOW_TO_FIX}", config_h.display()));
    match header_define(&config, "RTC_VERSION_MAJOR") {
        Some(4) => {}
        Some(major) => panic!(
            "{} is Embree {major}, dormant needs Embree 4 (found through {}). {HOW_TO_FIX}",
            config_h.display(),
            embree.origin
        ),
        None => panic!("{} has no RTC_VERSION_MAJOR. {HOW_TO_FIX}", config_h.display()),
    }

    // Build options that change struct layouts, as cfgs for the ABI tests.
    println!("cargo:rustc-check-cfg=cfg(embree_instance_array)");
    if config.lines().any(|l| l.split_whitespace().eq(["#define", "RTC_GEOMETRY_INSTANCE_ARRAY"])) {
        println!("cargo:rustc-cfg=embree_instance_array");
    }

    let bindings = bindgen::Builder::default()
        .header_contents("wrapper.h", "#include <embree4/rtcore.h>\n")
        .clang_arg(format!("-I{}", embree.include_dir.display()))
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC_.*")
        .default_enum_style(bindgen::EnumVariation::ModuleConsts)
        .prepend_enum_name(false)
        .derive_default(true)
        .derive_debug(true)
        .layout_tests(true)
        .generate()
        .unwrap_or_else(|e| {
            panic!(
                "bindgen failed on {}: {e} (is libclang-dev installed? scripts/setup.sh installs it)",
                embree.include_dir.display()
            )
        });
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("bindings.rs");
    bindings.write_to_file(&out).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));

    if let Some(dir) = &embree.lib_dir {
        println!("cargo:rustc-link-search=native={}", dir.display());
        // Metadata for dependents (DEP_EMBREE4_LIBDIR): they add an rpath for this directory.
        println!("cargo:LIBDIR={}", dir.display());
        // This crate's own tests need the rpath too.
        if !is_system_dir(dir) {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
        }
    }
    println!("cargo:INCLUDE={}", embree.include_dir.display());
    println!("cargo:rustc-link-lib=dylib=embree4");
    println!("cargo:rustc-env=EMBREE4_SYS_INCLUDE_DIR={}", embree.include_dir.display());
    println!("cargo:rustc-env=EMBREE4_SYS_ORIGIN={}", embree.origin);
}

fn is_system_dir(dir: &Path) -> bool {
    ["/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu"]
        .iter()
        .any(|s| dir == Path::new(s))
}
