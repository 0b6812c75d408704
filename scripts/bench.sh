#!/usr/bin/env bash
# Runs every benchmark program of tests/benchmarks on default inputs from ../shared/meshes and prints
# one summary table of all their bars (docs/benchmarks.md, "How to run the benchmarks").
#
# usage: scripts/bench.sh [--check] [--quick] [--only NAME[,NAME...]]
#   BUILD_DIR   build tree holding tests/benchmarks (default: build); configure it with
#               -DLODBAKE_BUILD_BENCHMARKS=ON and build it first: this script builds nothing.
#   --check     passed to every bench; the script exits 1 when any bar is not met.
#   --quick     smaller inputs and fewer runs (the bars whose input is fixed, such as the bake and
#               memory bars on dragon_poisson, keep it).
#   --only      run only the named benches (e.g. --only codec_bench,pfrep_bench; the scripts by their
#               name without .sh: bench-textured, bench-merge).
# The script exits 1 when a bench fails to run, whatever --check says. Logs: BENCH_LOG_DIR
# (default BUILD_DIR/bench_logs). The anchors of simplify_bench and pack_size_bench come from npm
# (scripts/node-bench); they are installed with `npm ci` when missing.
set -uo pipefail
cd "$(dirname "$0")/.."

build_dir=${BUILD_DIR:-build}
check=0
quick=0
only=""
while [ $# -gt 0 ]; do
    case "$1" in
        --check) check=1 ;;
        --quick) quick=1 ;;
        --only) shift; only=",${1:-},"; [ "$only" = ",," ] && { echo "bench.sh: --only needs a list" >&2; exit 2; } ;;
        *) echo "usage: scripts/bench.sh [--check] [--quick] [--only NAME[,NAME...]]" >&2; exit 2 ;;
    esac
    shift
done

bin="$build_dir/tests/benchmarks"
meshes=$(cd .. && pwd)/shared/meshes
log_dir=${BENCH_LOG_DIR:-$build_dir/bench_logs}
mkdir -p "$log_dir"
if [ ! -d "$meshes" ]; then
    echo "bench.sh: $meshes: the shared meshes folder is missing" >&2
    exit 1
fi
benches="bake_bench bake_stages_bench batch_bench codec_bench collapse_bench distance_bench multilevel_bench
pack_size_bench pfrep_bench read_bench repair_bench runtime_bench simplify_bench"
benches="$benches cluster_bench"
benches="$benches ooc_bench"
for b in $benches; do
    if [ ! -x "$bin/$b" ]; then
        echo "bench.sh: $bin/$b: not built (configure with -DLODBAKE_BUILD_BENCHMARKS=ON and build; BUILD_DIR=$build_dir)" >&2
        exit 1
    fi
done
wanted() { [ -z "$only" ] || [[ "$only" == *",$1,"* ]]; }
if { wanted simplify_bench || wanted pack_size_bench; } && [ ! -x scripts/node-bench/node_modules/.bin/gltfpack ]; then
    echo "bench.sh: installing the npm anchors (meshoptimizer 1.3, gltfpack) in scripts/node-bench" >&2
    (cd scripts/node-bench && npm ci --no-audit --no-fund --loglevel=error) || { echo "bench.sh: npm ci failed" >&2; exit 1; }
fi

checkflag=()
[ $check = 1 ] && checkflag=(--check)
# A few inputs for the benches that take a folder: read_bench reads every mesh under it.
quick_dir="$log_dir/quick_meshes"
if [ $quick = 1 ]; then
    rm -rf "$quick_dir" && mkdir -p "$quick_dir"
    for f in bunny_zipper.ply lucy100k.ply fandisk.obj rocker_arm.obj; do ln -s "$meshes/$f" "$quick_dir/$f"; done
fi

