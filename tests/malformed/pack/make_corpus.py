#!/usr/bin/env python3
"""Regenerates the lying-pack corpus in this folder (usage: make_corpus.py LODBAKE_CLI; deterministic).

Each case is a GLB a buggy or hostile baker could write: a pack of a small sphere baked by
`lodbake bake` (three levels, LODBAKE_lod_metrics, LODBAKE_valence_compression streams and a
LODBAKE_progressive_fans blob), then one lie told in its JSON or its BIN chunk. NAME.glb comes with
NAME.expected, the substring of the one-line error the runtime must report for it: lodrt
(loadPack, then buildModels) when it refuses the pack, else loddump's first problem (the stream
and blob checks, which decode with lodrt's decoders). tests/runtime/pack_corpus_test.cpp checks
every pair, and that no two cases expect the same message. Standard library only.
"""
import json, math, os, struct, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


def sphere_off(rings=8, segments=12):
    """A UV sphere as OFF text: a closed mesh the simplifier can take down to a few triangles."""
    verts = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        theta = math.pi * r / rings
        for s in range(segments):
            phi = 2 * math.pi * s / segments
            verts.append((math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)))
    verts.append((0.0, 0.0, -1.0))
    south = len(verts) - 1
    ring = lambda r, s: 1 + (r - 1) * segments + s % segments
    faces = [(0, ring(1, s), ring(1, s + 1)) for s in range(segments)]
    for r in range(1, rings - 1):
        for s in range(segments):
            a, b, c, d = ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1)
            faces += [(a, b, c), (a, c, d)]
    faces += [(south, ring(rings - 1, s + 1), ring(rings - 1, s)) for s in range(segments)]
    lines = ["OFF", "%d %d 0" % (len(verts), len(faces))]
    lines += ["%.6f %.6f %.6f" % v for v in verts]
    lines += ["3 %d %d %d" % f for f in faces]
    return "\n".join(lines) + "\n"


def read_glb(data):
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == GLB_MAGIC and version == 2 and length == len(data)
    json_len, kind = struct.unpack_from("<II", data, 12)
    assert kind == JSON_CHUNK
    doc = json.loads(data[20:20 + json_len].decode("utf-8"))
    pos = 20 + json_len
    bin_len, kind = struct.unpack_from("<II", data, pos)
    assert kind == BIN_CHUNK
    return doc, bytearray(data[pos + 8:pos + 8 + bin_len])


def write_glb(doc, bin_bytes):
    text = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
    text += b" " * (-len(text) % 4)
    bin_bytes = bytes(bin_bytes) + b"\0" * (-len(bin_bytes) % 4)
    body = struct.pack("<II", len(text), JSON_CHUNK) + text + struct.pack("<II", len(bin_bytes), BIN_CHUNK) + bin_bytes
    return struct.pack("<III", GLB_MAGIC, 2, 12 + len(body)) + body


def bake(cli, tmp, pfrep_format, clusters=False):
    off = os.path.join(tmp, "sphere.off")
    with open(off, "w") as f:
        f.write(sphere_off(16, 24) if clusters else sphere_off())
    out = os.path.join(tmp, "sphere.glb")
    subprocess.run([cli, "bake", off, "-o", out, "--levels", "0.5,0.25", "--preset",
                    os.path.join(HERE, "..", "..", "..", "configs", "desktop.json"), "--quiet",
                    "--pfrep-format", str(pfrep_format)] + (["--clusters", "--no-progressive-fans"] if clusters else []),
                   check=True, stdout=subprocess.DEVNULL)
    with open(out, "rb") as f:
        return f.read()


