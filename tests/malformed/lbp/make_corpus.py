#!/usr/bin/env python3
"""Regenerates the malformed PFRep (.lbp) corpus in this folder from a valid blob of a tetrahedron
written by `lodbake pfrep` (usage: make_corpus.py LODBAKE_CLI; deterministic)."""
import os, struct, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TET = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"

with tempfile.TemporaryDirectory() as tmp:
    off = os.path.join(tmp, "tet.off")
    open(off, "w").write(TET)
    subprocess.run([sys.argv[1], "pfrep", off, "-o", os.path.join(tmp, "tet.lbp")], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    good = open(os.path.join(tmp, "tet.lbp"), "rb").read()

cases = {
    "empty.lbp": b"",
    "bad_magic.lbp": b"XFR1" + good[4:],
    "truncated_header.lbp": good[:30],
    "truncated_body.lbp": good[:-3],
    "trailing_bytes.lbp": good + b"\0\0\0\0",
    "unknown_version.lbp": good[:4] + struct.pack("<I", 99) + good[8:],
    "huge_vertex_count.lbp": good[:8] + struct.pack("<I", 0xFFFFFFF0) + good[12:],
}
for name, data in cases.items():
    open(os.path.join(HERE, name), "wb").write(data)
