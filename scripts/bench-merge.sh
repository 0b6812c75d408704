#!/usr/bin/env bash
# The bars of the range-scan merge (docs/benchmarks.md, "Range-scan merge"), printed as
#   BAR|merge_bench|bar|ours|anchor|ratio|limit|met
# lines (the format of tests/benchmarks/bench_bar.h):
#   - the bundled rock (scripts/demo.sh's bake: rock.conf, desktop preset, merge auto): level 5
#     Hausdorff error relative to the diagonal, the plinth present at every level (the largest
#     distance from the input's plinth samples to the level), one component at every level;
#   - dragon_stand_merged.ply: `lodbake merge` wall time, CPU time and peak memory, the merged
#     surface's 95th-percentile sample distance; each level of a desktop-preset bake with
#     --merge auto against the same bake of dragon_poisson.ply (--merge off): mean surface distance
#     to the input scans with ../shared/eval/meshdist.py, ours / anchor.
#
# usage: scripts/bench-merge.sh [--check] [BUILD_DIR]   (default build; needs ../shared/meshes and
# ../shared/eval, and Debian's python3 with python3-open3d). --check: exit 1 when a bar is not met.
set -uo pipefail
cd "$(dirname "$0")/.."
check=0
build_dir=build
for a in "$@"; do
    case "$a" in
        --check) check=1 ;;
        *) build_dir=$a ;;
    esac
done
lodbake=$build_dir/baker/lodbake
shared=$(cd .. && pwd)/shared
py=/usr/bin/python3
[ -x "$py" ] || py=python3
[ -x "$lodbake" ] || { echo "bench-merge.sh: $lodbake: not built" >&2; exit 1; }
[ -d "$shared/meshes" ] || { echo "bench-merge.sh: $shared/meshes: missing" >&2; exit 1; }
out=$build_dir/bench_logs/merge
mkdir -p "$out"

rm -f "$out/bars.txt"
bar() { bar_line "$@" | tee -a "$out/bars.txt"; }
bar_line() { # name ours anchor limit direction(le|ge) [on_ratio]
    "$py" - "$@" <<'EOF'
import math, sys
name, ours, anchor, limit, direction = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
on_ratio = len(sys.argv) > 6
ratio = ours / anchor if anchor > 0 else float('nan')
value = ratio if on_ratio else ours
met = math.isfinite(value) and (value <= limit if direction == 'le' else value >= limit)
fmt = lambda v: '-' if math.isnan(v) else '%.4g' % v
print('BAR|merge_bench|%s|%s|%s|%s|%s %s %.4g|%s' % (name, fmt(ours), fmt(anchor), fmt(ratio),
      'ratio' if on_ratio else 'ours', '<=' if direction == 'le' else '>=', limit, 'met' if met else 'NOT met'))
EOF
}

# The rock, as the demo bakes it.
"$lodbake" bake assets/samples/rock_scan/rock.conf --preset configs/desktop.json -o "$out/rock.glb" \
    --report "$out/rock_report.json" --quiet || { echo "bench-merge.sh: the rock bake failed" >&2; exit 1; }
"$py" - "$out/rock.glb" "$out/rock_report.json" "$shared/eval" assets/samples/rock_scan/rock.conf "$lodbake" \
    > "$out/rock.txt" <<'EOF' || { echo "bench-merge.sh: measuring the rock failed" >&2; exit 1; }
import json, subprocess, sys, os, tempfile
import numpy as np, open3d as o3d
glb, report, evaldir, conf, lodbake = sys.argv[1:6]
sys.path.insert(0, evaldir)
from meshio import read_mesh
tmp = tempfile.mkdtemp()
subprocess.run([lodbake, 'convert', conf, '-o', tmp + '/input.ply'], check=True, capture_output=True)
V, F = read_mesh(tmp + '/input.ply')
used = np.unique(F)
P = V[used]
diag = float(np.linalg.norm(P.max(0) - P.min(0)))
plinth = P[P[:, 1] < 0.015]  # the plinth's wall below the rock (scansim: base_height 0.02, y up)
levels = json.load(open(report))['assets'][0]['levels']
worst_plinth, most_components = 0.0, 0
for l in range(len(levels)):
    LV, LF = read_mesh(glb, l)
    s = o3d.t.geometry.RaycastingScene()
    s.add_triangles(o3d.core.Tensor(LV.astype(np.float32)), o3d.core.Tensor(LF.astype(np.uint32)))
    d = s.compute_distance(o3d.core.Tensor(plinth.astype(np.float32))).numpy()
    worst_plinth = max(worst_plinth, float(d.max()) / diag)
    m = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(LV.astype(np.float64)), o3d.utility.Vector3iVector(LF))
    m = m.merge_close_vertices(0.0)
    clusters, _, _ = m.cluster_connected_triangles()
    most_components = max(most_components, len(set(np.asarray(clusters).tolist())))
