#!/usr/bin/env python3
"""Regenerates the malformed bake-preset corpus in this folder (run from anywhere; deterministic).
Each case is baked with `lodbake bake tet.off --preset CASE` (tet.off: a valid tetrahedron)."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
cases = {
    "empty.json": "",
    "not_json.json": "version = 1\n",
    "trailing_garbage.json": '{"version": 1} x\n',
    "array_root.json": "[1, 2, 3]\n",
    "missing_version.json": '{"lod_ratios": [0.5]}\n',
    "version_2.json": '{"version": 2}\n',
    "unknown_key.json": '{"version": 1, "lod_ratio": [0.5]}\n',
    "unknown_texture_key.json": '{"version": 1, "textures": {"max_px": 10}}\n',
    "ratio_zero.json": '{"version": 1, "lod_ratios": [0.5, 0]}\n',
    "ratio_string.json": '{"version": 1, "lod_ratios": ["half"]}\n',
    "too_many_ratios.json": '{"version": 1, "lod_ratios": [' + ", ".join(["0.5"] * 17) + "]}\n",
    "huge_number.json": '{"version": 1, "pixel_threshold": 1e999}\n',
    "fractional_samples.json": '{"version": 1, "error_samples": 1000.5}\n',
    "negative_threads.json": '{"version": 1, "threads": -1}\n',
    "min_above_max.json": '{"version": 1, "textures": {"min_size_px": 512, "max_size_px": 256}}\n',
    "deep_nesting.json": '{"version": 1, "textures": ' + "[" * 100 + "]" * 100 + "}\n",
    "deep_nesting_unclosed.json": "[" * 1000,
    "invalid_utf8.json": '{"version": 1, "\xff": 1}\n',
    "compact_string.json": '{"version": 1, "compact": "yes"}\n',
}
for name, text in cases.items():
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(text.encode("latin-1"))
with open(os.path.join(HERE, "tet.off"), "w") as f:
    f.write("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
