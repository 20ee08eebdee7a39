#!/usr/bin/env bash
# The C tests, plugins and example hosts under memory checkers:
#   scripts/sanitize.sh [asan|valgrind|hosts|all]     (default: all)
# asan:     build-asan/, built with -DGLINT_SANITIZE=address,undefined (ASan, UBSan and
#           LeakSanitizer; cmake/GlintSanitize.cmake), then the whole ctest suite.
# valgrind: build-memcheck/, an ordinary build, every test program under valgrind
#           memcheck (ctest -T memcheck), a test failing on any error or leak.
# hosts:    build-memcheck/, every example host rendering small images (all showcase
#           materials, the Charlie plugin, JSON and block closures, the scene files)
#           under valgrind memcheck: the ctest renders are too large for valgrind.
# The Cargo-built library is the normal release build in both. Exits non-zero when a
# checker reports anything; the logs are build-memcheck/Testing/Temporary/MemoryChecker.*.log.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
mode=${1:-all}
jobs=$(nproc)
cargo build --release
status=0

if [ "$mode" = asan ] || [ "$mode" = all ]; then
    cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
          -DGLINT_SANITIZE=address,undefined >/dev/null
    cmake --build build-asan -j"$jobs"
    # detect_leaks: LeakSanitizer at exit; UBSan reports are fatal (-fno-sanitize-recover).
    ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1 \
    UBSAN_OPTIONS=print_stacktrace=1 \
        ctest --test-dir build-asan --output-on-failure -j"$jobs" || status=1
fi

if [ "$mode" = valgrind ] || [ "$mode" = hosts ] || [ "$mode" = all ]; then
    if ! command -v valgrind >/dev/null; then
        sudo_cmd=()
        [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
        "${sudo_cmd[@]}" apt-get update -qq
        DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq valgrind >/dev/null
    fi
    cmake -S . -B build-memcheck -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
    cmake --build build-memcheck -j"$jobs"
fi
memcheck_options=(--leak-check=full --show-leak-kinds=definite,indirect
                  --errors-for-leak-kinds=definite,indirect --error-exitcode=1
                  --num-callers=40 --track-origins=yes)

if [ "$mode" = valgrind ] || [ "$mode" = all ]; then
    # Not under valgrind: package_consumers (a CMake build of an outside project) and
    # plugin_guide_example (a CMake script comparing the guide with minimal.c) run no
    # Glint code of their own; the example hosts' ctest renders (hours under valgrind)
    # are replaced by the small renders of the hosts mode; the *_valgrind tests run
    # valgrind themselves.
    ctest --test-dir build-memcheck -T memcheck --output-on-failure --timeout 3000 \
          -E '^(package_consumers|plugin_guide_example|pathtracer_.*|scanline_.*|.*_valgrind)$' \
          --overwrite MemoryCheckCommand="$(command -v valgrind)" \
          --overwrite "MemoryCheckCommandOptions=${memcheck_options[*]}" \
        || status=1
fi

if [ "$mode" = hosts ] || [ "$mode" = all ]; then
    out=build-memcheck/host-images
    mkdir -p "$out"
    pt=build-memcheck/examples/pathtracer/pathtracer
    sl=build-memcheck/examples/scanline/scanline
    small=(--width 24 --height 16 --threads 2 --quiet)
    runs=(
        "build-memcheck/examples/quickstart"
        "$pt ${small[*]} --spp 2 --out $out/pt_showcase"
        "$pt ${small[*]} --spp 2 --scene examples/pathtracer/scenes/torus.json --out $out/pt_torus"
        "$pt ${small[*]} --spp 2 --furnace --material sheen --out $out/pt_sheen"
        "$sl ${small[*]} --out $out/sl_showcase"
        "$sl ${small[*]} --scene examples/scanline/scenes/direct.json --out $out/sl_direct"
    )
    for run in "${runs[@]}"; do
        echo "valgrind: $run"
        # shellcheck disable=SC2086 # each run is a command line
        valgrind "${memcheck_options[@]}" --log-file="$out/valgrind.%p.log" $run \
            || { status=1; echo "FAILED under valgrind: $run (logs: $out/valgrind.*.log)"; }
    done
fi
exit "$status"
