#!/usr/bin/env python3
"""Regenerates the malformed glTF/GLB corpus in this folder (run from anywhere; deterministic)."""
import base64, copy, json, os, struct

HERE = os.path.dirname(os.path.abspath(__file__))


def tri_buffer(positions, indices):
    data = b"".join(struct.pack("<3f", *p) for p in positions)
    idx = b"".join(struct.pack("<H", i) for i in indices)
    while len(idx) % 4:
        idx += b"\0"
    return data, idx


def base_doc(positions=((0, 0, 0), (1, 0, 0), (0, 1, 0)), indices=(0, 1, 2)):
    pos, idx = tri_buffer(positions, indices)
    blob = pos + idx
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
            {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)},
        ],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }, blob


def write_json(name, doc):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, indent=1, sort_keys=True)
        f.write("\n")


def glb_bytes(doc, blob):
    doc = copy.deepcopy(doc)
    del doc["buffers"][0]["uri"]
    js = json.dumps(doc, sort_keys=True).encode()
    while len(js) % 4:
        js += b" "
    while len(blob) % 4:
        blob += b"\0"
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def write_bytes(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


cases = []  # (file, expected substring)

doc, blob = base_doc()
good_glb = glb_bytes(doc, blob)

write_bytes("bad_magic.glb", b"gLTF" + good_glb[4:]); cases.append(("bad_magic.glb", "bad magic"))
write_bytes("short_header.glb", good_glb[:7]); cases.append(("short_header.glb", "GLB header"))
write_bytes("truncated.glb", good_glb[:len(good_glb) - 20]); cases.append(("truncated.glb", "length field says"))
lie = bytearray(good_glb)
struct.pack_into("<I", lie, 12, 100000)
write_bytes("chunk_length_lies.glb", bytes(lie)); cases.append(("chunk_length_lies.glb", "runs past the end of the file"))
ver = bytearray(good_glb)
struct.pack_into("<I", ver, 4, 1)
write_bytes("version_1.glb", bytes(ver)); cases.append(("version_1.glb", "version 1, expected 2"))

write_bytes("json_syntax.gltf", b'{"asset": {"version": "2.0"}, "meshes": [ {,] }\n'); cases.append(("json_syntax.gltf", "syntax error"))
write_bytes("not_object.gltf", b"[1, 2, 3]\n"); cases.append(("not_object.gltf", "expected an object"))

d = copy.deepcopy(doc); d["accessors"][0]["count"] = 30
write_json("accessor_past_buffer.gltf", d); cases.append(("accessor_past_buffer.gltf", "accessor 0 (POSITION)"))

d, _ = base_doc(indices=(0, 1, 7))
write_json("index_out_of_range.gltf", d); cases.append(("index_out_of_range.gltf", "out of range (3 vertices)"))

d = copy.deepcopy(doc); d["accessors"][1]["componentType"] = 5124
write_json("bad_component_type.gltf", d); cases.append(("bad_component_type.gltf", "componentType 5124"))

d = copy.deepcopy(doc); d["buffers"][0]["uri"] = "missing_buffer.bin"
write_json("missing_buffer_file.gltf", d); cases.append(("missing_buffer_file.gltf", "missing_buffer.bin"))

d = copy.deepcopy(doc); d["extensionsUsed"] = ["EXT_future_thing"]; d["extensionsRequired"] = ["EXT_future_thing"]
write_json("unknown_required_extension.gltf", d); cases.append(("unknown_required_extension.gltf", "EXT_future_thing"))

d, _ = base_doc(positions=((0, 0, 0), (float("nan"), 0, 0), (0, 1, 0)))
d["accessors"][0].pop("min"); d["accessors"][0].pop("max")
write_json("nan_position.gltf", d); cases.append(("nan_position.gltf", "vertex 1 is not finite"))

d = copy.deepcopy(doc)
d["extensionsUsed"] = ["KHR_draco_mesh_compression"]; d["extensionsRequired"] = ["KHR_draco_mesh_compression"]
d["meshes"][0]["primitives"][0]["extensions"] = {
    "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}
d["accessors"][0].pop("bufferView"); d["accessors"][1].pop("bufferView")
write_json("corrupt_draco.gltf", d); cases.append(("corrupt_draco.gltf", "KHR_draco_mesh_compression"))

d = copy.deepcopy(doc); d["meshes"] = []; d["nodes"] = [{}]
write_json("empty_meshes.gltf", d); cases.append(("empty_meshes.gltf", "no triangle primitives"))

d = copy.deepcopy(doc); d["meshes"][0]["primitives"][0]["attributes"] = {"NORMAL": 0}
write_json("missing_position.gltf", d); cases.append(("missing_position.gltf", "POSITION is missing"))

d = copy.deepcopy(doc); d["bufferViews"][1]["byteOffset"] = 4000
write_json("buffer_view_past_buffer.gltf", d); cases.append(("buffer_view_past_buffer.gltf", "bufferView 1"))

d, _ = base_doc(positions=((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)), indices=(0, 1, 2, 3))
write_json("indices_not_triangles.gltf", d); cases.append(("indices_not_triangles.gltf", "multiple of 3"))

d = copy.deepcopy(doc); d["nodes"] = [{"mesh": 0, "children": [1]}, {"children": [0]}]
write_json("node_cycle.gltf", d); cases.append(("node_cycle.gltf", "cycle"))

d = copy.deepcopy(doc); d["bufferViews"][0]["byteStride"] = 8
write_json("byte_stride_too_small.gltf", d); cases.append(("byte_stride_too_small.gltf", "byteStride"))

d = copy.deepcopy(doc); d["accessors"][0]["type"] = "VEC2"
write_json("position_vec2.gltf", d); cases.append(("position_vec2.gltf", "expected VEC3, got VEC2"))

d = copy.deepcopy(doc)
d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2
d["accessors"].append({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC2"})
write_json("attribute_count_mismatch.gltf", d); cases.append(("attribute_count_mismatch.gltf", "differs from POSITION count"))

d = copy.deepcopy(doc)
d["accessors"][0]["sparse"] = {"count": 4, "indices": {"bufferView": 1, "componentType": 5123},
                               "values": {"bufferView": 0}}
write_json("sparse_count_too_large.gltf", d); cases.append(("sparse_count_too_large.gltf", "sparse"))

d = copy.deepcopy(doc); d["scene"] = 3
write_json("missing_scene.gltf", d); cases.append(("missing_scene.gltf", "scene"))

d = copy.deepcopy(doc); d["accessors"][0].pop("bufferView"); d["accessors"][0]["count"] = 4000000000
d["accessors"][0].pop("min"); d["accessors"][0].pop("max")
write_json("absurd_accessor_count.gltf", d); cases.append(("absurd_accessor_count.gltf", "exceeds the reader limit"))

d = copy.deepcopy(doc)
d["extensionsUsed"] = ["KHR_draco_mesh_compression"]; d["extensionsRequired"] = ["KHR_draco_mesh_compression"]
d["meshes"][0]["primitives"][0]["extensions"] = {
    "KHR_draco_mesh_compression": {"bufferView": 2, "attributes": {"POSITION": 0}}}
d["accessors"][0].pop("bufferView"); d["accessors"][1].pop("bufferView")
garbage = bytes((i * 37 + 11) % 251 for i in range(64))
d["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(garbage)})
d["buffers"][0]["byteLength"] = len(blob) + len(garbage)
write_bytes("corrupt_draco.glb", glb_bytes(d, blob + garbage)); cases.append(("corrupt_draco.glb", "KHR_draco_mesh_compression"))

first_bin = bytearray(good_glb)
struct.pack_into("<I", first_bin, 16, 0x004E4942)
write_bytes("bin_chunk_first.glb", bytes(first_bin)); cases.append(("bin_chunk_first.glb", "expected the JSON chunk first"))

d = copy.deepcopy(doc); d["buffers"][0]["byteLength"] = 4096
write_bytes("buffer_longer_than_bin_chunk.glb", glb_bytes(d, blob)); cases.append(("buffer_longer_than_bin_chunk.glb", "byteLength"))

d = copy.deepcopy(doc); d["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@"
write_json("bad_data_uri.gltf", d); cases.append(("bad_data_uri.gltf", "Failed to decode"))

d = copy.deepcopy(doc); d["buffers"][0]["uri"] = "short_side.bin"; d["buffers"][0]["byteLength"] = len(blob) + 1000
d["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": 1000})
d["images"] = [{"bufferView": 2, "mimeType": "image/png"}]; d["textures"] = [{"source": 0}]
write_bytes("short_side.bin", blob)
write_json("external_bin_too_short.gltf", d); cases.append(("external_bin_too_short.gltf", "short_side.bin"))
sides = ["short_side.bin"]
# Written by hand (not generated here): an image file that cannot be read.
cases.append(("missing_image_file.gltf", 'image 0: "missing_texture.png": cannot read'))

# A decompression bomb: a 107-byte Draco stream (a tetrahedron made by draco_encoder -cl 0) whose
# accessors claim 50 million points; refused from the declared counts before Draco decodes anything.
TET_DRC = bytes.fromhex(
    "445241434f0202010000000404010002010001030003020102030102000903000002020401010201000101000303"
    "012001200300208488810100000000ff070000000101000303012001200300f08369803100000000ff00000000000000"
    "00000000000000000000803f0b")
d = copy.deepcopy(doc)
d["extensionsUsed"] = ["KHR_draco_mesh_compression"]; d["extensionsRequired"] = ["KHR_draco_mesh_compression"]
d["accessors"] = [{"componentType": 5126, "count": 50000000, "type": "VEC3"},
                  {"componentType": 5125, "count": 12, "type": "SCALAR"}]
d["bufferViews"] = [{"buffer": 0, "byteOffset": 0, "byteLength": len(TET_DRC)}]
d["meshes"][0]["primitives"][0]["extensions"] = {
    "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}
d["buffers"][0]["byteLength"] = len(TET_DRC)
write_bytes("draco_count_bomb.glb", glb_bytes(d, TET_DRC))
cases.append(("draco_count_bomb.glb", "count 50000000, expected at most"))

# Resource limits and self reference: a buffer that names the .gltf itself (read once, too short),
# JSON nested past the reader's depth limit (would overflow the stack of a recursive parser), and
# a GLB whose JSON chunk is nested the same way.
d = copy.deepcopy(doc); d["buffers"][0]["uri"] = "self_buffer.gltf"; d["buffers"][0]["byteLength"] = 1 << 20
write_json("self_buffer.gltf", d); cases.append(("self_buffer.gltf", "self_buffer.gltf"))
d = copy.deepcopy(doc); d["extras"] = "@NEST@"
text = json.dumps(d, sort_keys=True).replace('"@NEST@"', "[" * 100 + "]" * 100)
write_bytes("deep_extras.gltf", (text + "\n").encode()); cases.append(("deep_extras.gltf", "levels of nested arrays and objects"))
d = copy.deepcopy(doc); d["extras"] = "@NEST@"
js = json.dumps({k: v for k, v in d.items() if k != "buffers"} | {"buffers": [{"byteLength": len(blob)}]},
                sort_keys=True).replace('"@NEST@"', '{"a":' * 100 + "1" + "}" * 100).encode()
js += b" " * (-len(js) % 4)
body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
write_bytes("deep_extras.glb", struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
cases.append(("deep_extras.glb", "levels of nested arrays and objects"))

with open(os.path.join(HERE, "expect.tsv"), "w") as f:
    f.write("# Inputs every command must refuse: file<TAB>substring the one-line error must contain.\n")
    f.write("# Generated by make_corpus.py (listed as a side file).\n")
    f.write("side\tmake_corpus.py\n")
    for name in sides:
        f.write(f"side\t{name}\n")
    for name, expected in cases:
        f.write(f"{name}\t{expected}\n")
print(len(cases), "cases")
