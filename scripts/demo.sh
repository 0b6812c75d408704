#!/usr/bin/env bash
# One command from a fresh Debian machine to a baked sample: install the dependencies (the same
# script setup-and-test.sh uses), build lodbake and loddump in Release, run the bundled sample scan
# (assets/samples/rock_scan, made by lodbake_scansim) through the pipeline into build/demo/, and show
# what came out (one view converted; the whole set baked into build/demo/rock.glb, shown by loddump).
#
# usage: scripts/demo.sh [--no-install] [VIEW]
#   --no-install  skip scripts/install-deps.sh (the dependencies are already there)
#   VIEW          which view of the sample to use (default rock_000; see assets/samples/rock_scan)
# environment: LODBAKE_BUILD_DIR (default build), the build tree shared with setup-and-test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

say() { printf '\n==> %s\n' "$*"; }
die() {
    printf 'demo: error: %s\n' "$*" >&2
    exit 1
}
# Echoes a command, runs it, and stops the demo with a clear message if it fails.
run() {
    printf '$ %s\n' "$*"
    local rc=0
    "$@" || rc=$?
    if ((rc != 0)); then die "'$*' failed with exit code $rc"; fi
}

install=1
view=rock_000
while (($#)); do
    case "$1" in
    --no-install) install=0 ;;
    -h | --help)
        sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'
        exit 0
        ;;
    -*) die "unknown option '$1' (see scripts/demo.sh --help)" ;;
    *) view=$1 ;;
    esac
    shift
done

build_dir=${LODBAKE_BUILD_DIR:-build}
demo_dir=$build_dir/demo
sample_dir=assets/samples/rock_scan
input=$sample_dir/$view.ply
if [ ! -f "$input" ]; then
    views=()
    for f in "$sample_dir"/*.ply; do views+=("$(basename "$f" .ply)"); done
    die "no sample view '$view': $input does not exist (views: ${views[*]})"
fi

if ((install)); then
    say "installing dependencies (scripts/install-deps.sh)"
    run scripts/install-deps.sh
fi

say "configuring and building lodbake and loddump (Release, in $build_dir)"
jobs=$(nproc 2>/dev/null || echo 2)
# Same configuration as setup-and-test.sh, so both scripts share one build tree.
run cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DLODBAKE_WERROR=ON
run cmake --build "$build_dir" --parallel "$jobs" --target lodbake loddump
lodbake=$build_dir/baker/lodbake
loddump=$build_dir/runtime/loddump
[ -x "$lodbake" ] || die "the build did not produce $lodbake"
[ -x "$loddump" ] || die "the build did not produce $loddump"

rm -rf -- "$demo_dir"
mkdir -p -- "$demo_dir"

# The pipeline. Each stage reads "$current" (the latest file) and, if it writes a file, points
# "$current" at it. To add a step (repair, simplify, bake a pack and show it with loddump), write a
# stage_<name> function and add <name> to `stages`.
current=$input
stage_inspect() {
    say "the input: $current (one view of the sample scan, a Stanford range grid)"
    run "$lodbake" info "$current"
}
stage_convert() {
    local out=$demo_dir/$view.glb
    say "converting to glTF binary: $out"
    run "$lodbake" convert "$current" -o "$out"
    current=$out
}
stage_bake() {
    # The whole scan set (every view aligned by rock.conf), not just one view: repair, then the six
    # overlapping views merged into one surface (--merge auto: screened Poisson, docs/bake.md), then
    # the LOD chain, texture levels and the pack.
    local out=$demo_dir/rock.glb
    say "baking the whole scan set into one LOD pack: $out (desktop preset, views merged)"
    run "$lodbake" bake "$sample_dir/rock.conf" --preset configs/desktop.json --merge auto -o "$out" \
        --report "$demo_dir/rock_report.json"
    current=$out
}
stage_dump() {
    say "the pack as the runtime sees it (loddump: LOD table, checks, meshes; every level drawn in $demo_dir/rock_levels.png)"
    run "$loddump" "$current" --render "$demo_dir/rock_levels.png"
}
stages=(inspect convert bake dump)

for stage in "${stages[@]}"; do
    "stage_$stage"
done

say "what the demo produced: $current"
run "$lodbake" info "$current"

say "files in $demo_dir"
find "$demo_dir" -maxdepth 1 -type f -printf '%f\t%s\n' | sort | while IFS=$'\t' read -r name size; do
    printf '  %-32s %10s bytes\n' "$name" "$size"
done
printf '\ndemo finished: the baked output is in %s\n' "$demo_dir"
