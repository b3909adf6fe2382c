#!/usr/bin/env bash
# Installs everything dormant needs to build and test, on Debian 12 or 13, as root.
# Idempotent: a second run checks, prints what it found, and changes nothing.
# `setup.sh --bpy` installs only Blender as a Python module, for make compare-cycles (below).
# `setup.sh --rust` installs only Rust (below).
#
# Rust: the workspace's `rust-version` (Cargo.toml) or newer. Debian's packaged rustc is older,
#   so where no such Rust is found (on PATH or in ~/.cargo/bin), rustup installs that version
#   into ~/.cargo (minimal profile with clippy and rustfmt; the Makefile puts ~/.cargo/bin on
#   PATH); where that fails, the script stops with one line naming what to install.
#
# Embree 4 (feature `embree`):
#   Debian >= 13: apt's libembree-dev (Embree 4.3).
#   Debian 12:    a git-ignored prefix .deps/embree4/{include,lib} holding the headers from
#                 Debian 13's libembree-dev .deb (fetched with a private apt configuration; the
#                 system's stays untouched) and the official Embree 4.4 runtime with its TBB
#                 from PyPI's embreex==4.4.0.post1 wheel. See docs/embree.md for why.
#   Elsewhere:    set EMBREE_DIR to an Embree 4 prefix (include/embree4, lib/libembree4.so).
# Intel Open Image Denoise 2.5.1 (feature `oidn`, for `dormant render --denoise`):
#   Debian 12/13: neither ships it; a git-ignored prefix .deps/oidn/lib holding the official
#                 OIDN 2.5.1 runtime from PyPI's pyoidn==2.5.1.0 wheel (checked against a pinned
#                 sha256): the library, its core, the CPU device and TBB only (no GPU devices).
#                 The bindings (ffi/oidn-sys) are hand-written, so no headers are needed.
#   Elsewhere:    set OIDN_DIR to an OIDN 2.x prefix (lib/libOpenImageDenoise.so).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
prefix="$root/.deps/embree4"
embreex_version="4.4.0.post1"
oidn_prefix="$root/.deps/oidn"
oidn_version="2.5.1"
pyoidn_version="2.5.1.0"
pyoidn_sha256="32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e"

say() { printf 'setup: %s\n' "$*"; }
die() { printf 'setup: error: %s\n' "$*" >&2; exit 1; }

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo "$@"
    else die "need root to run: $* (run this script as root)"; fi
}

# --- apt packages ------------------------------------------------------------------------
# valgrind: `make instruction-check`, CI's instruction-count guard (scripts/instruction-check.py).
apt_packages=(build-essential pkg-config libclang-dev python3 python3-pip ca-certificates valgrind)
apt_updated=0
apt_install() {
    local missing=()
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -eq 0 ]; then
        say "apt packages present: $*"
        return
    fi
    if [ $apt_updated -eq 0 ]; then
        as_root apt-get update -qq >/dev/null
        apt_updated=1
    fi
    say "installing apt packages: ${missing[*]}"
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

if ! command -v dpkg-query >/dev/null 2>&1; then
    die "this script supports Debian 12/13 only; on other systems install libclang, pkg-config and
Embree 4 yourself and set EMBREE_DIR to its prefix (include/embree4/rtcore.h, lib/libembree4.so)"
fi
# python3/pip come from the image on some machines (pyenv); only install Debian's when absent.
command -v python3 >/dev/null 2>&1 && python3 -m pip --version >/dev/null 2>&1 \
    && apt_packages=(build-essential pkg-config libclang-dev ca-certificates)
apt_install "${apt_packages[@]}"