class Pack:
    """The parsed base pack and the shortcuts the cases use."""

    def __init__(self, glb):
        self.doc, self.bin = read_glb(glb)
        roots = [i for i, n in enumerate(self.doc["nodes"]) if "MSFT_lod" in n.get("extensions", {})]
        assert len(roots) == 1, "the base pack must have one LOD chain"
        self.root = roots[0]
        self.ids = self.root_node()["extensions"]["MSFT_lod"]["ids"]
        assert len(self.ids) == 2, "the base pack must have three levels"

    def root_node(self):
        return self.doc["nodes"][self.root]

    def metrics(self):
        return self.root_node()["extensions"]["LODBAKE_lod_metrics"]["levels"]

    def mesh_of(self, node):
        return self.doc["meshes"][self.doc["nodes"][node]["mesh"]]

    def prim(self, level):
        return self.mesh_of(self.root if level == 0 else self.ids[level - 1])["primitives"][0]

    def valence(self, level):
        return self.prim(level)["extensions"]["LODBAKE_valence_compression"]

    def pfrep(self):
        return self.mesh_of(self.root)["extensions"]["LODBAKE_progressive_fans"]

    def view_range(self, view):
        v = self.doc["bufferViews"][view]
        return v.get("byteOffset", 0), v["byteLength"]

    def patch(self, view, offset, fmt, value):
        start, _ = self.view_range(view)
        struct.pack_into(fmt, self.bin, start + offset, value)

    def read(self, view, offset, fmt):
        start, _ = self.view_range(view)
        return struct.unpack_from(fmt, self.bin, start + offset)[0]

    def glb(self):
        return write_glb(self.doc, self.bin)


# Every case: a function that tells one lie to `p` (a fresh Pack of the base) and returns the
# expected substring, or (GLB bytes, expected) when it edits the container itself.
CASES = {}


def case(fn):
    name = fn.__name__
    assert name not in CASES
    CASES[name] = fn
    return fn


def accessor(p, level, semantic):
    prim = p.prim(level)
    return prim["indices"] if semantic == "indices" else prim["attributes"][semantic]


def mesh_index(p, level):
    return p.doc["nodes"][p.root if level == 0 else p.ids[level - 1]]["mesh"]


def prim_path(p, level):
    return "/meshes/%d/primitives/0" % mesh_index(p, level)


def lod_path(p):
    return "/nodes/%d/extensions/MSFT_lod" % p.root


def metrics_path(p, level=None, key=None):
    path = "/nodes/%d/extensions/LODBAKE_lod_metrics/levels" % p.root
    if level is not None:
        path += "/%d" % level
    if key is not None:
        path += "/" + key
    return path


def valence_path(p, level):
    return prim_path(p, level) + "/extensions/LODBAKE_valence_compression"


def pfrep_path(p):
    return "/meshes/%d/extensions/LODBAKE_progressive_fans" % mesh_index(p, 0)


# --- Container and glTF structure: lodrt::loadPack ---

@case
def glb_length_too_long(p):
    glb = bytearray(p.glb())
    struct.pack_into("<I", glb, 8, len(glb) + 8)
    return bytes(glb), "container: truncated: a length field runs past the end of the data"


@case
def glb_length_too_short(p):
    return p.glb() + b"\0" * 8, "container: bytes follow the end given in the GLB header"


@case
def buffer_longer_than_bin(p):
    p.doc["buffers"][0]["byteLength"] += 64
    return "/buffers/0/byteLength: %d bytes, but the BIN chunk has" % p.doc["buffers"][0]["byteLength"]


@case
def view_past_buffer(p):
    view = p.valence(1)["bufferView"]
    p.doc["bufferViews"][view]["byteLength"] += 4096
    return "/bufferViews/%d: bytes [" % view


@case
def view_stride_not_multiple_of_4(p):
    view = p.doc["accessors"][accessor(p, 1, "POSITION")]["bufferView"]
    p.doc["bufferViews"][view]["byteStride"] = 6
    return "/bufferViews/%d/byteStride: 6; expected a multiple of 4 in [4, 252]" % view


@case
def accessor_count_past_view(p):
    a = accessor(p, 2, "NORMAL")
    p.doc["accessors"][a]["count"] *= 4
    return "/accessors/%d/count: %d elements" % (a, p.doc["accessors"][a]["count"])


@case
def accessor_offset_misaligned(p):
    a = accessor(p, 1, "POSITION")
    p.doc["accessors"][a]["byteOffset"] = 2
    return "/accessors/%d/byteOffset: data at byte" % a


@case
def attribute_count_mismatch(p):
    a = p.doc["accessors"][accessor(p, 1, "NORMAL")]
    a["count"] -= 1
    return prim_path(p, 1) + "/attributes/POSITION: count %d differs from NORMAL count %d" % (a["count"] + 1, a["count"])


