#!/usr/bin/env bash
# The whole test suite: formatting and lints, the Rust tests (including the header
# freshness check), then the C tests under ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
rustup component add rustfmt clippy >/dev/null 2>&1 || true
cargo fmt --all -- --check
cargo clippy --all-targets -- -D warnings
cargo test --release
cargo build --release
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure
# Fuzz smoke (cargo-fuzz on nightly; scripts/fuzz.sh installs what it needs): each
# target for GLINT_FUZZ_SECONDS (default 30) from its committed seeds.
scripts/fuzz.sh all "${GLINT_FUZZ_SECONDS:-30}"
