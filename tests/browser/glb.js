// Minimal GLB reading and writing for the browser tests: the JSON chunk parsed, the BIN chunk kept
// as bytes, and the broken copies the control tests serve.
"use strict";
const zlib = require("zlib");

const kMagic = 0x46546c67; // "glTF"
const kJson = 0x4e4f534a;
const kBin = 0x004e4942;

// Returns { json, bin } or throws with what is wrong.
function parseGlb(bytes) {
    if (bytes.length < 20 || bytes.readUInt32LE(0) !== kMagic) throw new Error("not a GLB file (magic)");
    if (bytes.readUInt32LE(8) !== bytes.length) {
        throw new Error(`GLB length field ${bytes.readUInt32LE(8)} != file size ${bytes.length}`);
    }
    const jsonLength = bytes.readUInt32LE(12);
    if (bytes.readUInt32LE(16) !== kJson || 20 + jsonLength > bytes.length) {
        throw new Error("GLB JSON chunk is missing or truncated");
    }
    const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString("utf8"));
    let bin = Buffer.alloc(0);
    const at = 20 + jsonLength;
    if (at + 8 <= bytes.length && bytes.readUInt32LE(at + 4) === kBin) {
        bin = bytes.subarray(at + 8, at + 8 + bytes.readUInt32LE(at));
    }
    return { json, bin };
}

function pad4(buffer, fill) {
    const extra = (4 - (buffer.length % 4)) % 4;
    return extra ? Buffer.concat([buffer, Buffer.alloc(extra, fill)]) : buffer;
}

function writeGlb(json, bin) {
    const jsonBytes = pad4(Buffer.from(JSON.stringify(json), "utf8"), 0x20);
    const binBytes = pad4(bin, 0);
    const header = Buffer.alloc(12);
    const total = 12 + 8 + jsonBytes.length + (binBytes.length ? 8 + binBytes.length : 0);
    header.writeUInt32LE(kMagic, 0);
    header.writeUInt32LE(2, 4);
    header.writeUInt32LE(total, 8);
    const chunk = (type, body) => {
        const h = Buffer.alloc(8);
        h.writeUInt32LE(body.length, 0);
        h.writeUInt32LE(type, 4);
        return [h, body];
    };
    const parts = [header, ...chunk(kJson, jsonBytes)];
    if (binBytes.length) parts.push(...chunk(kBin, binBytes));
    return Buffer.concat(parts);
}

// The pack's LOD chain: the first scene node carrying MSFT_lod, its mesh first (LOD0, finest) and
// then its MSFT_lod ids; for each level, the indices its mesh draws.
// The levels a client draws, finest first: per MSFT_lod level, the indices of every LOD group's
// node at that level summed (a pack of several groups, a scene, draws them all at once); a pack
// without MSFT_lod draws its first mesh node. Groups of different level counts are refused: a
// client's per-level totals would then not be a level of every group.
function lodLevels(json) {
    const nodes = json.nodes || [];
    const roots = nodes.filter((n) => n.extensions && n.extensions.MSFT_lod);
    const chains = roots.length ? roots.map((root) => [root, ...root.extensions.MSFT_lod.ids.map((id) => nodes[id])])
        : [nodes.filter((n) => n.mesh !== undefined).slice(0, 1)];
    if (chains.some((chain) => chain.length !== chains[0].length)) {
        throw new Error(`LOD groups of different level counts: ${chains.map((c) => c.length).join(" ")}`);
    }
    return chains[0].map((_, level) => {
        let indices = 0;
        const materials = [];
        for (const chain of chains) {
            const mesh = json.meshes[chain[level].mesh];
            for (const p of mesh.primitives) {
                indices += json.accessors[p.indices !== undefined ? p.indices : p.attributes.POSITION].count;
                materials.push(p.material);
            }
        }
        return { node: chains.map((chain) => chain[level].name).join("+"), indices, materials };
    });
}

// One GLB whose default scene places the meshes of several single-mesh GLBs (`parts`, parsed), each
// part at the nodes `placements[i]` lists ({name, translation, rotation, scale}); a part listed twice is
// instanced (its mesh written once). Untextured parts only: their materials are dropped.
function sceneOf(parts, placements) {
    const json = { asset: { version: "2.0", generator: "lodbake browser test" }, scene: 0, scenes: [{ nodes: [] }],
        nodes: [], meshes: [], accessors: [], bufferViews: [], buffers: [{ byteLength: 0 }] };
    const bins = [];
    let offset = 0;
    parts.forEach(({ json: part, bin }, i) => {
        if (part.meshes.length !== 1) throw new Error(`scene part ${i}: one mesh was expected`);
        const views = json.bufferViews.length, accessors = json.accessors.length;
        for (const view of part.bufferViews) {
            json.bufferViews.push({ ...view, buffer: 0, byteOffset: offset + (view.byteOffset || 0) });
        }
        for (const accessor of part.accessors) {
            json.accessors.push({ ...accessor, bufferView: accessor.bufferView + views });
        }
        const mesh = JSON.parse(JSON.stringify(part.meshes[0]));
        for (const p of mesh.primitives) {
            delete p.material;
            for (const key of Object.keys(p.attributes)) p.attributes[key] += accessors;
            if (p.indices !== undefined) p.indices += accessors;
        }
        json.meshes.push(mesh);
        const padded = pad4(bin, 0);
        bins.push(padded);
        offset += padded.length;
        for (const placement of placements[i]) {
            json.nodes.push({ ...placement, mesh: json.meshes.length - 1 });
            json.scenes[0].nodes.push(json.nodes.length - 1);
        }
    });
    const bin = Buffer.concat(bins);
    json.buffers[0].byteLength = bin.length;
    return writeGlb(json, bin);
}

