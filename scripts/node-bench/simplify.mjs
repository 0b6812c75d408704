// Quality anchor for tests/benchmarks/simplify_bench: meshoptimizer 1.3's simplifyWithUpdate.
//
// usage: node simplify.mjs INPUT.ply OUT_PREFIX TRIANGLES...
// Reads a binary little-endian PLY (as `lodbake` writes it), and for every requested triangle count
// simplifies the ORIGINAL mesh with simplifyWithUpdate (positions only, no error limit, no flags),
// writes OUT_PREFIX_<count>.ply and prints one JSON line per level:
//   {"target":N,"triangles":M,"error":E,"seconds":S,"path":"..."}
// Exit code 1 with a one-line message on any problem.
import fs from 'node:fs';
import { MeshoptSimplifier } from 'meshoptimizer';

const SCALAR = {
    char: ['getInt8', 1], int8: ['getInt8', 1], uchar: ['getUint8', 1], uint8: ['getUint8', 1],
    short: ['getInt16', 2], int16: ['getInt16', 2], ushort: ['getUint16', 2], uint16: ['getUint16', 2],
    int: ['getInt32', 4], int32: ['getInt32', 4], uint: ['getUint32', 4], uint32: ['getUint32', 4],
    float: ['getFloat32', 4], float32: ['getFloat32', 4], double: ['getFloat64', 8], float64: ['getFloat64', 8],
};

function fail(message) {
    process.stderr.write(`error: ${message}\n`);
    process.exit(1);
}

function readPly(path) {
    const bytes = fs.readFileSync(path);
    const marker = bytes.indexOf('end_header\n');
    if (marker < 0) fail(`${path}: header: expected end_header`);
    const header = bytes.subarray(0, marker).toString('latin1').split('\n');
    if (!header.includes('format binary_little_endian 1.0')) fail(`${path}: header: expected binary_little_endian`);
    const elements = [];
    for (const line of header) {
        const t = line.trim().split(/\s+/);
        if (t[0] === 'element') elements.push({ name: t[1], count: Number(t[2]), props: [] });
        else if (t[0] === 'property') {
            const e = elements[elements.length - 1];
            if (t[1] === 'list') e.props.push({ list: true, countType: t[2], itemType: t[3], name: t[4] });
            else e.props.push({ list: false, type: t[1], name: t[2] });
        }
    }
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    let offset = marker + 'end_header\n'.length;
    let positions = null, indices = null;
    const read = (type) => {
        const [getter, size] = SCALAR[type] || fail(`${path}: header: unknown type '${type}'`);
        const v = view[getter](offset, true);
        offset += size;
        return v;
    };
    for (const e of elements) {
        if (e.name === 'vertex') {
            positions = new Float32Array(e.count * 3);
            const axis = { x: 0, y: 1, z: 2 };
            for (let i = 0; i < e.count; ++i) {
                for (const p of e.props) {
                    if (p.list) { const n = read(p.countType); for (let k = 0; k < n; ++k) read(p.itemType); continue; }
                    const v = read(p.type);
                    if (p.name in axis) positions[i * 3 + axis[p.name]] = v;
                }
            }
        } else if (e.name === 'face') {
            const out = [];
            for (let i = 0; i < e.count; ++i) {
                for (const p of e.props) {
                    if (!p.list) { read(p.type); continue; }
                    const n = read(p.countType);
                    const poly = [];
                    for (let k = 0; k < n; ++k) poly.push(read(p.itemType));
                    if (p.name !== 'vertex_indices' && p.name !== 'vertex_index') continue;
                    for (let k = 1; k + 1 < n; ++k) out.push(poly[0], poly[k], poly[k + 1]);
                }
            }
            indices = Uint32Array.from(out);
        } else {
            fail(`${path}: element ${e.name}: not supported by this script`);
        }
    }
    if (!positions || !indices) fail(`${path}: expected vertex and face elements`);
    return { positions, indices };
}

function writePly(path, positions, indices, indexCount) {
    const vertexCount = positions.length / 3;
    const faceCount = indexCount / 3;
    const header = `ply\nformat binary_little_endian 1.0\ncomment meshoptimizer simplifyWithUpdate\n` +
        `element vertex ${vertexCount}\nproperty float x\nproperty float y\nproperty float z\n` +
        `element face ${faceCount}\nproperty list uchar int vertex_indices\nend_header\n`;
    const body = Buffer.alloc(vertexCount * 12 + faceCount * 13);
    let o = 0;
    for (let i = 0; i < vertexCount * 3; ++i, o += 4) body.writeFloatLE(positions[i], o);
    for (let f = 0; f < faceCount; ++f) {
        body.writeUInt8(3, o++);
        for (let k = 0; k < 3; ++k, o += 4) body.writeInt32LE(indices[f * 3 + k], o);
    }
    fs.writeFileSync(path, Buffer.concat([Buffer.from(header, 'latin1'), body]));
}

const [input, prefix, ...targets] = process.argv.slice(2);
if (!input || !prefix || targets.length === 0) fail('usage: node simplify.mjs INPUT.ply OUT_PREFIX TRIANGLES...');
await MeshoptSimplifier.ready;
const mesh = readPly(input);
const kNoErrorLimit = 3.4028234663852886e38; // FLT_MAX: stop only at the triangle target
for (const target of targets.map(Number)) {
    if (!(target > 0) || target * 3 > mesh.indices.length) fail(`target ${target}: expected 1..${mesh.indices.length / 3}`);
    // simplifyWithUpdate rewrites both arrays in place, so every level starts from a fresh copy.
    const indices = mesh.indices.slice();
    const positions = mesh.positions.slice();
    const start = process.hrtime.bigint();
    const [indexCount, error] = MeshoptSimplifier.simplifyWithUpdate(
        indices, positions, 3, new Float32Array(0), 0, [], null, target * 3, kNoErrorLimit, []);
    const seconds = Number(process.hrtime.bigint() - start) / 1e9;
    const path = `${prefix}_${target}.ply`;
    writePly(path, positions, indices, indexCount);
    console.log(JSON.stringify({ target, triangles: indexCount / 3, error, seconds, path }));
}
