#!/usr/bin/env python3
"""Wraps a Draco mesh (.drc, positions only) in a GLB using KHR_draco_mesh_compression: a fuzz seed
for the glTF importer's Draco path. usage: fuzz_draco_glb.py IN.drc OUT.glb VERTEX_COUNT TRIANGLE_COUNT (the counts Draco decodes to)"""
import json, struct, sys

drc = open(sys.argv[1], "rb").read()
doc = {
    "asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_draco_mesh_compression"],
    "extensionsRequired": ["KHR_draco_mesh_compression"],
    "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "extensions": {
        "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}}]}],
    "accessors": [
        {"componentType": 5126, "count": int(sys.argv[3]), "type": "VEC3"},
        {"componentType": 5125, "count": 3 * int(sys.argv[4]), "type": "SCALAR"},
    ],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(drc)}],
    "buffers": [{"byteLength": len(drc)}],
}
blob = drc + b"\0" * (-len(drc) % 4)
js = json.dumps(doc, sort_keys=True).encode()
js += b" " * (-len(js) % 4)
body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
open(sys.argv[2], "wb").write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