# Each entry: label, then the command's arguments (the bench's name first).
runs=()
add() { runs+=("$*"); }
if [ $quick = 1 ]; then
    add bake_bench --runs 1 --bar-only
    add bake_stages_bench --runs 1 --from-chain "$meshes/lucy100k.ply"
    add batch_bench --only bunny_zipper.ply,lucy100k.ply,fandisk.obj,rocker_arm.obj
    add codec_bench --runs 3 "$meshes" bunny_zipper.ply lucy100k.ply
    add collapse_bench --runs 1 "$meshes/lucy100k.ply"
    add distance_bench lucy100k.ply --runs 1
    add multilevel_bench --ratios 0.1 bunny_zipper.ply
    add pack_size_bench "$meshes/bunny_zipper.ply" "$meshes/lucy100k.ply" "$meshes/rocker_arm.obj"
    add pfrep_bench --quick
    add read_bench "$quick_dir"
    add repair_bench "$meshes" bunny_zipper.ply lucy100k.ply
    add runtime_bench --frames 50
    add simplify_bench bunny_zipper.ply lucy100k.ply
    add simplify_bench --speed-only --runs 1 dragon_poisson.ply
    add cluster_bench --mesh "$meshes/igea.ply" --frames 50
    add ooc_bench --triangles 2000000 --memory-limit 256
    add scripts/bench-textured.sh "$meshes/spot.obj"
    add scripts/bench-merge.sh "$build_dir"
else
    add bake_bench --runs 3 --bar-only
    add bake_stages_bench --runs 3 --from-chain "$meshes/dragon_poisson.ply"
    add batch_bench
    add codec_bench
    add collapse_bench --runs 3 "$meshes/dragon_poisson.ply"
    add distance_bench
    add multilevel_bench
    add pack_size_bench
    add pfrep_bench
    add read_bench
    add repair_bench
    add runtime_bench
    add simplify_bench
    add cluster_bench
    add ooc_bench
    add scripts/bench-textured.sh
    add scripts/bench-merge.sh "$build_dir"
fi

summary="$log_dir/summary.txt"
: > "$summary"
failed_runs=()
start_all=$(date +%s)
n=0
for entry in "${runs[@]}"; do
    # shellcheck disable=SC2206 # entries are space-separated words without spaces of their own
    words=($entry)
    name=${words[0]}
    # The benches whose anchor is a command-line tool are scripts (scripts/bench-*.sh); the rest are
    # programs of tests/benchmarks.
    program="$bin/$name"
    if [[ $name == scripts/* ]]; then
        program=$name
        name=$(basename "$name" .sh)
    fi
    wanted "$name" || continue
    n=$((n + 1))
    log="$log_dir/$n-$name.log"
    echo "== $entry" | sed "s|$meshes|MESHES|g"
    start=$(date +%s)
    BUILD_DIR="$build_dir" "$program" "${words[@]:1}" "${checkflag[@]}" > "$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    grep -E '^(BAR|NOBAR)\|' "$log" | sed "s/^/$n|/" >> "$summary"
    if ! grep -qE '^(BAR|NOBAR)\|' "$log"; then
        failed_runs+=("$name (rc $rc, no bar printed; see $log)")
    elif [ $rc -ne 0 ] && { [ $check = 0 ] || ! grep -qE '^BAR\|.*\|NOT met$' "$log"; }; then
        # Without --check a bench exits non-zero only on an error; with it, also on a bar not met.
        failed_runs+=("$name (exit $rc; see $log)")
    fi
    echo "   exit $rc after ${secs} s; log $log"
done
total=$(( $(date +%s) - start_all ))

echo
echo "## Bars ($( [ $quick = 1 ] && echo quick || echo full ) run, $(date -u '+%Y-%m-%d %H:%M UTC'), ${total} s, load average $(cut -d' ' -f1-3 /proc/loadavg))"
echo
echo "| bench | bar | ours | anchor | ratio | limit | met |"
echo "|---|---|---|---|---|---|---|"
awk -F'|' '$2 == "BAR" { printf "| %s | %s | %s | %s | %s | %s | %s |\n", $3, $4, $5, $6, $7, $8, $9 }
           $2 == "NOBAR" { printf "| %s | (no bar: %s) | | | | | |\n", $3, $4 }' "$summary"
met=$(awk -F'|' '$2 == "BAR" && $9 == "met"' "$summary" | wc -l)
all=$(awk -F'|' '$2 == "BAR"' "$summary" | wc -l)
echo
echo "$met of $all bars met"
status=0
if [ ${#failed_runs[@]} -gt 0 ]; then
    for f in "${failed_runs[@]}"; do echo "bench.sh: did not run to the end: $f" >&2; done
    status=1
fi
if [ $check = 1 ] && [ "$met" -ne "$all" ]; then
    echo "bench.sh: $((all - met)) bar(s) not met" >&2
    status=1
fi
exit $status