# --- Rust ----------------------------------------------------------------------------------
# RUSTUP_INIT_URL overrides where rustup's installer (the rustup-init binary) comes from; the
# tests point it nowhere.
install_rust() {
    local want have
    want=$(sed -n 's/^rust-version *= *"\([0-9.]*\)".*/\1/p' "$root/Cargo.toml" | head -1)
    [ -n "$want" ] || die "no rust-version in $root/Cargo.toml"
    export PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"
    have=$(rustc --version 2>/dev/null | awk '{print $2}' || true)
    if [ -n "$have" ] && command -v cargo >/dev/null 2>&1 \
        && [ "$(printf '%s\n%s\n' "$want" "$have" | sort -V | head -1)" = "$want" ]; then
        say "Rust $have present (the workspace needs $want or newer)"
        return
    fi
    local why="install Rust $want or newer (https://rustup.rs: rustup toolchain install $want) and run this again"
    if command -v rustup >/dev/null 2>&1; then
        say "installing Rust $want with rustup (found ${have:-no rustc})"
        rustup toolchain install "$want" --profile minimal -c clippy -c rustfmt >/dev/null \
            && rustup default "$want" >/dev/null || die "rustup could not install Rust $want: $why"
    else
        command -v curl >/dev/null 2>&1 || apt_install curl
        say "installing rustup and Rust $want into ${CARGO_HOME:-$HOME/.cargo} (found ${have:-no rustc})"
        local init url
        init="$(mktemp -d)/rustup-init"  # rustup-init takes its role from its file name
        url="${RUSTUP_INIT_URL:-https://static.rust-lang.org/rustup/dist/$(uname -m)-unknown-linux-gnu/rustup-init}"
        curl --proto '=https,file' -sSfL -o "$init" "$url" 2>/dev/null && chmod +x "$init" \
            && "$init" -y -q --no-modify-path --profile minimal --default-toolchain "$want" \
                -c clippy -c rustfmt >/dev/null 2>&1 \
            && command -v cargo >/dev/null 2>&1 || { rm -rf "${init%/*}"; die "could not install Rust $want: $why"; }
        rm -rf "${init%/*}"
    fi
    say "Rust $(rustc --version | awk '{print $2}') installed"
}
if [ "${1:-}" = --rust ]; then
    install_rust
    exit 0
fi