function crc32(bytes) {
    let c = ~0;
    for (const b of bytes) {
        c ^= b;
        for (let k = 0; k < 8; ++k) c = (c >>> 1) ^ (0xedb88320 & -(c & 1));
    }
    return ~c >>> 0;
}

// An 8x8 RGB PNG of one colour.
function flatPng(rgb) {
    const size = 8;
    const rows = Buffer.alloc(size * (1 + 3 * size));
    for (let y = 0; y < size; ++y)
        for (let x = 0; x < size; ++x) rows.set(rgb, y * (1 + 3 * size) + 1 + 3 * x);
    const chunk = (type, body) => {
        const length = Buffer.alloc(4);
        length.writeUInt32BE(body.length);
        const typed = Buffer.concat([Buffer.from(type, "ascii"), body]);
        const crc = Buffer.alloc(4);
        crc.writeUInt32BE(crc32(typed));
        return Buffer.concat([length, typed, crc]);
    };
    const ihdr = Buffer.alloc(13);
    ihdr.writeUInt32BE(size, 0);
    ihdr.writeUInt32BE(size, 4);
    ihdr[8] = 8; // bit depth
    ihdr[9] = 2; // RGB
    return Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk("IHDR", ihdr),
        chunk("IDAT", zlib.deflateSync(rows)), chunk("IEND", Buffer.alloc(0))]);
}

// A copy of the pack broken on purpose, for the control tests:
//   truncate     - the file cut in the middle of LOD0's positions;
//   flat-texture - every base colour texture's image replaced by a PNG of one flat colour;
//   drop-level   - the finest level left out of MSFT_lod's ids, so a client receives one level less;
//   zero-positions - every level's positions zeroed, so the pack draws nothing.
function breakPack(bytes, how) {
    const { json, bin } = parseGlb(bytes);
    if (how === "truncate") {
        // Cut in the middle of LOD0's positions, which every client draws (a cut elsewhere may
        // only remove data a client does not read: three.js reads LOD0 only).
        const lod0 = json.nodes[json.scenes[json.scene || 0].nodes[0]];
        const positions = json.accessors[json.meshes[lod0.mesh].primitives[0].attributes.POSITION];
        const view = json.bufferViews[positions.bufferView];
        const binStart = 20 + bytes.readUInt32LE(12) + 8;
        return bytes.subarray(0, binStart + (view.byteOffset || 0) + Math.floor(view.byteLength / 2));
    }
    if (how === "flat-texture") {
        const png = flatPng([200, 120, 60]); // a saturated colour: the hue alone must not pass as a texture
        const offset = bin.length + ((4 - (bin.length % 4)) % 4);
        json.bufferViews.push({ buffer: 0, byteOffset: offset, byteLength: png.length });
        const view = json.bufferViews.length - 1;
        for (const material of json.materials || []) {
            const ref = material.pbrMetallicRoughness && material.pbrMetallicRoughness.baseColorTexture;
            if (!ref) continue;
            const image = json.images[json.textures[ref.index].source];
            image.bufferView = view;
            image.mimeType = "image/png";
        }
        const grown = Buffer.concat([pad4(bin, 0), png]);
        json.buffers[0].byteLength = grown.length;
        return writeGlb(json, grown);
    }
    if (how === "drop-level") {
        const root = json.nodes.find((n) => n.extensions && n.extensions.MSFT_lod);
        if (!root || root.extensions.MSFT_lod.ids.length < 1) {
            throw new Error("drop-level: the pack has no MSFT_lod levels to drop");
        }
        // The finest level is the node's own mesh: LOD1's mesh takes its place.
        const ids = root.extensions.MSFT_lod.ids;
        root.mesh = json.nodes[ids[0]].mesh;
        root.extensions.MSFT_lod.ids = ids.slice(1);
        return writeGlb(json, bin);
    }
    if (how === "zero-positions") {
        // Every vertex at the origin (accessor bounds left as they were): a valid file that draws nothing.
        const copy = Buffer.from(bin);
        for (const mesh of json.meshes) {
            for (const p of mesh.primitives) {
                const view = json.bufferViews[json.accessors[p.attributes.POSITION].bufferView];
                copy.fill(0, view.byteOffset || 0, (view.byteOffset || 0) + view.byteLength);
            }
        }
        return writeGlb(json, copy);
    }
    throw new Error(`unknown --break mode "${how}" (truncate, flat-texture, drop-level, zero-positions)`);
}

module.exports = { parseGlb, writeGlb, lodLevels, sceneOf, breakPack, flatPng };
