#!/usr/bin/env bash
# The main job: install what is missing, build Glint and the C examples, run the quickstart.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
cargo build --release
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target quickstart
./build/examples/quickstart
