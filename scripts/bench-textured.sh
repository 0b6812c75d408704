#!/usr/bin/env bash
# Textured side-by-side benchmark (issue 28; docs/benchmarks.md, "Textured assets against gltfpack"):
# our bake's LOD chain against gltfpack 1.3 `-si R -se 1 -noq -kv` at equal triangle counts on
# nefertiti_fraunhofer_textured, spot, LeePerrySmith and an atlased rock from the scan simulator
# (216 charts), measured with ../shared/eval/meshdist.py. Prints BAR| lines (bench_bar.h's format).
# usage: scripts/bench-textured.sh [--check] [ASSET...]   (default: the four assets above)
# Needs: a Release build in BUILD_DIR (default build; lodbake and lodbake_scansim are built here),
# node + npm (gltfpack from scripts/node-bench, installed with `npm ci` when missing), python3 with
# numpy and Open3D (scripts/install-deps.sh), ../shared next to the repository.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${BUILD_DIR:-build}
check=()
assets=()
for a in "$@"; do
    if [ "$a" = --check ]; then check=(--check); else assets+=("$a"); fi
done
cmake --build "$build_dir" --parallel 2 --target lodbake lodbake_scansim >/dev/null
if [ ! -x scripts/node-bench/node_modules/.bin/gltfpack ]; then
    (cd scripts/node-bench && npm ci --no-audit --no-fund --loglevel=error)
fi
shared=$(cd .. && pwd)/shared
tmp=$(mktemp -d /tmp/textured_bench.XXXX)
trap 'rm -rf "$tmp"' EXIT
if [ ${#assets[@]} -eq 0 ]; then
    "$build_dir/assets/lodbake_scansim" -o "$tmp/rock" --atlas 6 >/dev/null
    assets=("$shared/meshes/nefertiti_fraunhofer_textured.glb" "$shared/meshes/spot.obj"
            "$shared/meshes/lee_perry_smith/LeePerrySmith.glb" "$tmp/rock/rock_atlas.obj")
fi
# The system python carries numpy and Open3D (Debian packages), whatever python3 comes first on PATH.
python=/usr/bin/python3
[ -x "$python" ] || python=python3
"$python" scripts/bench_textured.py --lodbake "$build_dir/baker/lodbake" \
    --gltfpack scripts/node-bench/node_modules/.bin/gltfpack --eval "$shared/eval" "${check[@]}" "${assets[@]}"
