#!/bin/sh
# Fuzzes the .lbm decoder with libFuzzer for a set time.
# usage: scripts/fuzz-valence.sh [SECONDS]   (default 60)
# Builds build-fuzz/ with Clang and LODRT_BUILD_FUZZERS=ON, seeds build-fuzz/valence-corpus with
# streams encoded by a normal build's lodbake (build/baker/lodbake) when present.
set -eu
seconds=${1:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DLODRT_BUILD_FUZZERS=ON >/dev/null
cmake --build build-fuzz --target lodrt_fuzz_valence --parallel 2
corpus=build-fuzz/valence-corpus
mkdir -p "$corpus"
if [ -x build/baker/lodbake ]; then
    printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' >"$corpus/tet.off"
    build/baker/lodbake encode "$corpus/tet.off" -o "$corpus/tet.lbm" --bits 10 >/dev/null
    rm "$corpus/tet.off"
    # Two triangles sharing only a vertex and a third on a fin edge: holes (dummy vertices) and copies.
    printf 'OFF\n6 4 0\n0 0 0\n1 0 0\n0 1 0\n-1 0 0\n0 -1 0\n1 1 1\n3 0 1 2\n3 0 3 4\n3 1 0 5\n3 0 1 5\n' \
        >"$corpus/fan.off"
    build/baker/lodbake encode "$corpus/fan.off" -o "$corpus/fan.lbm" --bits 9 >/dev/null
    rm "$corpus/fan.off"
    build/baker/lodbake encode assets/samples/rock_scan/rock_000.ply -o "$corpus/rock.lbm" --bits 8 >/dev/null
fi
exec build-fuzz/runtime/lodrt_fuzz_valence "$corpus" -max_total_time="$seconds" -max_len=65536
