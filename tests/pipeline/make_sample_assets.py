#!/usr/bin/env python3
"""Writes the small assets the CMake integration test bakes into OUT_DIR.

usage: make_sample_assets.py OUT_DIR

  crate.obj + crate.mtl + textures/crate.png    a UV-mapped sphere whose material has a texture
  barrel.obj + barrel.mtl + textures/barrel.png another one
  rock.ply                                      an untextured ASCII PLY
  light.json                                    a cheap bake preset (two levels, few error samples)
Deterministic: the same bytes on every run.
"""
import math
import os
import struct
import sys
import zlib


def png(path, size, rgb):
    rows = b"".join(b"\x00" + b"".join(bytes(((x * 16 + rgb[0]) % 256, (y * 16 + rgb[1]) % 256, rgb[2]))
                                         for x in range(size))
                    for y in range(size))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows, 9)))
        f.write(chunk(b"IEND", b""))


def sphere(rings, segments, radius, squash):
    """Latitude-longitude sphere: positions, uvs and triangles (1-based, shared index)."""
    verts, uvs, tris = [], [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            bump = 1.0 + 0.05 * math.sin(5 * phi) * math.sin(3 * theta)
            verts.append((radius * bump * math.sin(theta) * math.cos(phi), radius * squash * math.cos(theta),
                          radius * bump * math.sin(theta) * math.sin(phi)))
            uvs.append((s / segments, 1.0 - r / rings))
    for r in range(rings):
        for s in range(segments):
            a = r * (segments + 1) + s + 1
            b = a + segments + 1
            if r > 0:
                tris.append((a, a + 1, b))
            if r < rings - 1:
                tris.append((a + 1, b + 1, b))
    return verts, uvs, tris


def obj(out, name, squash, colour):
    verts, uvs, tris = sphere(24, 48, 1.0, squash)
    with open(os.path.join(out, name + ".obj"), "w", newline="\n") as f:
        f.write("mtllib %s.mtl\no %s\n" % (name, name))
        for v in verts:
            f.write("v %.6f %.6f %.6f\n" % v)
        for t in uvs:
            f.write("vt %.6f %.6f\n" % t)
        f.write("usemtl %s_material\n" % name)
        for t in tris:
            f.write("f %d/%d %d/%d %d/%d\n" % (t[0], t[0], t[1], t[1], t[2], t[2]))
    with open(os.path.join(out, name + ".mtl"), "w", newline="\n") as f:
        f.write("newmtl %s_material\nKd 1 1 1\nmap_Kd textures/%s.png\n" % (name, name))
    png(os.path.join(out, "textures", name + ".png"), 64, colour)


def ply(out, name):
    verts, _, tris = sphere(16, 32, 2.0, 0.6)
    with open(os.path.join(out, name + ".ply"), "w", newline="\n") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(verts), len(tris)))
        for v in verts:
            f.write("%.6f %.6f %.6f\n" % v)
        for t in tris:
            f.write("3 %d %d %d\n" % (t[0] - 1, t[1] - 1, t[2] - 1))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(os.path.join(out, "textures"), exist_ok=True)
    obj(out, "crate", 1.0, (40, 90, 200))
    obj(out, "barrel", 1.6, (200, 60, 30))
    ply(out, "rock")
    with open(os.path.join(out, "light.json"), "w", newline="\n") as f:
        f.write('{"version": 1, "lod_ratios": [0.5, 0.2], "error_samples": 2000}\n')


if __name__ == "__main__":
    main()