# --- Blender as a Python module (`--bpy` only: make compare-cycles, make blender-roundtrip) ---
# PyPI's bpy (BPY_VERSION, a wheel of some 400 MB) in the venv BPY_VENV (default the git-ignored
# .deps/bpy-venv; relative to the checkout). bpy 5.0 needs Python 3.11, Debian 12's; Debian
# ships venv's ensurepip apart (python3.11-venv).
if [ "${1:-}" = --bpy ]; then
    venv="${BPY_VENV:-.deps/bpy-venv}"
    case "$venv" in /*) ;; *) venv="$root/$venv" ;; esac
    bpy_version="${BPY_VERSION:-5.0.1}"
    has_bpy() {
        "$venv/bin/python" -c 'import importlib.metadata as m, sys; sys.exit(m.version("bpy") != sys.argv[1])' \
            "$bpy_version" 2>/dev/null
    }
    if ! has_bpy; then
        if [ ! -x "$venv/bin/python" ]; then
            python3.11 -c 'import ensurepip' 2>/dev/null || apt_install python3.11 python3.11-venv
            python3.11 -m venv "$venv"
        fi
        say "installing bpy==$bpy_version into $venv"
        "$venv/bin/pip" install -q "bpy==$bpy_version"
    fi
    say "bpy $bpy_version present: $venv"
    exit 0
fi

install_rust

# --- Open Image Denoise 2 (before Embree, whose section ends the script) -------------------
# The wheel's libraries carry RPATH $ORIGIN/../lib, and the core loads its device modules
# from its own directory by their versioned names, so they keep the wheel's names under lib/.
oidn_libs=(libOpenImageDenoise.so.$oidn_version libOpenImageDenoise_core.so.$oidn_version
           libOpenImageDenoise_device_cpu.so.$oidn_version libtbb.so.12)
oidn_stamp="OIDN $oidn_version (CPU device, TBB) from pyoidn $pyoidn_version"
if [ -n "${OIDN_DIR:-}" ]; then
    [ -e "$OIDN_DIR/lib/libOpenImageDenoise.so" ] || die "OIDN_DIR=$OIDN_DIR has no lib/libOpenImageDenoise.so"
    say "using OIDN_DIR=$OIDN_DIR; nothing to install"
elif [ -f "$oidn_prefix/.complete" ] && [ "$(cat "$oidn_prefix/.complete")" = "$oidn_stamp" ] \
    && [ -e "$oidn_prefix/lib/libOpenImageDenoise.so" ]; then
    say "OIDN prefix present: $oidn_prefix ($oidn_stamp)"
else
    oidn_work=$(mktemp -d "${TMPDIR:-/tmp}/dormant-setup-oidn.XXXXXX")
    trap 'rm -rf "$oidn_work"' EXIT
    mkdir -p "$oidn_work/prefix/lib"
    echo "pyoidn==$pyoidn_version --hash=sha256:$pyoidn_sha256" > "$oidn_work/requirements.txt"
    say "fetching pyoidn==$pyoidn_version wheel (official OIDN $oidn_version runtime, about 90 MB)"
    python3 -m pip download -q --no-deps --only-binary=:all: --platform manylinux2014_x86_64 \
        --python-version 3.11 --require-hashes -r "$oidn_work/requirements.txt" -d "$oidn_work/wheel"
    wheel=$(ls "$oidn_work"/wheel/pyoidn-*.whl | head -n1)
    python3 - "$wheel" "$oidn_work/prefix/lib" "${oidn_libs[@]}" <<'PY'
import os, sys, zipfile
wheel, dest, names = sys.argv[1], sys.argv[2], sys.argv[3:]
with zipfile.ZipFile(wheel) as z:
    for name in names:
        member = "pyoidn/oidn/lib/" + name
        if member not in z.namelist():
            sys.exit(f"setup: error: the pyoidn wheel has no {member}")
        target = os.path.join(dest, name)
        with z.open(member) as src, open(target, "wb") as out:
            out.write(src.read())
        os.chmod(target, 0o755)
PY
    ln -sf "libOpenImageDenoise.so.$oidn_version" "$oidn_work/prefix/lib/libOpenImageDenoise.so.2"
    ln -sf "libOpenImageDenoise.so.$oidn_version" "$oidn_work/prefix/lib/libOpenImageDenoise.so"
    echo "$oidn_stamp" > "$oidn_work/prefix/.complete"
    rm -rf "$oidn_prefix"
    mkdir -p "$(dirname "$oidn_prefix")"
    mv "$oidn_work/prefix" "$oidn_prefix"
    rm -rf "$oidn_work"
    say "installed $oidn_stamp into $oidn_prefix"
fi

# --- Embree 4 ------------------------------------------------------------------------------
if [ -n "${EMBREE_DIR:-}" ]; then
    [ -f "$EMBREE_DIR/include/embree4/rtcore.h" ] || die "EMBREE_DIR=$EMBREE_DIR has no include/embree4/rtcore.h"
    say "using EMBREE_DIR=$EMBREE_DIR; nothing to install"
    exit 0
fi

. /etc/os-release
debian_major=${VERSION_ID%%.*}
[ "${ID:-}" = debian ] || die "unsupported distribution '${ID:-unknown}': install Embree 4 and set EMBREE_DIR"

if [ "$debian_major" -ge 13 ]; then
    apt_install libembree-dev
    say "Embree 4 from Debian $debian_major's libembree-dev"
    exit 0
fi
[ "$debian_major" -eq 12 ] || die "Debian $VERSION_ID has no usable Embree 4: install it and set EMBREE_DIR"

# Debian 12: project-local prefix.
if [ -f "$prefix/include/embree4/rtcore.h" ] && [ -e "$prefix/lib/libembree4.so" ] \
    && [ -f "$prefix/.complete" ]; then
    say "Embree 4 prefix present: $prefix ($(cat "$prefix/.complete"))"
    exit 0
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/dormant-setup.XXXXXX")
trap 'rm -rf "$work"' EXIT
stage="$work/prefix"
mkdir -p "$stage/include" "$stage/lib"

# Headers: Debian 13's libembree-dev, through a private apt configuration. The mirror is the
# one this machine's own Debian sources already use.
mirror=""
for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    mirror=$(awk '/^URIs:/{u=$2} /^Suites:/{ if ($0 ~ /bookworm( |$)/) { print u; exit } }' "$f")
    [ -n "$mirror" ] && break
done
if [ -z "$mirror" ] && [ -f /etc/apt/sources.list ]; then
    mirror=$(awk '$1=="deb" && $0 ~ / bookworm / {for(i=2;i<=NF;i++) if ($i ~ /^[a-z]+:\/\//) {print $i; exit}}' /etc/apt/sources.list)
fi
[ -n "$mirror" ] || die "could not find this machine's Debian mirror in /etc/apt/sources.list*"
keyring=/usr/share/keyrings/debian-archive-keyring.gpg
[ -f "$keyring" ] || apt_install debian-archive-keyring

apt_dir="$work/apt"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
echo "deb [signed-by=$keyring] $mirror trixie main" > "$apt_dir/sources.list"
apt_opts=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o "Dir::Etc::SourceParts=/dev/null"
          -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache"
          -o "Debug::NoLocking=1" -o "APT::Sandbox::User=root")
say "fetching Debian 13 libembree-dev (headers only) from $mirror"
apt-get "${apt_opts[@]}" update -qq >/dev/null
(cd "$work" && apt-get "${apt_opts[@]}" download -qq libembree-dev >/dev/null)
deb=$(ls "$work"/libembree-dev_*.deb 2>/dev/null | head -n1)
[ -n "$deb" ] || die "apt-get download libembree-dev from trixie produced no .deb"
dpkg-deb -x "$deb" "$work/deb"
[ -f "$work/deb/usr/include/embree4/rtcore.h" ] || die "$deb has no usr/include/embree4/rtcore.h"
cp -r "$work/deb/usr/include/embree4" "$stage/include/"
header_version=$(basename "$deb" | sed -E 's/^libembree-dev_([^_]+)_.*/\1/')

