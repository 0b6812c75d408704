#!/usr/bin/env python3
"""Regenerates the malformed .lbm corpus in this folder. Only header-level damage (magic, version,
truncation, emptiness), so the cases hold while the stream layout behind the header evolves
(usage: make_corpus.py; deterministic)."""
import os, struct

HERE = os.path.dirname(os.path.abspath(__file__))
cases = {
    "empty.lbm": b"",
    "bad_magic.lbm": b"PK\x03\x04" + bytes(60),
    "magic_only.lbm": b"LBBM",
    "short_header.lbm": b"LBBM" + struct.pack("<III", 1, 4, 4),
    "unknown_version.lbm": b"LBBM" + struct.pack("<IIII", 0xFFFF, 4, 4, 10) + bytes(48),
    "text_file.lbm": b"this is not a compressed mesh\n" * 4,
}
for name, data in cases.items():
    open(os.path.join(HERE, name), "wb").write(data)
