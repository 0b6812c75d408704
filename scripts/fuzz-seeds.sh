#!/usr/bin/env bash
# Builds the seed corpora of every fuzz target (scripts/fuzz.sh) into OUT_DIR/<target>/:
# the malformed corpus and small test files of the repository, tiny meshes generated here, and
# derived files (pack, PFRep blob, .lbm, Draco GLB) made with a lodbake CLI. Nothing is copied into
# the repository; big shared meshes are only used, when present, to make small derived seeds.
# usage: scripts/fuzz-seeds.sh OUT_DIR LODBAKE_CLI
set -euo pipefail
out=$1
lodbake=$2
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for t in gltf obj off ply preset conf manifest cache stream lod pack pfrep valence meshopt cluster jobs; do mkdir -p "$out/$t"; done

cp "$root"/tests/malformed/ply/*.ply "$out/ply/"
cp "$root"/tests/malformed/off/*.off "$out/off/"
cp "$root"/tests/malformed/obj/*.obj "$out/obj/"
for m in "$root"/tests/malformed/obj/*.mtl; do
    printf 'mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl a\nf 1/1 2/1 3/1\n#lodbake-fuzz-mtl\n' \
        | cat - "$m" >"$out/obj/mtl_$(basename "$m" .mtl).obj"
done
cp "$root"/tests/malformed/gltf/*.gltf "$root"/tests/malformed/gltf/*.glb "$out/gltf/"
cp "$root"/configs/*.json "$out/preset/"
# Every corpus folder named here must exist and hold files (a missing one fails the script, so a
# renamed folder cannot shrink the seeds silently).
cp "$root"/tests/malformed/preset/*.json "$out/preset/"
cp "$root"/tests/malformed/lbm/*.lbm "$out/valence/"
cp "$root"/tests/fuzz/seeds/meshopt/* "$out/meshopt/"
cp "$root"/tests/fuzz/seeds/cluster/* "$out/cluster/"
cp "$root"/tests/malformed/lbp/*.lbp "$out/pfrep/"
cp "$root"/tests/malformed/pack/*.glb "$out/pack/"
cp "$root"/tests/malformed/conf/*.conf "$out/conf/"
cp "$root"/tests/malformed/manifest/*.json "$out/manifest/"
cp "$root"/tests/fuzz/seeds/cache/* "$out/cache/"
cp "$root"/tests/fuzz/seeds/jobs/* "$out/jobs/"
for dir in "$root"/tests/fuzz/regressions/*/; do
    t=$(basename "$dir")
    if [ ! -d "$out/$t" ]; then
        echo "fuzz-seeds.sh: tests/fuzz/regressions/$t is not a fuzz target" >&2
        exit 1
    fi
    cp "$dir"* "$out/$t/"
done

# Tiny generated meshes: a tetrahedron with colours, and a textured quad with a material.
cat >"$tmp/tet.off" <<'OFF'
COFF
4 4 0
0 0 0 255 0 0 255
1 0 0 0 255 0 255
0 1 0 0 0 255 255
0 0 1 255 255 255 255
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
OFF
cat >"$tmp/quad.obj" <<'OBJ'
mtllib quad.mtl
o quad
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0.1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl paint
f 1/1/1 2/2/1 3/3/1 4/4/1
g second
usemtl paint
f -4/-4/-1 -2/-2/-1 -1/-1/-1
OBJ
cat >"$tmp/quad.mtl" <<'MTL'
newmtl paint
Kd 0.8 0.7 0.6
d 1
Ns 10
map_Kd tex.png
map_Bump -bm 0.5 nrm.png
MTL
cp "$tmp/tet.off" "$out/off/tet.off"
cat "$tmp/quad.obj" <(printf '\n#lodbake-fuzz-mtl\n') "$tmp/quad.mtl" >"$out/obj/quad_with_mtl.obj"
printf 'fake png bytes' >"$tmp/tex.png"; cp "$tmp/tex.png" "$tmp/nrm.png"
"$lodbake" convert "$tmp/tet.off" -o "$out/ply/tet_binary.ply" >/dev/null
"$lodbake" convert "$tmp/tet.off" -o "$out/ply/tet_ascii.ply" --ascii >/dev/null
"$lodbake" convert "$tmp/tet.off" -o "$out/gltf/tet.glb" >/dev/null
"$lodbake" convert "$tmp/quad.obj" -o "$out/gltf/quad.glb" >/dev/null
"$lodbake" convert "$tmp/quad.obj" -o "$tmp/quad.gltf" >/dev/null
cp "$tmp/quad.gltf" "$out/gltf/quad_external_bin.gltf"

