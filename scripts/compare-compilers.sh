#!/usr/bin/env bash
# compare-compilers.sh RELEASE_DIR ASAN_DIR: packs must not depend on the compiler. Bakes shared scans
# with the lodbake of both build trees (the GCC release tree and the Clang sanitizer tree of
# setup-and-test.sh), with default options and with the desktop preset, and compares the sha256 of
# each pair. On a difference it names the accessors or buffer views and byte ranges that differ
# (scripts/glb_diff.py) and exits 1. The scans come from ../shared/meshes (LODBAKE_SHARED_MESHES
# overrides); a missing scan is an error, not a skip.
#   LODBAKE_COMPARE_THREADS  thread counts to bake with, space-separated (default "2")
set -euo pipefail
if [ $# -ne 2 ]; then
    echo "usage: scripts/compare-compilers.sh RELEASE_DIR ASAN_DIR" >&2
    exit 2
fi
release=$(realpath -m "$1/baker/lodbake")
asan=$(realpath -m "$2/baker/lodbake")
cd "$(dirname "$0")/.."
shared=${LODBAKE_SHARED_MESHES:-../shared/meshes}
scans=(bunny_zipper.ply lucy100k.ply nefertiti_fraunhofer_textured.glb)
for exe in "$release" "$asan"; do
    [ -x "$exe" ] || { echo "compare-compilers: $exe: not built" >&2; exit 1; }
done
for scan in "${scans[@]}"; do
    [ -f "$shared/$scan" ] || { echo "compare-compilers: $shared/$scan: shared scan missing" >&2; exit 1; }
done

out=$(mktemp -d "${TMPDIR:-/tmp}/lodbake-compilers.XXXXXX")
trap 'rm -rf "$out"' EXIT
# As the sanitizer tests run the CLI: findings abort; LeakSanitizer off for the bakes
# (tests/baker/gltf/gltf_test_util.h, withoutLeakCheck: its tracer can crash at the exit of a
# multi-threaded bake).
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=0:strict_string_checks=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
failed=0
for preset in none desktop; do
    args=()
    [ "$preset" = desktop ] && args=(--preset configs/desktop.json)
    for threads in ${LODBAKE_COMPARE_THREADS:-2}; do
        for scan in "${scans[@]}"; do
            stem=$(basename "${scan%.*}")
            for tree in release asan; do
                exe=$release
                [ "$tree" = asan ] && exe=$asan
                if ! "$exe" bake "$shared/$scan" -o "$out/$tree-$preset-$threads-$stem.glb" "${args[@]}" \
                    --threads "$threads" --quiet >"$out/$tree.log" 2>&1; then
                    cat "$out/$tree.log" >&2
                    echo "compare-compilers: $tree bake of $scan failed (preset $preset, $threads threads)" >&2
                    exit 1
                fi
            done
            a=$(sha256sum <"$out/release-$preset-$threads-$stem.glb" | cut -d' ' -f1)
            b=$(sha256sum <"$out/asan-$preset-$threads-$stem.glb" | cut -d' ' -f1)
            if [ "$a" = "$b" ]; then
                echo "same  $a  $scan (preset $preset, $threads threads)"
            else
                echo "DIFF  $scan (preset $preset, $threads threads): release $a, sanitizer $b"
                python3 scripts/glb_diff.py "$out/release-$preset-$threads-$stem.glb" \
                    "$out/asan-$preset-$threads-$stem.glb" | sed 's/^/      /' || true
                failed=1
            fi
        done
    done
done
if [ "$failed" != 0 ]; then
    echo "compare-compilers: packs differ between $1 and $2 (docs/architecture.md, Determinism)" >&2
    exit 1
fi