@case
def indices_not_triangles(p):
    a = accessor(p, 1, "indices")
    p.doc["accessors"][a]["count"] -= 1
    return "vertices for TRIANGLES; expected a multiple of 3"


@case
def index_out_of_range(p):
    a = p.doc["accessors"][accessor(p, 2, "indices")]
    vertices = p.doc["accessors"][accessor(p, 2, "POSITION")]["count"]
    fmt = {5121: "<B", 5123: "<H", 5125: "<I"}[a["componentType"]]
    p.patch(a["bufferView"], a.get("byteOffset", 0) + 5 * struct.calcsize(fmt), fmt, vertices)
    return prim_path(p, 2) + "/indices: index %d at position 5 out of range (%d vertices)" % (vertices, vertices)


@case
def node_mesh_out_of_range(p):
    p.doc["nodes"][p.ids[1]]["mesh"] = len(p.doc["meshes"]) + 7
    return "/nodes/%d/mesh: index %d out of range" % (p.ids[1], len(p.doc["meshes"]) + 7)


@case
def node_children_cycle(p):
    p.doc["nodes"][p.ids[0]]["children"] = [p.ids[1]]
    p.doc["nodes"][p.ids[1]]["children"] = [p.ids[0]]
    return "children: node hierarchy contains a cycle through node"


# --- MSFT_lod chains and node transforms: lodrt::buildModels ---

@case
def lod_ids_not_array(p):
    p.root_node()["extensions"]["MSFT_lod"]["ids"] = p.ids[0]
    return lod_path(p) + "/ids: expected an array"


@case
def lod_id_out_of_range(p):
    p.ids[1] = len(p.doc["nodes"]) + 3
    return lod_path(p) + "/ids/1: expected a node index below %d" % len(p.doc["nodes"])


@case
def lod_id_not_integer(p):
    p.ids[0] = 1.5
    return lod_path(p) + "/ids/0: expected a node index below"


@case
def lod_lists_itself(p):
    p.ids[1] = p.root
    return lod_path(p) + "/ids/1: cyclic: the node lists itself"


@case
def lod_level_lists_root_back(p):
    p.doc["nodes"][p.ids[0]].setdefault("extensions", {})["MSFT_lod"] = {"ids": [p.root]}
    return "cyclic: node %d lists node %d back" % (p.ids[0], p.root)


@case
def lod_nested_chain(p):
    p.doc["nodes"][p.ids[1]].setdefault("extensions", {})["MSFT_lod"] = {"ids": []}
    return "node %d has MSFT_lod too; expected a plain level node" % p.ids[1]


@case
def lod_id_repeated(p):
    p.ids[1] = p.ids[0]
    return lod_path(p) + "/ids/1: node %d is already a level of node %d" % (p.ids[0], p.root)


@case
def lod_level_in_two_chains(p):
    p.doc["nodes"].append({"name": "thief", "mesh": p.doc["nodes"][p.root]["mesh"],
                           "extensions": {"MSFT_lod": {"ids": [p.ids[1]]}}})
    p.doc["scenes"][0]["nodes"].append(len(p.doc["nodes"]) - 1)
    return "/nodes/%d/extensions/MSFT_lod/ids/0: node %d is already a level of node %d" % (
        len(p.doc["nodes"]) - 1, p.ids[1], p.root)


@case
def lod_too_many_levels(p):
    p.root_node()["extensions"]["MSFT_lod"]["ids"] = (p.ids * 4)[:8]
    return lod_path(p) + "/ids: 8 ids; lodrt supports at most 8 levels"


@case
def lod_level_without_mesh(p):
    del p.doc["nodes"][p.ids[0]]["mesh"]
    return "/nodes/%d/mesh: missing; level 1 of model 0 needs a mesh" % p.ids[0]


@case
def node_rotation_not_unit(p):
    p.doc["nodes"][p.ids[0]]["rotation"] = [0, 0, 0, 2]
    return "/nodes/%d/rotation: expected a unit quaternion (length 2)" % p.ids[0]


