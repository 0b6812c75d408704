#!/usr/bin/env python3
"""Textured side-by-side benchmark (issue 28): our bake's LOD chain against gltfpack 1.3 on textured
and atlased assets, at equal triangle counts, in the same run.

For every asset and every ratio of the default chain (0.5, 0.25, 0.1, 0.03, 0.01):
  - ours: `lodbake bake IN -o OUT.glb --report` (levels are the pack's meshes 1..n);
  - anchor: `gltfpack -i IN -o OUT.glb -si R -se 1 -noq -kv` (-kv keeps the UVs of assets whose
    material names no texture, so both sides keep the same seams);
  - both are measured against the input with ../shared/eval/meshdist.py's two-sided distance (mean,
    Hausdorff, relative to the input's diagonal) and with the UV displacement: the mean UV-space
    distance between a surface sample's UV on the level and the UV of the input at the sample's
    nearest input point (texture stretch and drift; both sides sampled with the same seed).
When the two triangle counts differ by more than 2 %, the side with more triangles is the one that
stopped early: the other one is made again at that count (gltfpack with the matching -si, ours with
`bake --levels`), so every comparison is at equal triangles.

Prints one BAR| line per bar (the format of tests/benchmarks/bench_bar.h):
  triangles of every level within 5 % of its target (or stopped, with the chain's note), no two
  levels with the same triangle count, mean, Hausdorff and UV displacement <= gltfpack's, and the
  goal mean <= 0.8x gltfpack's. Exit status 1 with --check when a bar is not met.
usage: bench_textured.py --lodbake BIN --gltfpack BIN --eval DIR [--check] ASSET...
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile

RATIOS = [0.5, 0.25, 0.1, 0.03, 0.01]
BENCH = 'textured_bench'


def load_eval(eval_dir):
    sys.path.insert(0, eval_dir)
    import meshdist  # noqa: E402  (../shared/eval, next to the repository)
    import meshio  # noqa: E402
    return meshdist, meshio


def read_obj_uv(path):
    """Positions, triangles and per-vertex UVs of an OBJ, one vertex per (v, vt) pair."""
    import numpy as np
    V, T, F, key = [], [], [], {}
    out_v, out_t = [], []
    with open(path, 'r', errors='replace') as f:
        for line in f:
            if line.startswith('v '):
                t = line.split(); V.append((float(t[1]), float(t[2]), float(t[3])))
            elif line.startswith('vt '):
                t = line.split(); T.append((float(t[1]), float(t[2])))
            elif line.startswith('f '):
                idx = []
                for tok in line.split()[1:]:
                    parts = tok.split('/')
                    vi = int(parts[0]); vi = vi - 1 if vi > 0 else len(V) + vi
                    ti = int(parts[1]) if len(parts) > 1 and parts[1] else 0
                    ti = ti - 1 if ti > 0 else (len(T) + ti if ti < 0 else -1)
                    k = (vi, ti)
                    if k not in key:
                        key[k] = len(out_v); out_v.append(V[vi]); out_t.append((T[ti][0], 1.0 - T[ti][1]) if ti >= 0 else (0.0, 0.0))
                    idx.append(key[k])
                for j in range(1, len(idx) - 1):
                    F.append((idx[0], idx[j], idx[j + 1]))
    return np.array(out_v, dtype=np.float64), np.array(F, dtype=np.int64).reshape(-1, 3), np.array(out_t)


def read_gltf_uv(meshio, path, mesh_index):
    import numpy as np
    doc, buffers = meshio.read_gltf_doc(path)
    Vs, Fs, Ts, base = [], [], [], 0
    for prim in doc['meshes'][mesh_index]['primitives']:
        if prim.get('mode', 4) != 4 or 'POSITION' not in prim['attributes']:
            continue
        V = meshio.accessor(doc, buffers, prim['attributes']['POSITION'])
        I = (meshio.accessor(doc, buffers, prim['indices']).astype(np.int64).reshape(-1, 3)
             if 'indices' in prim else np.arange(len(V)).reshape(-1, 3))
        T = (meshio.accessor(doc, buffers, prim['attributes']['TEXCOORD_0'])
             if 'TEXCOORD_0' in prim['attributes'] else np.zeros((len(V), 2)))
        Vs.append(V); Fs.append(I + base); Ts.append(T[:, :2]); base += len(V)
    return np.concatenate(Vs), np.concatenate(Fs), np.concatenate(Ts)


def read_mesh_uv(meshio, path, mesh_index=0):
    if path.lower().endswith('.obj'):
        return read_obj_uv(path)
    return read_gltf_uv(meshio, path, mesh_index)


def mesh_count(meshio, path):
    doc, _ = meshio.read_gltf_doc(path)
    return len(doc.get('meshes', []))


def uv_displacement(ref, approx, samples=100000, seed=7):
    """Mean |UV(level sample) - UV(input at its nearest point)|."""
    import numpy as np
    import open3d as o3d
    V1, F1, T1 = ref
    V2, F2, T2 = approx
    rng = np.random.default_rng(seed)
    A, B, C = V2[F2[:, 0]], V2[F2[:, 1]], V2[F2[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(B - A, C - A), axis=1)
    idx = rng.choice(len(F2), size=samples, p=area / area.sum())
    r1 = np.sqrt(rng.random(samples)); r2 = rng.random(samples)
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], axis=1)
    P = w[:, :1] * A[idx] + w[:, 1:2] * B[idx] + w[:, 2:3] * C[idx]
    uv_a = w[:, :1] * T2[F2[idx, 0]] + w[:, 1:2] * T2[F2[idx, 1]] + w[:, 2:3] * T2[F2[idx, 2]]
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(V1.astype(np.float32)), o3d.core.Tensor(F1.astype(np.uint32)))
    hit = scene.compute_closest_points(o3d.core.Tensor(P.astype(np.float32)))
    prim = hit['primitive_ids'].numpy().astype(np.int64)
    bu = hit['primitive_uvs'].numpy().astype(np.float64)
    b1, b2 = bu[:, 0], bu[:, 1]
    b0 = 1 - b1 - b2
    uv_r = b0[:, None] * T1[F1[prim, 0]] + b1[:, None] * T1[F1[prim, 1]] + b2[:, None] * T1[F1[prim, 2]]
    return float(np.linalg.norm(uv_a - uv_r, axis=1).mean())


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise RuntimeError('%s failed (%d): %s' % (' '.join(cmd), r.returncode, r.stderr.strip()[-400:]))
    return r


class Bars:
    def __init__(self):
        self.count = 0
        self.met = 0

    @staticmethod
    def num(v):
        return '-' if v is None or (isinstance(v, float) and math.isnan(v)) else '%.4g' % v

    def add(self, name, ours, anchor, limit, on_ratio, met=None):
        ratio = ours / anchor if (anchor and anchor > 0 and ours is not None) else float('nan')
        value = ratio if on_ratio else ours
        if met is None:
            met = value is not None and not math.isnan(value) and value <= limit
        self.count += 1
        self.met += bool(met)
        print('BAR|%s|%s|%s|%s|%s|%s <= %.4g|%s' % (BENCH, name, self.num(ours), self.num(anchor), self.num(ratio),
                                                   'ratio' if on_ratio else 'ours', limit,
                                                   'met' if met else 'NOT met'), flush=True)


def bake_ours(args, path, out, levels=None):
    cmd = [args.lodbake, 'bake', path, '-o', out, '--report', out + '.json', '--threads', '2']
    if levels:
        cmd += ['--levels', ','.join('%.9g' % r for r in levels)]
    r = run(cmd)
    notes = [l for l in r.stderr.splitlines() if 'lod chain' in l]
    report = json.load(open(out + '.json'))
    levels = report['assets'][0]['levels']
    return [l['triangles'] for l in levels], notes


def gltfpack(args, path, out, ratio):
    r = run([args.gltfpack, '-i', path, '-o', out, '-si', '%.9g' % ratio, '-se', '1', '-noq', '-kv', '-v'])
    m = re.search(r'output: \d+ mesh primitives \((\d+) triangles', r.stdout + r.stderr)
    return int(m.group(1)) if m else 0


def measure(meshdist, meshio, ref, path, mesh_index):
    V, F, T = read_mesh_uv(meshio, path, mesh_index)
    d = meshdist.dist(ref[0], ref[1], V, F)
    d['uv'] = uv_displacement(ref, (V, F, T))
    d['tris'] = int(len(F))
    return d


def bench_asset(args, meshdist, meshio, bars, path, tmp):
    name = os.path.splitext(os.path.basename(path))[0]
    ref = read_mesh_uv(meshio, path, 0)
    n_input = len(ref[1])
    ours_glb = os.path.join(tmp, name + '_ours.glb')
    tris, notes = bake_ours(args, path, ours_glb)
    n_ours = tris[0]
    for note in notes:
        print('# %s: %s' % (name, note))
    levels = tris[1:]
    print('# %s: input %d triangles, ours %s' % (name, n_input, ' '.join(str(t) for t in tris)))
    # Our levels in ratio order: a level omitted after a stop has no mesh of its own.
    stopped = any('stopped at' in n for n in notes)
    bars.add('%s: levels with the same triangle count' % name,
             float(len(levels) - len(set(levels))), None, 0, False)
    print('# %-28s %5s %7s %7s %7s | %9s %9s %6s | %9s %9s %6s | %9s %9s %6s' % (
        'asset level', 'ratio', 'target', 'ours', 'gltfp', 'mean', 'g_mean', 'ratio', 'hausd', 'g_hausd', 'ratio',
        'uv', 'g_uv', 'ratio'))
    for i, ratio in enumerate(RATIOS):
        target = int(math.ceil(ratio * n_ours))
        label = '%s L%d (%g)' % (name, i + 1, ratio)
        if i >= len(levels):
            bars.add('%s triangles / target (omitted after a stop: %s)' % (label, levels[-1] if levels else '-'),
                     float(levels[-1]) if levels else None, float(target), 1.05, True, met=stopped)
            continue
        ours_t = levels[i]
        bars.add('%s triangles / target%s' % (label, ' (stopped, reason noted)' if ours_t > 1.05 * target else ''),
                 float(ours_t), float(target), 1.05, True, met=ours_t <= 1.05 * target or stopped)
        g_path = os.path.join(tmp, '%s_g_%g.glb' % (name, ratio))
        g_t = gltfpack(args, path, g_path, ratio)
        ours_path, ours_index = ours_glb, i + 1
        if abs(g_t - ours_t) > 0.02 * max(g_t, ours_t):
            if g_t > ours_t:  # gltfpack stopped early: ours again at its count
                extra = os.path.join(tmp, '%s_ours_%d.glb' % (name, g_t))
                t2, _ = bake_ours(args, path, extra, [g_t / n_ours])
                ours_path, ours_index, ours_t = extra, 1, t2[1]
            else:  # ours stopped early, or gltfpack wrote nothing: gltfpack again at our count
                g_t = gltfpack(args, path, g_path, ours_t / n_input)
        o = measure(meshdist, meshio, ref, ours_path, ours_index)
        if g_t == 0:
            print('# %s: gltfpack wrote no triangles at -si %g nor at our %d: nothing to compare' % (
                label, ratio, ours_t))
            for what in ('mean', 'hausdorff', 'uv'):
                bars.add('%s %s / gltfpack (gltfpack: 0 triangles)' % (label, what), o[what], None, 1.0, True,
                         met=False)
            continue
        g = measure(meshdist, meshio, ref, g_path, 0)
        print('# %-28s %5g %7d %7d %7d | %9.3e %9.3e %6.3f | %9.3e %9.3e %6.3f | %9.3e %9.3e %6.3f' % (
            label, ratio, target, o['tris'], g['tris'], o['mean'], g['mean'], o['mean'] / g['mean'], o['hausdorff'],
            g['hausdorff'], o['hausdorff'] / g['hausdorff'], o['uv'], g['uv'], o['uv'] / max(g['uv'], 1e-30)),
            flush=True)
        tag = ' at %d/%d tris' % (o['tris'], g['tris'])
        bars.add('%s mean / gltfpack%s' % (label, tag), o['mean'], g['mean'], 1.0, True)
        bars.add('%s mean / gltfpack, goal%s' % (label, tag), o['mean'], g['mean'], 0.8, True)
        bars.add('%s hausdorff / gltfpack%s' % (label, tag), o['hausdorff'], g['hausdorff'], 1.0, True)
        bars.add('%s uv displacement / gltfpack%s' % (label, tag), o['uv'], g['uv'], 1.0, True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--lodbake', required=True)
    ap.add_argument('--gltfpack', required=True)
    ap.add_argument('--eval', required=True, help='folder of meshdist.py (../shared/eval)')
    ap.add_argument('--check', action='store_true')
    ap.add_argument('assets', nargs='+')
    a = ap.parse_args()
    meshdist, meshio = load_eval(a.eval)
    bars = Bars()
    with tempfile.TemporaryDirectory(prefix='textured_bench.') as tmp:
        for path in a.assets:
            bench_asset(a, meshdist, meshio, bars, path, tmp)
    print('%s: %d of %d bars met' % (BENCH, bars.met, bars.count))
    return 1 if a.check and bars.met != bars.count else 0


if __name__ == '__main__':
    sys.exit(main())
