#!/usr/bin/env bash
# The C tests, plugins and example hosts under memory checkers:
#   scripts/sanitize.sh [asan|valgrind|all]     (default: all)
# asan:     build-asan/, built with -DGLINT_SANITIZE=address,undefined (ASan, UBSan and
#           LeakSanitizer; cmake/GlintSanitize.cmake), then the whole ctest suite.
# valgrind: build-memcheck/, an ordinary build, every test program under valgrind
#           memcheck (ctest -T memcheck), a test failing on any error or leak.
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

if [ "$mode" = valgrind ] || [ "$mode" = all ]; then
    if ! command -v valgrind >/dev/null; then
        sudo_cmd=()
        [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
        "${sudo_cmd[@]}" apt-get update -qq
        DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq valgrind >/dev/null
    fi
    cmake -S . -B build-memcheck -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
    cmake --build build-memcheck -j"$jobs"
    # Not under valgrind: package_consumers (a CMake build of an outside project) and
    # plugin_guide_example (a CMake script comparing the guide with minimal.c) run no
    # Glint code of their own.
    ctest --test-dir build-memcheck -T memcheck --output-on-failure --timeout 3000 \
          -E '^(package_consumers|plugin_guide_example)$' \
          --overwrite MemoryCheckCommand="$(command -v valgrind)" \
          --overwrite "MemoryCheckCommandOptions=--leak-check=full --show-leak-kinds=definite,indirect --errors-for-leak-kinds=definite,indirect --error-exitcode=1 --num-callers=40 --track-origins=yes" \
        || status=1
fi
exit "$status"