@case
def node_matrix_and_trs(p):
    p.doc["nodes"][p.ids[1]]["matrix"] = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
    p.doc["nodes"][p.ids[1]]["translation"] = [1, 2, 3]
    return "/nodes/%d: expected either matrix or translation/rotation/scale, not both" % p.ids[1]


@case
def node_matrix_not_affine(p):
    p.root_node()["matrix"] = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1]
    return "/nodes/%d/matrix: expected an affine matrix (last row 0 0 0 1)" % p.root


@case
def position_min_above_max(p):
    a = p.doc["accessors"][accessor(p, 0, "POSITION")]
    a["min"][1], a["max"][1] = a["max"][1], a["min"][1]
    return "/accessors/%d/min: expected finite numbers with min <= max (component 1)" % accessor(p, 0, "POSITION")


@case
def position_without_bounds(p):
    del p.doc["accessors"][accessor(p, 0, "POSITION")]["max"]
    return "/accessors/%d: POSITION needs min and max of 3 numbers" % accessor(p, 0, "POSITION")


# --- LODBAKE_lod_metrics and MSFT_screencoverage: lodrt::buildModels ---

@case
def metrics_wrong_count(p):
    del p.metrics()[2]
    return metrics_path(p) + ": expected 3 entries (MSFT_lod ids + 1)"


@case
def metrics_level0_error(p):
    p.metrics()[0]["hausdorffError"] = 0.001
    return metrics_path(p, 0) + ": level 0 must have zero errors and switchDistance 0"


@case
def metrics_hausdorff_decreases(p):
    p.metrics()[2]["hausdorffError"] = p.metrics()[1]["hausdorffError"] / 2
    return metrics_path(p, 2, "hausdorffError") + ": level 2: decreases from level 1"


@case
def metrics_mean_decreases(p):
    p.metrics()[2]["meanError"] = p.metrics()[1]["meanError"] / 2
    return metrics_path(p, 2, "meanError") + ": level 2: decreases from level 1"


@case
def metrics_switch_distance_decreases(p):
    m = p.metrics()[2]
    m["switchDistance"] = p.metrics()[1]["switchDistance"] / 2
    m["hysteresisBand"] = [m["switchDistance"] * 0.9, m["switchDistance"] * 1.1]
    return metrics_path(p, 2, "switchDistance") + ": level 2: decreases from level 1"


@case
def metrics_negative_error(p):
    p.metrics()[1]["meanError"] = -0.001
    return metrics_path(p, 1, "meanError") + ": expected a finite number >= 0"


@case
def metrics_error_not_a_float(p):
    p.metrics()[2]["hausdorffError"] = 1e39
    return metrics_path(p, 2, "hausdorffError") + ": expected a finite number >= 0"


@case
def metrics_switch_distance_missing(p):
    del p.metrics()[1]["switchDistance"]
    return metrics_path(p, 1, "switchDistance") + ": expected a finite number >= 0"


@case
def metrics_nan_written_as_text(p):
    # A writer that prints a NaN error the way C's printf does: not JSON at all.
    p.metrics()[1]["hausdorffError"] = 0.125
    glb = p.glb()
    needle = b'"hausdorffError":0.125'
    assert glb.count(needle) == 1
    at = glb.index(needle) + len(b'"hausdorffError":')
    glb = glb[:at] + b"nan  " + glb[at + 5:]
    return glb, "JSON byte %d: " % (at - 20)


@case
def metrics_band_misses_switch_distance(p):
    m = p.metrics()[1]
    m["hysteresisBand"] = [m["switchDistance"] * 1.1, m["switchDistance"] * 1.2]
    return metrics_path(p, 1, "hysteresisBand") + ": level 1: expected near <="


@case
def metrics_band_not_a_pair(p):
    m = p.metrics()[2]
    m["hysteresisBand"] = [m["switchDistance"]]
    return metrics_path(p, 2, "hysteresisBand") + ": expected two finite numbers"


@case
def metrics_triangles_lie(p):
    p.metrics()[1]["triangles"] += 10
    return metrics_path(p, 1, "triangles") + ": %d; the level's mesh has %d" % (
        p.metrics()[1]["triangles"], p.metrics()[1]["triangles"] - 10)


