#!/usr/bin/env bash
# What the test suite needs besides Rust and Python 3, in one list, and how
# it gets onto the machine.
#
#   tests/setup.sh           install whatever is missing: the Debian packages
#                            (as root, through apt-get), the Rust components
#                            and targets (rustup) and the Python set of the
#                            tests in .venv (with zig and cargo-zigbuild)
#   tests/setup.sh --check   install nothing: list what is missing with the
#                            command that installs it, exit 1 if anything is
#
# tests/run_all.sh runs this first (installing when it can), so the test
# command works by itself on a fresh Debian or Ubuntu machine; .ci/run is
# nothing more than tests/run_all.sh.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

# The Debian packages, each with what needs it.
packages=(
    python3-venv          # the test venv (.venv)
    libtbb12              # ecospy's libecosc.so (an interop master) links it
    libclang-dev          # bindgen, for the `fmi` crate that interop-fmi-rs imports FMUs with
    valgrind              # robustness: memcheck of the C harness
    gcc g++               # the C harnesses, libFuzzer's runtime
    libxml2-utils         # xmllint: the FMI 3.0 descriptions against the standard's schema
    gcc-mingw-w64-x86-64  # the Windows x86-64 libraries and harness
    wine64                # ... run under wine
    gcc-aarch64-linux-gnu libc6-dev-arm64-cross # the Linux aarch64 harness
    qemu-user             # ... run under qemu-aarch64
)
# llvm-tools: llvm-profdata, which merges the training counts of the
# profile-guided x86-64 Linux libraries (fmu-build/src/pgo.rs).
rust_components=(rustfmt clippy llvm-tools)
rust_targets=(x86_64-pc-windows-gnu aarch64-unknown-linux-gnu)

check_only=false
case "${1:-}" in
    "") ;;
    --check) check_only=true ;;
    *)
        echo "usage: tests/setup.sh [--check]" >&2
        exit 2
        ;;
esac

missing_packages=()
if command -v dpkg-query >/dev/null; then
    for package in "${packages[@]}"; do
        dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
            missing_packages+=("$package")
    done
else
    python3 -c "import venv, ensurepip" 2>/dev/null || missing_packages+=(python3-venv)
    echo "note: no dpkg-query; make sure the equivalents of these Debian packages are installed: ${packages[*]}" >&2
fi
missing_components=()
installed_components="$(rustup component list --installed 2>/dev/null || true)"
for component in "${rust_components[@]}"; do
    case "$component" in
        llvm-tools) grep -q '^llvm-tools' <<<"$installed_components" ;;
        *) cargo "${component/rustfmt/fmt}" --version >/dev/null 2>&1 ;;
    esac || missing_components+=("$component")
done
missing_targets=()
installed_targets="$(rustup target list --installed 2>/dev/null || true)"
for target in "${rust_targets[@]}"; do
    grep -qx "$target" <<<"$installed_targets" || missing_targets+=("$target")
done

if $check_only; then
    status=0
    if [ ${#missing_packages[@]} -gt 0 ]; then
        echo "missing Debian packages: apt-get install -y --no-install-recommends ${missing_packages[*]}" >&2
        status=1
    fi
    if [ ${#missing_components[@]} -gt 0 ]; then
        echo "missing Rust components: rustup component add ${missing_components[*]}" >&2
        status=1
    fi
    if [ ${#missing_targets[@]} -gt 0 ]; then
        echo "missing Rust targets: rustup target add ${missing_targets[*]}" >&2
        status=1
    fi
    exit "$status"
fi

if [ ${#missing_packages[@]} -gt 0 ]; then
    if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null; then
        echo "the tests need these Debian packages, and only root can install them:" >&2
        echo "    apt-get install -y --no-install-recommends ${missing_packages[*]}" >&2
        echo "(then run the test command again)" >&2
        exit 1
    fi
    echo "installing ${missing_packages[*]}" >&2
    apt-get update >&2
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing_packages[@]}" >&2
fi
if [ ${#missing_components[@]} -gt 0 ]; then
    rustup component add "${missing_components[@]}" >&2
fi
if [ ${#missing_targets[@]} -gt 0 ]; then
    rustup target add "${missing_targets[@]}" >&2
fi
# The full Python set (tests/python/requirements.txt, which includes the
# quick-start set and fmu-build's zig and cargo-zigbuild).
tests/python_env.sh full >/dev/null
