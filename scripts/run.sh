#!/usr/bin/env bash
# The main job: install what is missing, build Glint and the C examples, run the quickstart,
# then render the path tracer's material showcase (about a minute on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
cargo build --release
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
./build/examples/quickstart
echo
mkdir -p build/renders
./build/examples/pathtracer/pathtracer --out build/renders/showcase
echo "image: $(pwd)/build/renders/showcase.png (linear: build/renders/showcase.exr)"