@case
def coverage_increases_beside_metrics(p):
    p.root_node().setdefault("extras", {})["MSFT_screencoverage"] = [0.5, 0.25, 0.75]
    return "/nodes/%d/extras/MSFT_screencoverage/2: expected a number in [0, 1] that does not increase" % p.root


@case
def coverage_increases_without_metrics(p):
    del p.root_node()["extensions"]["LODBAKE_lod_metrics"]
    p.root_node().setdefault("extras", {})["MSFT_screencoverage"] = [0.2, 0.4, 0.1]
    return "/nodes/%d/extras/MSFT_screencoverage/1: expected a number in [0, 1] that does not increase" % p.root


@case
def coverage_too_short(p):
    del p.root_node()["extensions"]["LODBAKE_lod_metrics"]
    p.root_node().setdefault("extras", {})["MSFT_screencoverage"] = [0.5]
    return "/nodes/%d/extras/MSFT_screencoverage: expected at least" % p.root


# --- LODBAKE_valence_compression streams: loddump (lodrt::valenceReadInfo / valenceDecode) ---

@case
def valence_view_out_of_range(p):
    p.valence(1)["bufferView"] = len(p.doc["bufferViews"]) + 5
    return valence_path(p, 1) + ": bufferView: expected a buffer view index below %d" % len(p.doc["bufferViews"])


@case
def valence_bad_magic(p):
    p.patch(p.valence(0)["bufferView"], 0, "<I", 0x4D424258)
    return valence_path(p, 0) + ": stream fails to decode: header: BadMagic"


@case
def valence_unknown_version(p):
    p.patch(p.valence(2)["bufferView"], 4, "<H", 99)
    return valence_path(p, 2) + ": stream fails to decode: header: UnsupportedVersion"


@case
def valence_vertex_count_lies(p):
    view = p.valence(1)["bufferView"]
    count = p.read(view, 8, "<I")
    p.patch(view, 8, "<I", count + 1)
    return valence_path(p, 1) + ": stream has %d vertices" % (count + 1)


@case
def valence_connectivity_size_lies(p):
    view = p.valence(0)["bufferView"]
    p.patch(view, 44, "<I", p.read(view, 44, "<I") + 4096)
    return valence_path(p, 0) + ": stream fails to decode: header: Truncated"


@case
def valence_stream_garbled(p):
    view = p.valence(0)["bufferView"]
    start, _ = p.view_range(view)
    for k in range(64, 96):
        p.bin[start + k] ^= 0x5A
    return valence_path(p, 0) + ": stream fails to decode: CorruptStream"


@case
def valence_accessor_count_disagrees(p):
    # A consistent primitive (indices still triangles, still in range, the metrics agreeing) whose
    # triangle count is not the stream's: the plain accessor lies about what the stream holds.
    a = p.doc["accessors"][accessor(p, 2, "indices")]
    a["count"] -= 3
    p.metrics()[2]["triangles"] -= 1
    view = p.valence(2)["bufferView"]
    vertices, triangles = p.read(view, 8, "<I"), p.read(view, 12, "<I")
    return valence_path(p, 2) + ": stream has %d vertices and %d triangles, the primitive %d and %d" % (
        vertices, triangles, vertices, triangles - 1)


@case
def valence_position_bits_lie(p):
    p.valence(1)["positionBits"] -= 1
    return valence_path(p, 1) + ": positionBits: %d; the stream header says %d" % (
        p.valence(1)["positionBits"], p.valence(1)["positionBits"] + 1)


@case
def valence_normals_not_named(p):
    del p.valence(2)["attributes"]["NORMAL"]
    p.valence(2).pop("normalBits", None)
    return valence_path(p, 2) + ": attributes: the stream has normals but NORMAL is not named"


# --- LODBAKE_progressive_fans format 3 blobs (`format`: 3; lodrt::pfrepDecompress): their base pack
# is baked with --pfrep-format 3, every other case's with --pfrep-format 2 ---

FORMAT3_CASES = set()


def case3(fn):
    FORMAT3_CASES.add(fn.__name__)
    return case(fn)


