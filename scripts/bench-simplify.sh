#!/usr/bin/env bash
# Simplification benchmark: builds tests/benchmarks/simplify_bench (Release), installs the pinned
# meshoptimizer 1.3 quality anchor with `npm ci` (scripts/node-bench), then runs the bench.
# Arguments are passed to simplify_bench, e.g.  scripts/bench-simplify.sh --check bunny_zipper.ply igea.ply
# (--check: exit 1 when a bar is not met). scripts/bench.sh runs it with every other benchmark.
# Needs: libmeshoptimizer-dev (native anchor), node + npm, ../shared/meshes next to the repository.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${LODBAKE_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DLODBAKE_BUILD_BENCHMARKS=ON >/dev/null
cmake --build "$build_dir" --parallel 2 --target simplify_bench

(cd scripts/node-bench && npm ci --no-audit --no-fund --loglevel=error)

exec "$build_dir/tests/benchmarks/simplify_bench" --node-bench "$PWD/scripts/node-bench" "$@"