# A small scan: the rock sample, simplified to a few hundred triangles, in every format.
"$lodbake" simplify "$root/assets/samples/rock_scan/rock_000.ply" -o "$tmp/rock.ply" --ratio 0.05 >/dev/null
for f in ply off obj glb; do "$lodbake" convert "$tmp/rock.ply" -o "$tmp/rock_small.$f" >/dev/null; done
cp "$tmp/rock_small.ply" "$out/ply/"; cp "$tmp/rock_small.off" "$out/off/"; cp "$tmp/rock_small.obj" "$out/obj/"
cp "$tmp/rock_small.glb" "$out/gltf/"
# Draco: the rock compressed by Draco's encoder, wrapped in a GLB with KHR_draco_mesh_compression.
draco_glb() { # MESH.ply OUT.glb
    draco_encoder -i "$1" -o "$tmp/d.drc" -qp 11 >/dev/null
    draco_decoder -i "$tmp/d.drc" -o "$tmp/d.ply" >/dev/null
    local v f
    v=$(grep -a -m1 '^element vertex' "$tmp/d.ply" | awk '{print $3}')
    f=$(grep -a -m1 '^element face' "$tmp/d.ply" | awk '{print $3}')
    python3 "$root/scripts/fuzz_draco_glb.py" "$tmp/d.drc" "$2" "$v" "$f"
}
if command -v draco_encoder >/dev/null && command -v draco_decoder >/dev/null; then
    "$lodbake" convert "$tmp/tet.off" -o "$tmp/tet.ply" >/dev/null
    draco_glb "$tmp/tet.ply" "$out/gltf/tet_draco.glb"
    draco_glb "$tmp/rock.ply" "$out/gltf/rock_draco.glb"
fi

# Scan sets naming the two scans the conf target writes next to its input (scan.ply, scan.off),
# with every kind of line it reads.
printf 'camera 0 0 0 0 0 0 1\nmesh calib.ply 0 0 0 0 0 0 1\nbmesh scan.ply 0 0 0 0 0 0 1\nbmesh scan.ply 0.5 -1 2 0 0 0.7071068 0.7071068\n' \
    >"$out/conf/two_scans.conf"
printf 'bmesh scan.off 1e-3 2 3 0.1 0.2 0.3 0.9\n' >"$out/conf/one_off_scan.conf"
# Manifests: the documented example shape, with presets and per-asset settings (the fuzz target
# finds no preset file, so one seed has none and reaches the assets).
cat >"$out/manifest/good.json" <<'JSON'
{"version": 1, "preset": "presets/light.json", "output_dir": "packs", "assets": [
  {"input": "meshes/rock.ply"},
  {"inputs": ["a.obj", "b.obj"], "output": "ab.glb", "settings": {"lod_ratios": [0.3], "textures": {"enabled": false}}},
  {"input": "c.glb", "output": "sub/c.glb", "settings": {"pixel_threshold": 3}}]}
JSON
cat >"$out/manifest/no_preset.json" <<'JSON'
{"version": 1, "output_dir": "packs", "assets": [{"input": "rock.ply"},
  {"inputs": ["a.obj", "b.glb"], "output": "x/ab.glb", "settings": {"lod_ratios": [0.5, 0.1], "pixel_threshold": 2}}]}
JSON
# Cache files: the entry and side-file list a real bake stores (the quad's MTL and textures make a
# list with side files).
"$lodbake" bake "$tmp/quad.obj" -o "$tmp/quad_cached.glb" --levels 0.5 --cache-dir "$tmp/cache" --quiet \
    --keep-unreadable-images # the fake PNG bytes stand in for any texture a cache entry lists
cp "$tmp"/cache/v2/packs/*.bin "$tmp"/cache/v2/deps/*.txt "$out/cache/"

# Runtime inputs: a baked pack, PFRep blobs, .lbm streams.
"$lodbake" bake "$tmp/tet.off" -o "$out/pack/tet_pack.glb" --levels 1 >/dev/null 2>&1 || true
"$lodbake" bake "$tmp/rock.ply" -o "$out/pack/rock_pack.glb" --levels 0.5,0.2 >/dev/null
# The --web form (EXT_meshopt_compression views, fallback buffer) for the pack, lod and glTF readers.
"$lodbake" bake "$tmp/rock.ply" -o "$out/pack/rock_web.glb" --levels 0.5,0.2 --web >/dev/null
cp "$out/pack/rock_web.glb" "$out/gltf/rock_web.glb"
"$lodbake" pfrep "$tmp/tet.off" -o "$out/pfrep/tet.lbp" >/dev/null
"$lodbake" pfrep "$tmp/rock.ply" -o "$out/pfrep/rock.lbp" >/dev/null
"$lodbake" pfrep "$tmp/tet.off" -o "$out/pfrep/tet_f2.lbp" --format 2 >/dev/null
"$lodbake" pfrep "$tmp/rock.ply" -o "$out/pfrep/rock_f2.lbp" --format 2 >/dev/null
"$lodbake" encode "$tmp/tet.off" -o "$out/valence/tet.lbm" --bits 10 >/dev/null
"$lodbake" encode "$tmp/rock.ply" -o "$out/valence/rock.lbm" --bits 8 >/dev/null
# Attribute paths of the .lbm decoder: the tetrahedron's colours (above), the quad's UVs and tangents.
"$lodbake" encode "$tmp/quad.obj" -o "$out/valence/quad_uv.lbm" --uv-bits 10 >/dev/null
"$lodbake" encode "$out/gltf/quad.glb" -o "$out/valence/quad_glb.lbm" >/dev/null
cp "$out"/gltf/*.glb "$out/pack/" 2>/dev/null || true
# The LOD runtime (models, streaming) reads the same packs.
cp "$out"/pack/* "$out/lod/"
# The streaming readers read every PLY and OBJ seed, and the small generated scans.
cp "$out"/ply/* "$out"/obj/* "$root"/tests/fuzz/seeds/stream/* "$out/stream/"