@case3
def pfrep3_unknown_format(p):
    p.pfrep()["format"] = 6
    return pfrep_path(p) + "/format: format: expected 2, 3, 4 or 5"


@case3
def pfrep5_claimed_by_a_format3_blob(p):
    p.pfrep()["format"] = 5
    return pfrep_path(p) + ": stream fails to decode (format 5): BadMagic"


# --- LODBAKE_progressive_fans format 5 blobs (`format`: 5, region blocks; lodrt::pfrepRegionOpen and
# pfrepRegionLoadBlock): their base pack is baked with --pfrep-format 5 ---

FORMAT5_CASES = set()


def case5(fn):
    FORMAT5_CASES.add(fn.__name__)
    return case(fn)


@case5
def pfrep5_directory_lies(p):
    # Block 0's size grows by one byte: the blocks no longer end at blob_size.
    view = p.pfrep()["bufferView"]
    p.patch(view, 64 + 4, "<I", p.read(view, 64 + 4, "<I") + 1)
    return pfrep_path(p) + ": stream fails to decode (format 5): OutOfBounds"


@case5
def pfrep5_blob_cut(p):
    view = p.pfrep()["bufferView"]
    # The view ends before the blob_size its header gives.
    p.doc["bufferViews"][view]["byteLength"] -= 4
    return pfrep_path(p) + ": stream fails to decode (format 5): BadStructure"


@case3
def pfrep3_header_version_lies(p):
    p.patch(p.pfrep()["bufferView"], 4, "<I", 2)
    return pfrep_path(p) + ": stream fails to decode (format 3): UnsupportedVersion"


@case3
def pfrep3_decoded_size_lies(p):
    view = p.pfrep()["bufferView"]
    p.patch(view, 52, "<I", p.read(view, 52, "<I") + 64)
    return pfrep_path(p) + ": stream fails to decode (format 3): CorruptStream"


@case3
def pfrep3_zero_field_lies(p):
    p.patch(p.pfrep()["bufferView"], 60, "<I", 1)
    return pfrep_path(p) + ": stream fails to decode (format 3): BadStructure"


@case3
def pfrep3_header_cut(p):
    view = p.pfrep()["bufferView"]
    p.doc["bufferViews"][view]["byteLength"] = 60
    return pfrep_path(p) + ": stream fails to decode (format 3): Truncated"


# --- LODBAKE_progressive_fans blobs: loddump (lodrt::openPfrep / pfrepExtractLevel) ---

@case
def pfrep_view_out_of_range(p):
    p.pfrep()["bufferView"] = len(p.doc["bufferViews"]) + 9
    return pfrep_path(p) + ": bufferView: expected a buffer view index"


@case
def pfrep_bad_magic(p):
    p.patch(p.pfrep()["bufferView"], 0, "<I", 0x31524658)
    return pfrep_path(p) + ": stream fails to decode: BadMagic"


@case
def pfrep_unknown_version(p):
    p.patch(p.pfrep()["bufferView"], 4, "<I", 7)
    return pfrep_path(p) + ": stream fails to decode: UnsupportedVersion"


@case
def pfrep_blob_size_lies(p):
    view = p.pfrep()["bufferView"]
    p.patch(view, 52, "<I", p.read(view, 52, "<I") + 64)
    return pfrep_path(p) + ": stream fails to decode: Truncated"


@case
def pfrep_directory_lies(p):
    view = p.pfrep()["bufferView"]
    p.patch(view, 64, "<I", 3)
    return pfrep_path(p) + ": stream fails to decode: OutOfBounds"


@case
def pfrep_vertex_count_field_lies(p):
    p.pfrep()["vertexCount"] += 1
    return pfrep_path(p) + "/vertexCount: vertexCount: expected the blob's %d" % (p.pfrep()["vertexCount"] - 1)


@case
def pfrep_removed_count_field_lies(p):
    p.pfrep()["removedCount"] -= 1
    return pfrep_path(p) + "/removedCount: removedCount: expected the blob's %d" % (p.pfrep()["removedCount"] + 1)


