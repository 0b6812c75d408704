#!/usr/bin/env python3
"""Runs lodview --headless under xvfb-run on a small pack and checks what it wrote.

  lodview_check.py --lodview EXE --xvfb-run XVFB --out DIR PACK...
  lodview_check.py --lodview EXE --xvfb-run XVFB --out DIR --textured-source SRC --lodbake EXE --preset P
  lodview_check.py --lodview EXE --xvfb-run XVFB --out DIR --format web|compact --source SRC --lodbake EXE
                   --preset P PLAIN_PACK
  lodview_check.py --lodview EXE --xvfb-run XVFB --out DIR --gltf-transform EXE --source SRC.glb
  lodview_check.py --missing REASON

Four runs of the same walk on a 3x3 grid (LOD, forced LOD0, colour by level, PFRep refinement),
each a few frames at 320x180. Checks: exit code 0; each PNG decodes (zlib, no imaging library), has the requested
size and is not blank (enough pixels differ from the clear colour, and the shading gives many
distinct colours); the JSON report has every field per frame and consistent counts (visible +
culled = instances, the level histogram plus the PFRep instances sums to the instances drawn, draw
calls and triangles positive when something is drawn, LOD0 frames draw only level 0 and at least
the LOD run's triangles, the PFRep run refines and draws instances from the streamed prefix, drawn
levels within 1 px, no lodrt allocation beyond the level reads and none from the heap). The blank and
size checks first reject images built to fail them, so they are known to be able to fail.

--textured-source SRC --lodbake EXE --preset P: bakes SRC (a textured shared scan) and checks
that every draw call of a plain run uses the base colour texture and none of a colour-by-level run
does; skipped (77) when SRC is missing unless LODBAKE_REQUIRE_SHARED_MESHES is set.

--format web|compact --source SRC: bakes SRC with --web (EXT_meshopt_compression, KHR_mesh_quantization)
or --compact (LODBAKE_valence_compression streams only) and runs the LOD and forced LOD0 walks on it and
on PLAIN_PACK (the plain bake of SRC with the same preset): every frame must show the same visible
instances, level histogram, draw calls and triangles as the plain pack, a non-blank image, and decode
time for the levels it decoded. Control: a copy of the pack whose coarsest level's stream has a broken
header must make lodview exit non-zero with a message naming the pack and that level.

--gltf-transform EXE --source SRC.glb: writes SRC with glTF-Transform's `meshopt` and `quantize`
(normalized integer positions under a dequantizing node transform) and checks a LOD run of each
like the plain runs (non-blank images, report fields); skipped (77) when EXE or SRC is missing unless
LODBAKE_REQUIRE_SHARED_MESHES is set (SRC).

--missing: lodview or xvfb-run was not found at configure time. The test is skipped (exit 77)
unless LODBAKE_REQUIRE_LODVIEW is set (scripts/setup-and-test.sh sets it), when it fails.
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import zlib

XVFB_WRAPPER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lodview_xvfb.sh")
CLEAR = (158, 178, 199)  # glClearColor(0.62, 0.70, 0.78) in 8 bits
FRAME_FIELDS = {
    "frame": int, "eye": list, "frame_ms": float, "cpu_ms": float, "gpu_ms": float, "cull_ms": float,
    "select_ms": float, "stream_ms": float, "upload_ms": float, "stream_wait_ms": float, "visible": int,
    "culled": int, "instances_drawn": int, "draw_calls": int, "textured_draw_calls": int, "triangles": int, "levels_resident": int,
    "resident_bytes": int, "bytes_streamed": int, "stream_requests": int, "lodrt_allocations": int, "lodrt_heap_allocations": int,
    "not_drawable": int, "coarser_than_selected": int, "max_sse_px": float, "pfrep_ms": float,
    "pfrep_instances": int, "pfrep_triangles": int, "pfrep_changes": int, "level_histogram": list,
    "decode_ms": float, "levels_decoded": int, "decode_growths": int,
}
SUMMARY_FIELDS = ["frames", "mean_frame_ms", "mean_cpu_ms", "mean_gpu_ms", "mean_triangles", "mean_draw_calls",
                  "max_sse_px", "bytes_streamed", "lodrt_allocations_beyond_requests", "lodrt_heap_allocations",
                  "frames_drawn_coarser", "decode_ms", "levels_decoded", "decode_growths"]
# The bakes these tests start run without LeakSanitizer's exit check in sanitizer builds: its tracer
# can crash at the exit of a multi-threaded bake (as tests/baker/gltf/gltf_test_util.h's
# withoutLeakCheck does for the CLI tests); lodview itself keeps the check.
BAKE_ENV = dict(os.environ, ASAN_OPTIONS=(os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0").lstrip(":"))
FRAMES, WIDTH, HEIGHT, GRID = 6, 320, 180, 3


def read_png_rgb(path):
    """(width, height, rows of RGB tuples) of an 8-bit RGB or RGBA, non-interlaced PNG."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or colour not in (2, 6) or interlace:
        raise ValueError(f"{path}: expected 8-bit RGB(A), non-interlaced")
    channels = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * channels
    rows, prev, at = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[at], bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * channels:x * channels + 3]) for x in range(width)])
        prev = line
    return width, height, rows


