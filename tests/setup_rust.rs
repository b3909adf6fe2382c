//! `scripts/setup.sh --rust` on a machine without a new enough Rust: it tries to install the
//! workspace's `rust-version` with rustup and, where it cannot, stops with one line naming
//! what to install. The installer's address points nowhere here, so no test downloads.

use std::path::Path;
use std::process::{Command, Output};

/// The workspace's `rust-version` from Cargo.toml.
fn required_rust() -> String {
    let manifest = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml")).unwrap();
    let line = manifest.lines().find(|l| l.starts_with("rust-version")).expect("rust-version in Cargo.toml");
    line.split('"').nth(1).unwrap().to_string()
}

/// Runs `setup.sh --rust` with only `path_dirs` and the system folders on PATH, a fresh HOME
/// (no ~/.cargo) and rustup's installer at an address that does not exist.
fn setup_rust(home: &Path, path_dirs: &[&Path]) -> Output {
    let mut path: Vec<String> = path_dirs.iter().map(|p| p.display().to_string()).collect();
    path.extend(["/usr/sbin", "/usr/bin", "/sbin", "/bin"].map(String::from));
    Command::new("bash")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/setup.sh"))
        .arg("--rust")
        .env_clear()
        .env("PATH", path.join(":"))
        .env("HOME", home)
        .env("RUSTUP_INIT_URL", "file:///nonexistent/rustup-init.sh")
        .output()
        .unwrap()
}

/// A folder holding a `rustc` that reports `version` and a `cargo` that does nothing.
fn fake_rust(dir: &Path, version: &str) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::create_dir_all(dir).unwrap();
    let scripts = [("rustc", format!("echo 'rustc {version} (fake)'")), ("cargo", "exit 0".to_string())];
    for (name, body) in scripts {
        let file = dir.join(name);
        std::fs::write(&file, format!("#!/bin/sh\n{body}\n")).unwrap();
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

fn stderr_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr).lines().map(String::from).collect()
}

#[test]
fn no_cargo_on_path_stops_with_one_line_naming_the_rust_to_install() {
    let home = tempfile::tempdir().unwrap();
    let out = setup_rust(home.path(), &[]);
    let want = required_rust();
    assert!(!out.status.success(), "setup.sh --rust succeeded without a way to install Rust");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains(&format!("installing rustup and Rust {want}")), "{stdout}");
    assert!(stdout.contains("found no rustc"), "{stdout}");
    let lines = stderr_lines(&out);
    assert_eq!(lines.len(), 1, "one line: {lines:?}");
    assert!(
        lines[0].starts_with("setup: error:") && lines[0].contains(&format!("install Rust {want} or newer")),
        "{lines:?}"
    );
    assert!(lines[0].contains("https://rustup.rs"), "{lines:?}");
}

#[test]
fn a_rust_older_than_the_workspace_needs_is_replaced_not_used() {
    let home = tempfile::tempdir().unwrap();
    let old = home.path().join("old-rust");
    fake_rust(&old, "1.63.0");
    let out = setup_rust(home.path(), &[&old]);
    assert!(!out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("(found 1.63.0)"), "{stdout}");
    assert_eq!(stderr_lines(&out).len(), 1, "{:?}", stderr_lines(&out));
}

#[test]
fn a_new_enough_rust_is_kept() {
    let home = tempfile::tempdir().unwrap();
    let new = home.path().join("new-rust");
    fake_rust(&new, "9.99.0");
    let out = setup_rust(home.path(), &[&new]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        stdout.contains(&format!("Rust 9.99.0 present (the workspace needs {} or newer)", required_rust())),
        "{stdout}"
    );
}