@case
def pfrep_triangle_count_field_lies(p):
    p.pfrep()["triangleCount"] += 2
    return pfrep_path(p) + "/triangleCount: triangleCount: expected the blob's %d" % (p.pfrep()["triangleCount"] - 2)


@case
def pfrep_levels_wrong_count(p):
    del p.pfrep()["levels"][2]
    return pfrep_path(p) + "/levels: expected 3 levels (one per level of the LOD group), got 2"


@case
def pfrep_first_level_not_zero(p):
    p.pfrep()["levels"][0]["removals"] = 1
    return pfrep_path(p) + "/levels/0/removals: PFRep level 1: the first level must be 0"


@case
def pfrep_removals_decrease(p):
    levels = p.pfrep()["levels"]
    levels[2]["removals"] = levels[1]["removals"] - 1
    return pfrep_path(p) + "/levels/2/removals: PFRep level %d: expected at least the previous level's" % (
        levels[2]["removals"])


@case
def pfrep_triangles_lie(p):
    levels = p.pfrep()["levels"]
    levels[1]["triangles"] -= 2
    return pfrep_path(p) + "/levels/1/triangles: PFRep level %d has %d triangles, the extension says %d" % (
        levels[1]["removals"], levels[1]["triangles"] + 2, levels[1]["triangles"])


# --- LODBAKE_cluster_lod (docs/format/cluster_lod.md): loddump's check, with lodrt's reader ---
# Their base is a finer sphere baked with --clusters (and without the PFRep blob, to keep the packs
# small), so the hierarchy has levels of groups.
CLUSTER_CASES = set()


def cluster_case(fn):
    CLUSTER_CASES.add(fn.__name__)
    return case(fn)


def cluster_ext(p):
    return p.mesh_of(p.root)["extensions"]["LODBAKE_cluster_lod"]


def cluster_path(p):
    return "/meshes/%d/extensions/LODBAKE_cluster_lod" % mesh_index(p, 0)


def cluster_table(p):
    """(view, header counts) of the table: clusters, groups, children, roots, pages."""
    view = cluster_ext(p)["table"]
    return view, [p.read(view, 8 + 4 * i, "<I") for i in range(5)]


CLUSTER_RECORD, GROUP_RECORD, PAGE_RECORD, HEADER = 48, 48, 16, 64


def cluster_record(p, c):
    return HEADER + CLUSTER_RECORD * c


def group_record(p, g):
    _, (clusters, _, _, _, _) = cluster_table(p)
    return HEADER + CLUSTER_RECORD * clusters + GROUP_RECORD * g


def page_record(p, page):
    _, (clusters, groups, children, roots, _) = cluster_table(p)
    return HEADER + CLUSTER_RECORD * clusters + GROUP_RECORD * groups + 4 * (children + roots) + PAGE_RECORD * page


@cluster_case
def cluster_table_view_missing(p):
    cluster_ext(p)["table"] = len(p.doc["bufferViews"]) + 3
    return cluster_path(p) + "/table: expected a buffer view index"


@cluster_case
def cluster_table_bad_magic(p):
    view, _ = cluster_table(p)
    p.patch(view, 0, "<I", 0x4C43424D)
    return "table: bad magic (expected \"LBCL\")"


@cluster_case
def cluster_table_count_lies(p):
    view, counts = cluster_table(p)
    p.patch(view, 8, "<I", counts[0] + 1)
    return "table: %d bytes, its counts need %d" % (p.view_range(view)[1], p.view_range(view)[1] + CLUSTER_RECORD)


@cluster_case
def cluster_page_outside_view(p):
    view, _ = cluster_table(p)
    p.patch(view, page_record(p, 0), "<I", 1 << 24)
    return "page 0: bytes [16777216, "


@cluster_case
def cluster_triangle_count_lies(p):
    view, _ = cluster_table(p)
    p.patch(view, cluster_record(p, 1) + 46, "<B", 200)
    return "cluster 1: 200 triangles over"


@cluster_case
def cluster_parent_does_not_list_it(p):
    view, (clusters, groups, _, _, _) = cluster_table(p)
    parent = p.read(view, cluster_record(p, 0) + 36, "<I")
    p.patch(view, cluster_record(p, 0) + 36, "<I", (parent + 1) % groups)
    return "table: the hierarchy is inconsistent (BadStructure"


