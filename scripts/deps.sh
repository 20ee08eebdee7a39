#!/usr/bin/env bash
# Install what building and testing Glint needs on Debian 12, skipping what is there.
# Sourced by scripts/run.sh and scripts/test.sh.
set -euo pipefail

# binutils: nm for tests/simd_inlining.rs.
# libembree-dev, libopenimageio-dev, libassimp-dev, libcjson-dev: the example hosts
# (Embree 3 geometry, EXR/PNG output, meshes and scene files).
# valgrind: the *_valgrind ctests (reads of the uninstrumented Rust library).
packages=(cmake pkg-config gcc g++ make binutils libcmocka-dev valgrind
          libembree-dev libopenimageio-dev libassimp-dev libcjson-dev)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    echo "glint: installing Debian packages: ${missing[*]}" >&2
    sudo_cmd=()
    [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null; then
    echo "glint: cargo not found; install Rust (https://rustup.rs) and re-run" >&2
    exit 1
fi
