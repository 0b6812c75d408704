#!/usr/bin/env python3
"""Regenerates the malformed PFRep (.lbp) corpus in this folder from a valid blob of a tetrahedron
written by `lodbake pfrep` in format 2 and in format 3 (usage: make_corpus.py LODBAKE_CLI; deterministic)."""
import os, struct, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TET = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"

with tempfile.TemporaryDirectory() as tmp:
    off = os.path.join(tmp, "tet.off")
    open(off, "w").write(TET)
    subprocess.run([sys.argv[1], "pfrep", off, "-o", os.path.join(tmp, "tet.lbp"), "--format", "2"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    good = open(os.path.join(tmp, "tet.lbp"), "rb").read()
    subprocess.run([sys.argv[1], "pfrep", off, "-o", os.path.join(tmp, "tet3.lbp")], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    good3 = open(os.path.join(tmp, "tet3.lbp"), "rb").read()

cases = {
    "empty.lbp": b"",
    "bad_magic.lbp": b"XFR1" + good[4:],
    "truncated_header.lbp": good[:30],
    "truncated_body.lbp": good[:-3],
    "trailing_bytes.lbp": good + b"\0\0\0\0",
    "unknown_version.lbp": good[:4] + struct.pack("<I", 99) + good[8:],
    "huge_vertex_count.lbp": good[:8] + struct.pack("<I", 0xFFFFFFF0) + good[12:],
    # Format 3: the coded stream cut, a byte of the stream changed, the slot total lying, a
    # decoded size below the directory.
    "f3_truncated_stream.lbp": good3[:-2],
    "f3_stream_byte_changed.lbp": good3[:70] + bytes([good3[70] ^ 0x40]) + good3[71:],
    "f3_slot_count_lies.lbp": good3[:56] + struct.pack("<I", struct.unpack("<I", good3[56:60])[0] + 1) + good3[60:],
    "f3_decoded_size_too_small.lbp": good3[:52] + struct.pack("<I", 8) + good3[56:],
}
for name, data in cases.items():
    open(os.path.join(HERE, name), "wb").write(data)
