#!/usr/bin/env bash
# The main job: install what is missing, build Glint and the C examples, run the quickstart,
# then render the material showcase with the path tracer (about a minute on 2 cores) and the
# scanline host (well under a second).
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
echo
./build/examples/scanline/scanline --out build/renders/showcase_scanline
echo
echo "image: $(pwd)/build/renders/showcase.png (linear: build/renders/showcase.exr)"
echo "scanline image: $(pwd)/build/renders/showcase_scanline.png"
