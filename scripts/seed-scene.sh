#!/usr/bin/env bash
# The seed's test scene drawn through lodrt (docs/lodview.md): five shared scans (dragon_poisson,
# igea, lucy100k, nefertiti, bunny) baked with the desktop preset, 5x5 instances of them on a grid,
# a walk through the grid with lodview --headless at 1280x720, once with LOD and once with LOD0
# forced, the same camera path and frame count. Without a display it runs under xvfb-run (Mesa's
# llvmpipe on a machine without a GPU). The LOD run fails when a drawn level projects above 1 px.
# The last line reads
#   seed scene: LOD mean frame A ms, LOD0 mean frame B ms, speedup S        (S = B / A)
#
# usage: scripts/seed-scene.sh [--frames N] [--size WxH] [--check]
#   BUILD_DIR  build tree with baker/lodbake and runtime/lodview (default: build); builds nothing.
#   OUT_DIR    packs, reports (lod.json, lod0.json) and screenshots (default: BUILD_DIR/seed-scene).
#   --check    exit 1 unless the LOD mean frame is at most 0.25x the LOD0 one (the issue's bar).
# Packs are baked once through a content-hash cache in OUT_DIR/cache, so a rerun only renders.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${BUILD_DIR:-build}
out_dir=${OUT_DIR:-$build_dir/seed-scene}
meshes=../shared/meshes
frames=60
size=1280x720
check=0
while [ $# -gt 0 ]; do
    case "$1" in
        --frames) shift; frames=${1:?--frames needs a count} ;;
        --size) shift; size=${1:?--size needs WxH} ;;
        --check) check=1 ;;
        *) echo "usage: scripts/seed-scene.sh [--frames N] [--size WxH] [--check]" >&2; exit 2 ;;
    esac
    shift
done

lodbake=$build_dir/baker/lodbake
lodview=$build_dir/runtime/lodview
for tool in "$lodbake" "$lodview"; do
    [ -x "$tool" ] || { echo "seed-scene: $tool: not built (lodview needs libglfw3-dev and libepoxy-dev)" >&2; exit 1; }
done
inputs=("$meshes/dragon_poisson.ply" "$meshes/igea.ply" "$meshes/lucy100k.ply" "$meshes/nefertiti.obj"
        "$meshes/bunny_zipper.ply")
for f in "${inputs[@]}"; do
    [ -f "$f" ] || { echo "seed-scene: $f: missing (the shared scans live in ../shared/meshes)" >&2; exit 1; }
done

mkdir -p "$out_dir/packs"
"$lodbake" bake "${inputs[@]}" -o "$out_dir/packs/" --preset configs/desktop.json --cache-dir "$out_dir/cache" \
    --quiet
packs=()
for f in "${inputs[@]}"; do
    stem=$(basename "${f%.*}")
    packs+=("$out_dir/packs/$stem.glb")
done

run_view=("$lodview")
if [ -z "${DISPLAY:-}" ]; then
    command -v xvfb-run >/dev/null || { echo "seed-scene: no DISPLAY and no xvfb-run (Debian xvfb, xauth)" >&2; exit 1; }
    run_view=(xvfb-run -a -s "-screen 0 ${size}x24" "$lodview")
fi
common=("${packs[@]}" --headless --size "$size" --frames "$frames" --grid 5)
"${run_view[@]}" "${common[@]}" --mode lod --max-sse 1 --report "$out_dir/lod.json" \
    --screenshot "$out_dir/lod" --shots "0,$((frames / 3)),$((frames / 2))"
"${run_view[@]}" "${common[@]}" --mode lod0 --report "$out_dir/lod0.json" \
    --screenshot "$out_dir/lod0" --shots "$((frames / 3))"
"${run_view[@]}" "${common[@]}" --mode lod --colour-by-level --report "$out_dir/levels.json" \
    --screenshot "$out_dir/levels" --shots "$((frames / 3))" >/dev/null

python3 - "$out_dir/lod.json" "$out_dir/lod0.json" "$check" <<'EOF'
import json, sys
lod, lod0 = (json.load(open(p))["summary"] for p in sys.argv[1:3])
a, b = lod["mean_frame_ms"], lod0["mean_frame_ms"]
speedup = b / a if a > 0 else 0.0
print(f"seed scene: LOD mean triangles {lod['mean_triangles']:.0f}, LOD0 {lod0['mean_triangles']:.0f}; "
      f"LOD max drawn screen-space error {lod['max_sse_px']:.3f} px; "
      f"lodrt allocations beyond level reads {lod['lodrt_allocations_beyond_requests']}")
failed = sys.argv[3] == "1" and not a <= 0.25 * b
if failed:
    print(f"error: LOD mean frame {a:.2f} ms is above 0.25x the LOD0 mean frame {b:.2f} ms", file=sys.stderr)
print(f"seed scene: LOD mean frame {a:.2f} ms, LOD0 mean frame {b:.2f} ms, speedup {speedup:.2f}")
sys.exit(1 if failed else 0)
EOF