@cluster_case
def cluster_first_triangle_lies(p):
    view, _ = cluster_table(p)
    first = p.read(view, cluster_record(p, 0) + 44, "<H")
    p.patch(view, cluster_record(p, 0) + 44, "<H", first + 1)
    return "cluster 0: first triangle %d, expected 0" % (first + 1)


@cluster_case
def cluster_vertex_count_lies(p):
    view, _ = cluster_table(p)
    vertices = p.read(view, cluster_record(p, 0) + 47, "<B")
    p.patch(view, cluster_record(p, 0) + 47, "<B", vertices - 1)
    return "vertices, its record says"


@cluster_case
def cluster_page_grid_differs(p):
    view, _ = cluster_table(p)
    pages = cluster_ext(p)["pages"]
    offset = p.read(view, page_record(p, 0), "<I")
    p.patch(pages, offset + 28, "<f", p.read(pages, offset + 28, "<f") - 1.0)
    return "page 0: expected a positions-only stream on the table's grid"


@cluster_case
def cluster_run_names_no_cluster(p):
    view, _ = cluster_table(p)
    pages = cluster_ext(p)["pages"]
    offset, stream = p.read(view, page_record(p, 0), "<I"), p.read(view, page_record(p, 0) + 4, "<I")
    p.patch(pages, offset + stream, "<B", 255)
    return "page 0: run 0 names no cluster of the page or is empty"


@cluster_case
def cluster_page_stream_corrupt(p):
    view, _ = cluster_table(p)
    pages = cluster_ext(p)["pages"]
    offset = p.read(view, page_record(p, 0), "<I")
    p.patch(pages, offset + 64, "<B", 0xff) # the connectivity stream's first byte must be 0
    return "page 0: stream fails to decode"


@cluster_case
def cluster_error_decreases(p):
    view, (clusters, _, _, _, _) = cluster_table(p)
    for c in range(clusters):
        own, parent = p.read(view, cluster_record(p, c) + 32, "<I"), p.read(view, cluster_record(p, c) + 36, "<I")
        if own != 0xFFFFFFFF and parent != 0xFFFFFFFF:
            error = p.read(view, group_record(p, own) + 16, "<f")
            p.patch(view, group_record(p, parent) + 16, "<f", error / 2)
            return "(errors must not decrease)"
    raise AssertionError("the cluster base has no cluster with both groups")


@cluster_case
def cluster_group_never_entered(p):
    view, (clusters, _, _, _, _) = cluster_table(p)
    # Every output of the group the first LOD0 cluster is an input of claims a LOD0 origin instead:
    # the group is never entered and its inputs cannot be reached.
    parent = p.read(view, cluster_record(p, 0) + 36, "<I")
    for c in range(clusters):
        if p.read(view, cluster_record(p, c) + 32, "<I") == parent:
            p.patch(view, cluster_record(p, c) + 32, "<I", 0xFFFFFFFF)
    return ": not reachable from the roots"


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make_corpus.py LODBAKE_CLI")
    with tempfile.TemporaryDirectory() as tmp:
        bases = {2: bake(sys.argv[1], tmp, 2), 3: bake(sys.argv[1], tmp, 3), 5: bake(sys.argv[1], tmp, 5),
                 "clusters": bake(sys.argv[1], tmp, 3, clusters=True)}
    for old in os.listdir(HERE):
        if old.endswith(".glb") or old.endswith(".expected"):
            os.remove(os.path.join(HERE, old))
    for name, fn in CASES.items():
        p = Pack(bases["clusters" if name in CLUSTER_CASES else 3 if name in FORMAT3_CASES else
                       5 if name in FORMAT5_CASES else 2])
        out = fn(p)
        glb, expected = out if isinstance(out, tuple) else (p.glb(), out)
        assert "\n" not in expected
        with open(os.path.join(HERE, name + ".glb"), "wb") as f:
            f.write(glb)
        with open(os.path.join(HERE, name + ".expected"), "w") as f:
            f.write(expected + "\n")
    print("%d packs written to %s" % (len(CASES), HERE))


if __name__ == "__main__":
    main()
