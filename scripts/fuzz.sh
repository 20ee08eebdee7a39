#!/usr/bin/env bash
# Fuzz Glint for a set time (cargo-fuzz: libFuzzer + AddressSanitizer + LeakSanitizer,
# nightly Rust):
#   scripts/fuzz.sh <target|all> [seconds per target, default 60] [libFuzzer flags...]
# Targets (fuzz/fuzz_targets/): json, api_calls, plugin_decl. The committed seeds in
# fuzz/corpus/<target> are read, never written; new inputs go to
# fuzz/target/corpus/<target> and a crash to fuzz/artifacts/<target>/ (exit status 1).
# Reproduce one: cargo +nightly fuzz run <target> <file>. Installs nightly and
# cargo-fuzz when missing.
set -euo pipefail
cd "$(dirname "$0")/.."
targets=(json api_calls plugin_decl)
target=${1:?"usage: scripts/fuzz.sh <${targets[*]// /|}|all> [seconds] [libFuzzer flags...]"}
seconds=${2:-60}
shift $(($# < 2 ? $# : 2))
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
if [ "$target" = all ]; then selected=("${targets[@]}"); else selected=("$target"); fi
cargo +nightly fuzz build -O
for t in "${selected[@]}"; do
    scratch=fuzz/target/corpus/$t
    mkdir -p "$scratch" "fuzz/corpus/$t"
    dict=()
    [ -f "fuzz/dict/$t.dict" ] && dict=("-dict=fuzz/dict/$t.dict")
    echo "glint: fuzzing $t for ${seconds}s" >&2
    cargo +nightly fuzz run -O "$t" "$scratch" "fuzz/corpus/$t" -- \
        -max_total_time="$seconds" -timeout=20 -print_final_stats=1 "${dict[@]}" "$@"
    # Known reproducers (fuzz/artifacts-known/<target>-*), each run twice in one process
    # so that state a run leaves behind (interned plugin strings) is used by the next.
    known=(fuzz/artifacts-known/"$t"-*)
    if [ -e "${known[0]}" ]; then
        echo "glint: replaying ${#known[@]} known reproducer(s) of $t" >&2
        cargo +nightly fuzz run -O "$t" "${known[@]}" "${known[@]}"
    fi
done