def image_problem(width, height, rows, want_width, want_height):
    """None when the image has the wanted size and shows a scene; else what is wrong."""
    if (width, height) != (want_width, want_height):
        return f"size {width}x{height}, expected {want_width}x{want_height}"
    pixels = [p for row in rows for p in row]
    covered = sum(1 for p in pixels if max(abs(p[k] - CLEAR[k]) for k in range(3)) > 8)
    distinct = len(set(pixels))
    if covered < 0.005 * len(pixels) or distinct < 16:
        return f"blank: {covered} of {len(pixels)} pixels differ from the clear colour, {distinct} colours"
    return None


def self_test():
    """The image checks must reject a blank image and a wrong size."""
    blank = [[CLEAR] * WIDTH for _ in range(HEIGHT)]
    assert image_problem(WIDTH, HEIGHT, blank, WIDTH, HEIGHT), "a blank image passed the check"
    flat = [[CLEAR] * WIDTH for _ in range(HEIGHT - 20)] + [[(200, 10, 10)] * WIDTH for _ in range(20)]
    assert image_problem(WIDTH, HEIGHT, flat, WIDTH, HEIGHT), "a two-colour image passed the check"
    shaded = [[(x % 256, y % 256, 40) for x in range(WIDTH)] for y in range(HEIGHT)]
    assert image_problem(WIDTH, HEIGHT, shaded, WIDTH, HEIGHT) is None, "a shaded image failed the check"
    assert image_problem(WIDTH, HEIGHT + 1, shaded, WIDTH, HEIGHT), "a wrong size passed the check"


