#!/usr/bin/env python3
"""glb_diff.py A.glb B.glb: names where two GLB packs differ.

Prints one line per difference: the JSON chunk (first differing byte), each accessor whose bytes
differ (mesh, primitive, semantic, byte range in BIN, differing elements, largest float difference)
and each buffer view not read through an accessor (streams, images, extension blobs) whose bytes
differ. Exit status: 0 when the files are byte-identical, 1 when they differ, 2 on unreadable input.
"""
import json
import struct
import sys

COMPONENT = {5120: ("b", 1), 5121: ("B", 1), 5122: ("h", 2), 5123: ("H", 2), 5125: ("I", 4), 5126: ("f", 4)}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def read_glb(path):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 20 or data[:4] != b"glTF":
        raise ValueError(f"{path}: not a GLB file")
    chunks = []
    pos = 12
    while pos + 8 <= len(data):
        length, kind = struct.unpack_from("<II", data, pos)
        chunks.append((kind, data[pos + 8:pos + 8 + length]))
        pos += 8 + length
    text = next((c for k, c in chunks if k == 0x4E4F534A), None)
    binary = next((c for k, c in chunks if k == 0x004E4942), b"")
    if text is None:
        raise ValueError(f"{path}: no JSON chunk")
    return data, text, binary


def accessor_names(gltf):
    names = {}
    for m, mesh in enumerate(gltf.get("meshes", [])):
        for p, prim in enumerate(mesh.get("primitives", [])):
            where = f"mesh {m} \"{mesh.get('name', '')}\" primitive {p}"
            for semantic, acc in prim.get("attributes", {}).items():
                names[acc] = f"{where} {semantic}"
            if "indices" in prim:
                names[prim["indices"]] = f"{where} indices"
    return names


def accessor_span(gltf, acc):
    view = gltf["bufferViews"][acc["bufferView"]]
    fmt, size = COMPONENT[acc["componentType"]]
    width = WIDTH[acc["type"]]
    stride = view.get("byteStride", 0) or size * width
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    end = start + stride * (acc["count"] - 1) + size * width if acc["count"] else start
    return start, end, fmt, size, width, stride


def compare_accessor(gltf, index, acc, bin_a, bin_b, name):
    start, end, fmt, size, width, stride = accessor_span(gltf, acc)
    if bin_a[start:end] == bin_b[start:end]:
        return None
    first = next(i for i in range(start, end) if i >= len(bin_b) or bin_a[i] != bin_b[i])
    last = next(i for i in range(end - 1, start - 1, -1) if i >= len(bin_b) or bin_a[i] != bin_b[i])
    elements, worst = 0, 0.0
    for e in range(acc["count"]):
        o = start + e * stride
        a, b = bin_a[o:o + size * width], bin_b[o:o + size * width]
        if a != b:
            elements += 1
            if fmt == "f" and len(b) == len(a):
                va, vb = struct.unpack(f"<{width}f", a), struct.unpack(f"<{width}f", b)
                worst = max(worst, max(abs(x - y) for x, y in zip(va, vb)))
    detail = f", largest difference {worst:.3g}" if fmt == "f" else ""
    return (f"accessor {index} ({name}): BIN bytes [{first}, {last + 1}) differ, "
            f"{elements} of {acc['count']} elements{detail}")


def main():
    if len(sys.argv) != 3:
        print("usage: glb_diff.py A.glb B.glb", file=sys.stderr)
        return 2
    try:
        data_a, text_a, bin_a = read_glb(sys.argv[1])
        data_b, text_b, bin_b = read_glb(sys.argv[2])
        gltf = json.loads(text_a)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if data_a == data_b:
        return 0
    lines = []
    if text_a != text_b:
        first = next((i for i in range(min(len(text_a), len(text_b))) if text_a[i] != text_b[i]),
                     min(len(text_a), len(text_b)))
        lines.append(f"JSON chunk differs from byte {first} (lengths {len(text_a)} and {len(text_b)})")
    if len(bin_a) != len(bin_b):
        lines.append(f"BIN chunk lengths differ: {len(bin_a)} and {len(bin_b)}")
    names = accessor_names(gltf)
    covered = set()
    for i, acc in enumerate(gltf.get("accessors", [])):
        if "bufferView" not in acc:
            continue
        covered.add(acc["bufferView"])
        line = compare_accessor(gltf, i, acc, bin_a, bin_b, names.get(i, "unused"))
        if line:
            lines.append(line)
    for i, view in enumerate(gltf.get("bufferViews", [])):
        if i in covered:
            continue
        start = view.get("byteOffset", 0)
        end = start + view["byteLength"]
        if bin_a[start:end] != bin_b[start:end]:
            first = next(k for k in range(start, end) if k >= len(bin_b) or bin_a[k] != bin_b[k])
            lines.append(f"bufferView {i} (no accessor): BIN bytes [{first}, {end}) differ")
    if not lines:
        lines.append("files differ outside the JSON and BIN chunks")
    print("\n".join(lines))
    return 1


if __name__ == "__main__":
    sys.exit(main())
