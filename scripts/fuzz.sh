#!/usr/bin/env bash
# Runs one libFuzzer target for a set time.
# usage: scripts/fuzz.sh TARGET SECONDS [libFuzzer options...]
#   TARGET: ply obj off gltf preset conf manifest cache stream jobs (baker readers, bake manifests, cache
#   files, the streaming readers and the job list, tests/fuzz/) or lod pack pfrep valence meshopt cluster (runtime,
#   runtime/tools/fuzz_*.cpp).
# Configures and builds $LODBAKE_FUZZ_BUILD_DIR (default build-fuzz) with Clang and
# -DLODBAKE_BUILD_FUZZERS=ON unless LODBAKE_FUZZ_NO_BUILD=1, builds the seed corpora once
# (scripts/fuzz-seeds.sh, with $LODBAKE_CLI or build/baker/lodbake, else the fuzz build's own CLI),
# and fuzzes on one core into $build/corpus/TARGET (kept between runs) with crashes written to
# $build/artifacts/TARGET/. Exit status is libFuzzer's: non-zero on a crash, leak, timeout or
# sanitizer report. A crash input belongs in tests/fuzz/regressions/TARGET/ once fixed.
# libFuzzer picks a random seed, so each run explores anew (what hunting wants). With
# LODBAKE_FUZZ_SEED=N the run is repeatable instead (the CI smoke, scripts/setup-and-test.sh): seed N,
# a corpus folder emptied first ($build/corpus-seeded/TARGET), the seeds given in name order, no
# corpus reloads, and address-space randomisation off (setarch -R) where the system allows it, since
# the comparisons libFuzzer learns from include pointers. Add -runs=N to stop after N inputs rather
# than after SECONDS (which then only caps the run).
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: scripts/fuzz.sh TARGET SECONDS [libFuzzer options...]" >&2
    exit 2
fi
target=$1
seconds=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
build=${LODBAKE_FUZZ_BUILD_DIR:-build-fuzz}

case "$target" in
ply | obj | off | gltf | preset | conf | manifest | cache | stream | jobs)
    exe="$build/tests/fuzz/lodbake_fuzz_$target" cmake_target=lodbake_fuzz_$target
    ;;
lod | pack | pfrep | valence | meshopt | cluster) exe="$build/runtime/lodrt_fuzz_$target" cmake_target=lodrt_fuzz_$target ;;
*)
    echo "fuzz.sh: unknown target '$target' (ply obj off gltf preset conf manifest cache stream lod pack pfrep valence meshopt cluster jobs)" >&2
    exit 2
    ;;
esac
dict=
case "$target" in
ply | obj | off | gltf | preset) dict=tests/fuzz/dict/$target.dict ;;
manifest | jobs) dict=tests/fuzz/dict/preset.dict ;;
stream) dict=tests/fuzz/dict/ply.dict ;;
lod | pack) dict=tests/fuzz/dict/gltf.dict ;;
esac

if [ "${LODBAKE_FUZZ_NO_BUILD:-0}" != 1 ]; then
    if [ ! -f "$build/CMakeCache.txt" ]; then
        launcher=()
        command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
        CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
            -DLODBAKE_BUILD_FUZZERS=ON -DLODBAKE_BUILD_TESTS=OFF -DLODBAKE_BUILD_BENCHMARKS=OFF \
            "${launcher[@]}" >/dev/null
    fi
    cmake --build "$build" --target "$cmake_target" --parallel 2 >/dev/null
fi

seeds="$build/seeds"
if [ ! -f "$seeds/.done" ]; then
    cli=${LODBAKE_CLI:-build/baker/lodbake}
    if [ ! -x "$cli" ]; then
        cmake --build "$build" --target lodbake --parallel 2 >/dev/null
        cli="$build/baker/lodbake"
    fi
    rm -rf "$seeds"
    ASAN_OPTIONS=detect_leaks=0 scripts/fuzz-seeds.sh "$seeds" "$cli"
    touch "$seeds/.done"
fi

artifacts="$build/artifacts/$target"
mkdir -p "$artifacts"
args=(-max_total_time="$seconds" -max_len=65536 -timeout=20 -rss_limit_mb=2048 -print_final_stats=1
    -artifact_prefix="$artifacts/")
[ -n "$dict" ] && args+=(-dict="$dict")
run=()
if [ -n "${LODBAKE_FUZZ_SEED:-}" ]; then
    corpus="$build/corpus-seeded/$target"
    rm -rf "$corpus"
    mkdir -p "$corpus"
    list="$build/seeds/$target.list"
    (cd "$seeds/$target" && find . -maxdepth 1 -type f | LC_ALL=C sort | sed "s|^\./|$PWD/|" | paste -sd, -) >"$list"
    args=("$corpus" -seed_inputs=@"$list" -seed="$LODBAKE_FUZZ_SEED" -reload=0 "${args[@]}")
    setarch "$(uname -m)" -R true 2>/dev/null && run=(setarch "$(uname -m)" -R)
else
    corpus="$build/corpus/$target"
    mkdir -p "$corpus"
    args=("$corpus" "$seeds/$target" "${args[@]}")
fi
exec "${run[@]}" "$exe" "${args[@]}" "$@"