# Runtime: the official Embree 4.4 build inside PyPI's embreex wheel.
say "fetching embreex==$embreex_version wheel (official Embree 4.4 runtime + TBB)"
python3 -m pip download -q --no-deps --only-binary=:all: --platform manylinux_2_28_x86_64 \
    --python-version 3.11 -d "$work/wheel" "embreex==$embreex_version"
wheel=$(ls "$work"/wheel/embreex-*.whl | head -n1)
python3 - "$wheel" "$stage/lib" <<'PY'
import os, sys, zipfile
wheel, dest = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if name.startswith("embreex.libs/") and ".so" in name:
            target = os.path.join(dest, os.path.basename(name))
            with z.open(name) as src, open(target, "wb") as out:
                out.write(src.read())
            os.chmod(target, 0o755)
PY
lib=$(cd "$stage/lib" && ls libembree4-*.so.4 2>/dev/null | head -n1)
[ -n "$lib" ] || die "the embreex wheel has no embreex.libs/libembree4-*.so.4"
ln -sf "$lib" "$stage/lib/libembree4.so"
ln -sf "$lib" "$stage/lib/libembree4.so.4"

echo "headers $header_version (Debian 13 libembree-dev), library embreex $embreex_version ($lib)" > "$stage/.complete"
rm -rf "$prefix"
mkdir -p "$(dirname "$prefix")"
mv "$stage" "$prefix"
say "installed Embree 4 into $prefix: $(cat "$prefix/.complete")"
