#!/usr/bin/env python3
"""Regenerates tests/fuzz/seeds/cache/ (usage: make_cache_seeds.py LODBAKE_CLI; deterministic): the
entry and side-file list `lodbake bake --cache-dir` stores for a small OBJ with a material, and
damaged copies of each (cut short, one bit flipped, a section size that lies, a garbled list).
FuzzReplay.cache replays them and scripts/fuzz-seeds.sh seeds the cache fuzz target with them."""
import glob, os, subprocess, sys, tempfile

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "cache")
OBJ = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 0.5\nusemtl paint\n" \
      "f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 4 3\nf 1 3 2\n"
MTL = "newmtl paint\nKd 0.8 0.5 0.2\n"

with tempfile.TemporaryDirectory() as tmp:
    open(os.path.join(tmp, "box.obj"), "w").write(OBJ)
    open(os.path.join(tmp, "box.mtl"), "w").write(MTL)
    subprocess.run([sys.argv[1], "bake", os.path.join(tmp, "box.obj"), "-o", os.path.join(tmp, "box.glb"),
                    "--levels", "0.5", "--cache-dir", os.path.join(tmp, "cache"), "--quiet"], check=True)
    entry = open(glob.glob(os.path.join(tmp, "cache", "v2", "packs", "*.bin"))[0], "rb").read()
    deps = open(glob.glob(os.path.join(tmp, "cache", "v2", "deps", "*.txt"))[0], "rb").read()

head_end = entry.index(b"\n", len(b"lodbake-cache 2\n"))
flipped = bytearray(entry)
flipped[len(entry) - 40] ^= 0x04
sizes = bytearray(entry)
sizes[head_end - 18] = ord("0") if sizes[head_end - 18] == ord("9") else sizes[head_end - 18] + 1
garbled_deps = bytearray(deps)
garbled_deps[deps.index(b"\n", deps.index(b"input")) + 1] ^= 0x20
seeds = {
    "entry.bin": entry,
    "entry_cut_in_half.bin": entry[:len(entry) // 2],
    "entry_header_only.bin": entry[:head_end + 1],
    "entry_flipped_bit.bin": bytes(flipped),
    "entry_size_lies.bin": bytes(sizes),
    "deps.txt": deps,
    "deps_cut.txt": deps[:len(deps) // 2],
    "deps_garbled_path.txt": bytes(garbled_deps),
}
os.makedirs(OUT, exist_ok=True)
for old in os.listdir(OUT):
    os.remove(os.path.join(OUT, old))
for name, data in seeds.items():
    open(os.path.join(OUT, name), "wb").write(data)
print("%d cache seeds written to %s" % (len(seeds), OUT))