print(levels[-1]['hausdorffError'] / diag, worst_plinth, most_components, len(plinth), diag)
EOF
read -r rock_l5 rock_plinth rock_components _ rock_diag < "$out/rock.txt"
# For scale: the same bake with the views left as sheets.
"$lodbake" bake assets/samples/rock_scan/rock.conf --preset configs/desktop.json --merge off -o "$out/rock_sheets.glb" \
    --report "$out/rock_sheets_report.json" --quiet 2>/dev/null || { echo "bench-merge.sh: the sheets bake failed" >&2; exit 1; }
rock_sheets=$("$py" -c "import json,sys; l=json.load(open(sys.argv[1]))['assets'][0]['levels'][-1]; print(l['hausdorffError'] / float(sys.argv[2]))" \
    "$out/rock_sheets_report.json" "$rock_diag")
bar rock_level5_hausdorff_rel_diag "$rock_l5" "$rock_sheets" 0.03 le
bar rock_plinth_max_sample_distance_rel_diag_every_level "$rock_plinth" nan 0.03 le
bar rock_components_every_level "$rock_components" nan 1 le

# The dragon: the merge alone (time, memory, accuracy), then the two bakes level by level.
dragon=$shared/meshes/dragon_stand_merged.ply
/usr/bin/time -f "%e %U %S %M" -o "$out/merge_time.txt" "$lodbake" merge "$dragon" -o "$out/dragon_merged.ply" \
    --json > "$out/merge.json" || { echo "bench-merge.sh: the dragon merge failed" >&2; exit 1; }
read -r wall user sys rss_kb < "$out/merge_time.txt"
p95=$("$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['p95_distance_rel'])" "$out/merge.json")
cpu=$("$py" -c "print($user + $sys)")
bar dragon_merge_wall_s "$wall" nan 60 le
bar dragon_merge_cpu_s "$cpu" nan 60 le
bar dragon_merge_peak_gib "$("$py" -c "print($rss_kb / 1048576)")" nan 2 le
bar dragon_merged_p95_sample_distance_rel_diag "$p95" nan 0.001 le

"$lodbake" bake "$dragon" --preset configs/desktop.json --merge auto -o "$out/dragon_merged.glb" --quiet ||
    { echo "bench-merge.sh: the dragon bake failed" >&2; exit 1; }
"$lodbake" bake "$shared/meshes/dragon_poisson.ply" --preset configs/desktop.json --merge off \
    -o "$out/dragon_poisson.glb" --quiet || { echo "bench-merge.sh: the dragon_poisson bake failed" >&2; exit 1; }
rm -f "$out/dragon_levels.txt"
levels=$("$py" -c "
import sys; sys.path.insert(0, sys.argv[1]); import json, struct
b = open(sys.argv[2], 'rb').read(); n = struct.unpack_from('<I', b, 12)[0]
print(len(json.loads(b[20:20 + n])['meshes']))" "$shared/eval" "$out/dragon_merged.glb")
for ((l = 0; l < levels; ++l)); do
    ours=$("$py" "$shared/eval/meshdist.py" "$dragon" "$out/dragon_merged.glb" --mesh $l --json)
    anchor=$("$py" "$shared/eval/meshdist.py" "$dragon" "$out/dragon_poisson.glb" --mesh $l --json)
    echo "level $l ours $ours anchor $anchor" >> "$out/dragon_levels.txt"
    m_ours=$("$py" -c "import json,sys; print(json.loads(sys.argv[1])['mean'])" "$ours")
    m_anchor=$("$py" -c "import json,sys; print(json.loads(sys.argv[1])['mean'])" "$anchor")
    bar "dragon_level${l}_mean_distance_to_scans_vs_poisson" "$m_ours" "$m_anchor" 1.5 le ratio
done
if [ $check = 1 ] && grep -q "NOT met" "$out/bars.txt"; then exit 1; fi
exit 0