def lodview(args, name, extra):
    prefix = os.path.join(args.out, name)
    report = prefix + ".json"
    # lodview's own exit status, not xvfb-run's (which can fail its clean-up after lodview is done).
    cmd = [XVFB_WRAPPER, args.xvfb_run, "640x480x24", args.lodview, *args.packs, "--headless",
           "--frames", str(FRAMES), "--size", f"{WIDTH}x{HEIGHT}", "--grid", str(GRID), "--report", report,
           "--screenshot", prefix, "--shots", f"0,{FRAMES // 2}", *extra]
    print("+", " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    sys.stdout.write(proc.stdout)
    sys.stderr.write(proc.stderr)
    return proc, prefix, report


def run(args, name, extra):
    proc, prefix, report = lodview(args, name, extra)
    if proc.returncode != 0:
        raise AssertionError(f"{name}: lodview exited {proc.returncode}")
    for frame in (0, FRAMES // 2):
        png = f"{prefix}_{frame:04d}.png"
        problem = image_problem(*read_png_rgb(png), WIDTH, HEIGHT)
        if problem:
            raise AssertionError(f"{png}: {problem}")
    return json.load(open(report))


def check_report(name, report):
    def fail(what):
        raise AssertionError(f"{name}: report: {what}")
    instances = GRID * GRID
    if report.get("instances") != instances or report.get("width") != WIDTH or report.get("height") != HEIGHT:
        fail("expected instances 9, width 320, height 180")
    frames = report.get("frames")
    if not isinstance(frames, list) or len(frames) != FRAMES:
        fail(f"expected {FRAMES} frames")
    for f in frames:
        for key, kind in FRAME_FIELDS.items():
            if not isinstance(f.get(key), kind) and not (kind is float and isinstance(f.get(key), int)):
                fail(f"frame {f.get('frame')}: /{key}: expected {kind.__name__}")
        if f["visible"] + f["culled"] != instances:
            fail(f"frame {f['frame']}: visible + culled != {instances}")
        if sum(f["level_histogram"]) + f["pfrep_instances"] != f["instances_drawn"] or f["instances_drawn"] > f["visible"]:
            fail(f"frame {f['frame']}: level histogram does not sum to the instances drawn")
        if f["instances_drawn"] and (f["draw_calls"] < f["instances_drawn"] or f["triangles"] <= 0):
            fail(f"frame {f['frame']}: instances drawn without draw calls or triangles")
        if f["levels_resident"] < 1 or f["frame_ms"] <= 0:
            fail(f"frame {f['frame']}: no level resident or no frame time")
        if f["max_sse_px"] > 1.0001:
            fail(f"frame {f['frame']}: drawn level projects to {f['max_sse_px']} px")
    if not any(f["instances_drawn"] for f in frames):
        fail("nothing was drawn")
    summary = report.get("summary", {})
    for key in SUMMARY_FIELDS:
        if key not in summary:
            fail(f"/summary/{key}: missing")
    if summary["frames"] != FRAMES or summary["lodrt_allocations_beyond_requests"] != 0:
        fail("summary: expected 6 frames and no lodrt allocation beyond the level reads")
    if summary["lodrt_heap_allocations"] != 0 or sum(f["lodrt_heap_allocations"] for f in frames) != 0:
        fail("summary: lodrt made heap allocations during frames")
    if sum(f["stream_requests"] for f in frames) and not sum(f["lodrt_allocations"] for f in frames):
        fail("levels were streamed but no lodrt allocation was counted (the counter does not count)")
    if summary["frames_drawn_coarser"] != 0:
        fail("summary: a headless run must draw the selected levels")


def check_textured(args):
    """Bakes a textured shared scan and checks that lodview draws it with its base colour texture."""
    if not os.path.isfile(args.textured_source):
        required = os.environ.get("LODBAKE_REQUIRE_SHARED_MESHES", "") not in ("", "0")
        print(f"lodview textured test: {args.textured_source}: missing", file=sys.stderr)
        return 1 if required else 77
    os.makedirs(args.out, exist_ok=True)
    pack = os.path.join(args.out, "textured.glb")
    bake = subprocess.run([args.lodbake, "bake", args.textured_source, "-o", pack, "--preset", args.preset, "--quiet"],
                          env=BAKE_ENV, capture_output=True, text=True, timeout=600)
    if bake.returncode != 0:
        raise AssertionError(f"bake of {args.textured_source} failed: {bake.stderr.strip()}")
    args.packs = [pack]
    textured = run(args, "textured", ["--mode", "lod"])
    by_level = run(args, "textured_levels", ["--mode", "lod", "--colour-by-level"])
    check_report("textured", textured)
    check_report("textured_levels", by_level)
    for f in textured["frames"]:
        if f["textured_draw_calls"] != f["draw_calls"]:
            raise AssertionError(f"textured: frame {f['frame']}: {f['textured_draw_calls']} of {f['draw_calls']} "
                                 "draw calls used the base colour texture")
    if any(f["textured_draw_calls"] for f in by_level["frames"]):
        raise AssertionError("textured_levels: colour by level still drew textures")
    if not any(f["textured_draw_calls"] for f in textured["frames"]):
        raise AssertionError("textured: nothing was drawn")
    print(f"lodview textured check: 2 runs of {FRAMES} frames passed")
    return 0


def glb_json(path):
    """(bytes, JSON chunk as a dict, offset of the BIN chunk payload) of a GLB."""
    data = bytearray(open(path, "rb").read())
    json_length = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(bytes(data[20:20 + json_length]))
    return data, doc, 20 + json_length + 8


def break_coarsest_stream(src, dst, kind):
    """Copies pack src to dst with the header byte of its coarsest level's POSITION data stream
    zeroed (a meshopt attribute stream for web, the valence stream for compact); returns that
    level's number."""
    data, doc, bin_at = glb_json(src)
    root = next(n for n in doc["nodes"] if "MSFT_lod" in n.get("extensions", {}))
    ids = root["extensions"]["MSFT_lod"]["ids"]
    prim = doc["meshes"][doc["nodes"][ids[-1]]["mesh"]]["primitives"][0]
    if kind == "web":
        view = doc["bufferViews"][doc["accessors"][prim["attributes"]["POSITION"]]["bufferView"]]
        offset = view["extensions"]["EXT_meshopt_compression"].get("byteOffset", 0)
    else:
        view = doc["bufferViews"][prim["extensions"]["LODBAKE_valence_compression"]["bufferView"]]
        offset = view.get("byteOffset", 0)
    data[bin_at + offset] ^= 0xFF
    open(dst, "wb").write(data)
    return len(ids)




def check_format(args):
    """A --web or --compact bake of args.source draws what the plain pack draws, frame by frame."""
    os.makedirs(args.out, exist_ok=True)
    plain_pack = args.packs[0]
    pack = os.path.join(args.out, f"{args.format}.glb")
    bake = subprocess.run([args.lodbake, "bake", args.source, "-o", pack, "--preset", args.preset, f"--{args.format}",
                           "--quiet"], env=BAKE_ENV, capture_output=True, text=True, timeout=600)
    if bake.returncode != 0:
        raise AssertionError(f"--{args.format} bake of {args.source} failed: {bake.stderr.strip()}")
    args.packs = [pack]
    runs = {}
    for mode in ("lod", "lod0"):
        args.packs = [plain_pack]
        runs["plain", mode] = run(args, f"plain_{mode}", ["--mode", mode, "--warmup", "0"])
        args.packs = [pack]
        runs[args.format, mode] = run(args, f"{args.format}_{mode}", ["--mode", mode, "--warmup", "0"])
    for (name, mode), report in runs.items():
        check_report(f"{name}_{mode}", report)
    keys = ("visible", "instances_drawn", "draw_calls", "triangles", "level_histogram")
    for mode in ("lod", "lod0"):
        plain, other = runs["plain", mode], runs[args.format, mode]
        for a, b in zip(plain["frames"], other["frames"]):
            for key in keys:
                if a[key] != b[key]:
                    raise AssertionError(f"{args.format}_{mode}: frame {b['frame']}: {key} {b[key]}, "
                                         f"the plain pack's {a[key]}")
        if not other["summary"]["levels_decoded"] or other["summary"]["decode_ms"] <= 0:
            raise AssertionError(f"{args.format}_{mode}: no level decode was reported")
    broken = os.path.join(args.out, f"{args.format}_broken.glb")
    level = break_coarsest_stream(pack, broken, args.format)
    args.packs = [broken]
    proc, _, _ = lodview(args, f"{args.format}_broken", ["--mode", "lod"])
    expected = f"{broken}: model 0 level {level}: "
    if proc.returncode == 0 or expected not in proc.stderr:
        raise AssertionError(f"{broken}: a broken stream: expected a non-zero exit and '{expected}...', "
                             f"got exit {proc.returncode}")
    print(f"lodview --{args.format} check: {len(runs)} runs of {FRAMES} frames matched the plain pack; "
          "the broken copy was refused")
    return 0


def check_transform(args):
    """glTF-Transform's meshopt and quantize outputs of args.source draw non-blank images."""
    for path, what in ((args.gltf_transform, "gltf-transform (npm ci in scripts/node-bench)"), (args.source, "source")):
        if not os.path.isfile(path):
            required = what == "source" and os.environ.get("LODBAKE_REQUIRE_SHARED_MESHES", "") not in ("", "0")
            print(f"lodview glTF-Transform test: {path}: missing {what}", file=sys.stderr)
            return 1 if required else 77
    os.makedirs(args.out, exist_ok=True)
    for command in ("meshopt", "quantize"):
        out = os.path.join(args.out, f"transform_{command}.glb")
        proc = subprocess.run([args.gltf_transform, command, args.source, out], capture_output=True, text=True,
                              timeout=600)
        if proc.returncode != 0:
            raise AssertionError(f"gltf-transform {command} {args.source} failed: {proc.stderr.strip()}")
        args.packs = [out]
        check_report(f"transform_{command}", run(args, f"transform_{command}", ["--mode", "lod"]))
    print(f"lodview glTF-Transform check: 2 runs of {FRAMES} frames passed")
    return 0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--textured-source")
    parser.add_argument("--lodbake")
    parser.add_argument("--preset")
    parser.add_argument("--lodview")
    parser.add_argument("--xvfb-run")
    parser.add_argument("--out")
    parser.add_argument("--missing")
    parser.add_argument("--format", choices=("web", "compact"))
    parser.add_argument("--source")
    parser.add_argument("--gltf-transform")
    parser.add_argument("packs", nargs="*")
    args = parser.parse_args()
    if args.missing:
        required = os.environ.get("LODBAKE_REQUIRE_LODVIEW", "") not in ("", "0")
        print(f"lodview test: {args.missing}", file=sys.stderr)
        return 1 if required else 77
    self_test()
    if args.textured_source:
        return check_textured(args)
    if args.format:
        return check_format(args)
    if args.gltf_transform:
        return check_transform(args)
    os.makedirs(args.out, exist_ok=True)
    lod = run(args, "lod", ["--mode", "lod"])
    lod0 = run(args, "lod0", ["--mode", "lod0"])
    levels = run(args, "levels", ["--mode", "lod", "--colour-by-level"])
    pfrep = run(args, "pfrep", ["--mode", "pfrep"])
    for name, report in (("lod", lod), ("lod0", lod0), ("levels", levels), ("pfrep", pfrep)):
        check_report(name, report)
    if any(f["pfrep_instances"] for f in lod["frames"]):
        raise AssertionError("lod: instances were drawn from PFRep outside --mode pfrep")
    if not any(f["pfrep_instances"] and f["pfrep_triangles"] and f["pfrep_changes"] for f in pfrep["frames"]):
        raise AssertionError("pfrep: no instance was refined and drawn from its PFRep prefix")
    for a, b in zip(lod["frames"], lod0["frames"]):
        if any(b["level_histogram"][1:]):
            raise AssertionError(f"lod0: frame {b['frame']} drew a level other than 0")
        if b["visible"] != a["visible"] or b["triangles"] < a["triangles"]:
            raise AssertionError(f"lod0: frame {b['frame']}: fewer triangles than with LOD on the same path")
    if read_png_rgb(os.path.join(args.out, "levels_0000.png")) == read_png_rgb(os.path.join(args.out, "lod_0000.png")):
        raise AssertionError("colour by level drew the same image as the plain run")
    print(f"lodview check: 4 runs of {FRAMES} frames passed")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (AssertionError, ValueError, OSError, subprocess.TimeoutExpired) as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(1)
