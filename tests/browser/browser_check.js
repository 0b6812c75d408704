#!/usr/bin/env node
// Real clients for lodbake packs: serves a pack, a client page and the client library (Babylon.js or
// three.js from scripts/node/node_modules) over HTTP on 127.0.0.1, opens the page in headless
// Chromium (WebGL through SwiftShader, so no GPU is needed), receives the page's measurements and
// checks them against what the pack says. Node's standard library only.
//
//   browser_check.js bake --lodbake EXE --source MESH|scene:MESH_A+MESH_B --out PACK [-- BAKE_OPTION...]
//   browser_check.js check --client babylon|three --pack PACK --expect plain|textured[,uses=EXT...]
//       --node-modules DIR --out DIR [--chromium EXE] [--size WxH] [--timeout S]
//       [--break truncate|flat-texture|drop-level|zero-positions --expect-failure TEXT]
//
// check passes (exit 0) when the client renders a non-blank image of the requested size and, for
// Babylon, received every MSFT_lod level of the pack, coarsest first, each drawing exactly its
// level's indices (three.js, without MSFT_lod, must draw LOD0's); with `textured`, when the albedo
// recovered from renders with and without the base colour textures varies over the surface. Every
// failed check is one stderr line `<pack>: <client>: <what was expected>`, exit 1. Exit 77
// (skipped, with the reason) when Chromium or the npm packages are missing, unless
// LODBAKE_REQUIRE_BROWSER is set, or the source mesh of a bake is missing, unless
// LODBAKE_REQUIRE_SHARED_MESHES is set.
// bake with `scene:A+B` first writes a glTF scene of the two meshes (converted by `lodbake convert`):
// A at two nodes (instanced), B rotated and scaled to A's size at a third, every node named; the
// bake must keep them as three LOD groups with those names (checked here, before any client).
// A control (--break) serves a copy of the pack broken on purpose and passes only when the check
// fails with a message containing --expect-failure.
"use strict";
const fs = require("fs");
const http = require("http");
const path = require("path");
const { spawn, spawnSync } = require("child_process");
const { parseGlb, lodLevels, sceneOf, breakPack } = require("./glb.js");

const kSkip = 77;
const kPageDir = path.join(__dirname, "page");
// The packages each client page loads (Babylon's page also takes meshoptimizer's decoder from three).
const kLibraries = { babylon: ["babylonjs", "babylonjs-loaders", "three"], three: ["three"] };
// Thresholds of the checks. A rendered model covers far more than 1 % of the frame (the camera is
// fitted to it). Textures change the mean colour by more than a few 8-bit steps, and the albedo
// recovered from the textured and untextured renders varies over the surface: a base colour texture
// of one flat colour, whatever its hue, stays near 0 (shading, specular and rounding only), a
// photographic texture far above.
const kMinForeground = 0.01;
const kMinTextureDifference = 4;
const kMinAlbedoVariation = 0.25;

function required(name) {
    return !["", "0", undefined].includes(process.env[name]);
}

function parseArgs(argv) {
    const args = { _: [], rest: [] };
    for (let i = 0; i < argv.length; ++i) {
        if (argv[i] === "--") { args.rest = argv.slice(i + 1); break; }
        if (argv[i].startsWith("--")) {
            if (i + 1 >= argv.length) throw new Error(`${argv[i]}: a value was expected`);
            args[argv[i].slice(2)] = argv[++i];
        } else {
            args._.push(argv[i]);
        }
    }
    return args;
}

// lodbake runs without LeakSanitizer's exit check in sanitizer builds: its tracer can crash at the
// exit of a multi-threaded bake (as tests/baker/gltf/gltf_test_util.h's withoutLeakCheck does).
const kBakeEnv = {
    ...process.env,
    ASAN_OPTIONS: `${process.env.ASAN_OPTIONS || ""}:detect_leaks=0`.replace(/^:/, ""),
};

function bake(args) {
    for (const key of ["lodbake", "source", "out"]) if (!args[key]) throw new Error(`bake: --${key} was expected`);
    const sources = args.source.startsWith("scene:") ? args.source.slice(6).split("+") : [args.source];
    for (const source of sources) {
        if (!fs.existsSync(source)) {
            console.error(`browser test: ${source}: missing (the shared meshes next to the repository)`);
            return required("LODBAKE_REQUIRE_SHARED_MESHES") ? 1 : kSkip;
        }
    }
    fs.mkdirSync(path.dirname(args.out), { recursive: true });
    const input = sources.length === 1 ? sources[0] : writeScene(args.lodbake, sources, args.out);
    const run = spawnSync(args.lodbake, ["bake", input, "-o", args.out, ...args.rest],
        { stdio: "inherit", env: kBakeEnv });
    if (run.status !== 0 || sources.length === 1) return run.status === null ? 1 : run.status;
    return checkSceneGroups(args.out);
}

const kSceneNodes = ["Left", "LeftAgain", "Right"];

// The scene's source GLB next to `out` (see the header); returns its path.
function writeScene(lodbake, sources, out) {
    const parts = sources.map((source, i) => {
        const glb = `${out}.part${i}.glb`;
        const run = spawnSync(lodbake, ["convert", source, "-o", glb], { stdio: "inherit", env: kBakeEnv });
        if (run.status !== 0) throw new Error(`${source}: lodbake convert failed`);
        return parseGlb(fs.readFileSync(glb));
    });
    const extent = (part) => {
        const a = part.json.accessors[part.json.meshes[0].primitives[0].attributes.POSITION];
        return Math.max(...a.max.map((v, k) => v - a.min[k]));
    };
    const size = extent(parts[0]), scale = size / extent(parts[1]);
    const scene = sceneOf(parts, [
        [{ name: kSceneNodes[0], translation: [-size, 0, 0] }, { name: kSceneNodes[1], translation: [0, 0, -size] }],
        [{ name: kSceneNodes[2], translation: [size, 0, 0], rotation: [0, Math.SQRT1_2, 0, Math.SQRT1_2],
            scale: [scale, scale, scale] }]]);
    const file = `${out}.scene.glb`;
    fs.writeFileSync(file, scene);
    return file;
}

// The baked scene: one LOD group per input node, named as the input's nodes.
function checkSceneGroups(pack) {
    const { json } = parseGlb(fs.readFileSync(pack));
    const roots = (json.nodes || []).filter((n) => n.extensions && n.extensions.MSFT_lod).map((n) => n.name);
    if (JSON.stringify(roots) !== JSON.stringify(kSceneNodes)) {
        console.error(`${pack}: LOD groups ${JSON.stringify(roots)}, ` +
            `expected one per scene node ${JSON.stringify(kSceneNodes)}`);
        return 1;
    }
    return 0;
}

function isExecutable(file) {
    try {
        fs.accessSync(file, fs.constants.X_OK);
        return fs.statSync(file).isFile();
    } catch (_) {
        return false;
    }
}

// The configured path first (found at configure time), then PATH, so that Chromium installed after
// configuring is found too.
function findChromium(configured) {
    if (configured && isExecutable(configured)) return configured;
    for (const dir of (process.env.PATH || "").split(path.delimiter).filter(Boolean)) {
        for (const name of ["chromium", "chromium-browser", "google-chrome"]) {
            if (isExecutable(path.join(dir, name))) return path.join(dir, name);
        }
    }
    return null;
}

function contentType(file) {
    const types = { ".html": "text/html", ".js": "text/javascript", ".map": "application/json" };
    return types[path.extname(file)] || "application/octet-stream";
}

// Serves /page/*, /lib/<package>/* (the client's packages only), /pack.glb with HTTP range
// requests, and takes the page's POST /result. Resolves with the server once it listens.
function startServer(pack, libraries, nodeModules, onResult) {
    const served = { packRequests: 0, packBytes: 0 };
    const server = http.createServer((req, res) => {
        const url = new URL(req.url, "http://127.0.0.1");
        if (req.method === "POST" && url.pathname === "/result") {
            const body = [];
            req.on("data", (c) => body.push(c));
            req.on("end", () => { res.end("ok"); onResult(Buffer.concat(body).toString("utf8"), served); });
            return;
        }
        if (url.pathname === "/pack.glb") {
            ++served.packRequests;
            const range = /^bytes=(\d+)-(\d*)$/.exec(req.headers.range || "");
            if (range) {
                const start = Number(range[1]);
                const end = range[2] === "" ? pack.length - 1 : Math.min(Number(range[2]), pack.length - 1);
                if (start >= pack.length || end < start) {
                    res.writeHead(416, { "Content-Range": `bytes */${pack.length}` });
                    return res.end();
                }
                served.packBytes += end - start + 1;
                res.writeHead(206, {
                    "Content-Type": "model/gltf-binary",
                    "Content-Range": `bytes ${start}-${end}/${pack.length}`,
                    "Accept-Ranges": "bytes",
                });
                return res.end(pack.subarray(start, end + 1));
            }
            served.packBytes += pack.length;
            res.writeHead(200, { "Content-Type": "model/gltf-binary", "Accept-Ranges": "bytes" });
            return res.end(pack);
        }
        let file = null;
        const parts = url.pathname.split("/").filter(Boolean);
        if (parts[0] === "page" && parts.length === 2) file = path.join(kPageDir, parts[1]);
        // meshoptimizer's own decoder, as three.js ships it: Babylon.js would fetch it from its CDN.
        if (url.pathname === "/decoder/meshopt_decoder.module.js") {
            file = path.join(nodeModules, "three/examples/jsm/libs/meshopt_decoder.module.js");
        }
        if (parts[0] === "lib" && libraries.includes(parts[1])) {
            const root = path.join(nodeModules, parts[1]);
            const candidate = path.normalize(path.join(root, ...parts.slice(2)));
            if (candidate.startsWith(root + path.sep)) file = candidate;
        }
        if (!file || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
            res.writeHead(404);
            return res.end();
        }
        res.writeHead(200, { "Content-Type": contentType(file) });
        fs.createReadStream(file).pipe(res);
    });
    return new Promise((resolve) => server.listen(0, "127.0.0.1", () => resolve(server)));
}

// Runs the page in headless Chromium until it posts its result or the timeout passes.
async function runClient(chromium, client, pack, libraries, nodeModules, size, timeoutSeconds, outDir) {
    let finish;
    const done = new Promise((resolve) => { finish = resolve; });
    const server = await startServer(pack, libraries, nodeModules, (body, served) => finish({ body, served }));
    const port = server.address().port;
    const url = `http://127.0.0.1:${port}/page/${client}.html?pack=/pack.glb&width=${size[0]}&height=${size[1]}`;
    const profile = fs.mkdtempSync(path.join(outDir, "chromium-profile-"));
    const browser = spawn(chromium, [
        "--headless=new", "--no-sandbox", "--no-first-run", "--no-default-browser-check",
        "--disable-extensions", "--disable-background-networking", "--disable-dev-shm-usage",
        "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--mute-audio",
        `--user-data-dir=${profile}`, `--window-size=${size[0] + 64},${size[1] + 64}`, url,
    ], { detached: true, stdio: ["ignore", "ignore", "pipe"] });
    let browserLog = "";
    browser.stderr.on("data", (d) => { browserLog = (browserLog + d).slice(-4000); });
    const exited = new Promise((resolve) => browser.on("exit", resolve));
    browser.on("exit", (code) => finish({ exited: code }));
    browser.on("error", (error) => finish({ exited: error.message }));
    const timer = setTimeout(() => finish({ timeout: true }), timeoutSeconds * 1000);
    const outcome = await done;
    clearTimeout(timer);
    // The whole process group: Chromium's zygote, GPU and renderer processes too.
    if (browser.pid !== undefined) { // undefined: the spawn itself failed
        try { process.kill(-browser.pid, "SIGKILL"); } catch (_) { /* already gone */ }
        if (browser.exitCode === null && browser.signalCode === null) await exited;
    }
    server.close();
    fs.rmSync(profile, { recursive: true, force: true });
    const tail = browserLog.slice(-600);
    if (outcome.timeout) return { error: `no result within ${timeoutSeconds} s (Chromium stderr tail: ${tail})` };
    if (outcome.exited !== undefined) {
        return { error: `Chromium exited (${outcome.exited}) before the page posted a result: ${tail}` };
    }
    const result = JSON.parse(outcome.body);
    result.served = outcome.served;
    return result;
}

function pngSize(dataUrl) {
    const png = Buffer.from(dataUrl.slice(dataUrl.indexOf(",") + 1), "base64");
    return { png, width: png.readUInt32BE(16), height: png.readUInt32BE(20) };
}

// The checks: every failure as one message.
function judge(result, client, levels, expect, size) {
    const failures = [];
    if (result.error) return [`the client failed to load or render the pack: ${result.error.split("\n")[0]}`];
    const png = pngSize(result.png);
    for (const [what, got] of [["canvas", result.canvas], ["drawing buffer", result.render], ["rendered image", png]]) {
        if (got.width !== size[0] || got.height !== size[1]) {
            failures.push(`${what} ${got.width}x${got.height}, expected ${size[0]}x${size[1]}`);
        }
    }
    const t = result.textured;
    if (!(t.foreground / t.pixels >= kMinForeground)) {
        failures.push(`blank image: ${t.foreground} of ${t.pixels} pixels differ from the background, ` +
            `expected at least ${(kMinForeground * 100).toFixed(0)} %`);
    }

    const drawn = result.drawnMeshes.reduce((sum, m) => sum + m.indices, 0);
    if (client === "babylon") {
        const got = result.lodEvents.map((e) => e.indices);
        const want = levels.map((l) => l.indices).reverse(); // coarsest first
        if (levels.length > 1 && !result.msftLodExtension) {
            failures.push("the MSFT_lod extension of the loader was not used");
        } else if (levels.length > 1 && got.length !== want.length) {
            failures.push(`received ${got.length} of ${want.length} MSFT_lod levels ` +
                `(indices drawn per level: ${got.join(" ")}; pack: ${want.join(" ")})`);
        } else if (levels.length > 1 && got.some((n, i) => n !== want[i])) {
            failures.push(`indices drawn per MSFT_lod level ${got.join(" ")}, ` +
                `expected the pack's ${want.join(" ")} (coarsest first)`);
        }
    }
    if (drawn !== levels[0].indices) {
        failures.push(`finally draws ${drawn} indices, expected LOD0's ${levels[0].indices}`);
    }

    if (expect.textured) {
        if (!result.textures.length) failures.push("no base colour texture on the drawn meshes");
        if (result.untextured) {
            if (!(result.texturedVsUntextured >= kMinTextureDifference)) {
                failures.push("textures do not show: mean colour difference to the untextured render " +
                    `${result.texturedVsUntextured.toFixed(2)}, expected >= ${kMinTextureDifference}`);
            }
            if (!(result.albedo.variation >= kMinAlbedoVariation)) {
                const { variation, pixels } = result.albedo;
                failures.push(`textures do not show: albedo variation ${variation.toFixed(3)} over ${pixels} lit ` +
                    `pixels, expected >= ${kMinAlbedoVariation} (one flat colour is near 0)`);
            }
        }
    }
    return failures;
}

function parseExpect(text) {
    const expect = { textured: false, uses: [] };
    for (const word of (text || "").split(",").filter(Boolean)) {
        if (word === "textured") expect.textured = true;
        else if (word === "plain") expect.textured = false;
        else if (word.startsWith("uses=")) expect.uses.push(word.slice(5));
        else throw new Error(`--expect: unknown word "${word}" (plain, textured, uses=EXTENSION)`);
    }
    return expect;
}

async function check(args) {
    for (const key of ["client", "pack", "node-modules", "out"]) {
        if (!args[key]) throw new Error(`check: --${key} was expected`);
    }
    const client = args.client;
    if (!kLibraries[client]) throw new Error(`--client: babylon or three was expected, got "${client}"`);
    const label = `${args.pack}: ${client}`;
    const skip = (why) => {
        console.error(`browser test: ${why}`);
        return required("LODBAKE_REQUIRE_BROWSER") ? 1 : kSkip;
    };
    const chromium = findChromium(args.chromium);
    if (!chromium) return skip("Chromium not found (Debian package chromium; scripts/install-deps.sh installs it)");
    for (const lib of kLibraries[client]) {
        const dir = path.join(args["node-modules"], lib);
        if (!fs.existsSync(path.join(dir, "package.json"))) {
            return skip(`${dir}: missing (npm ci in scripts/node; scripts/install-deps.sh runs it)`);
        }
    }
    if (!fs.existsSync(args.pack)) {
        console.error(`${args.pack}: missing: the pack was expected from its Browser.Bake test`);
        return required("LODBAKE_REQUIRE_SHARED_MESHES") ? 1 : kSkip;
    }
    const expect = parseExpect(args.expect);
    const original = fs.readFileSync(args.pack);
    const { json } = parseGlb(original);
    const levels = lodLevels(json);
    const problems = [];
    for (const ext of expect.uses) {
        if (!(json.extensionsUsed || []).includes(ext)) problems.push(`extensionsUsed lacks ${ext}`);
    }
    if (expect.textured && !(json.images || []).length) {
        problems.push("a textured pack was expected, the pack has no images");
    }
    const served = args.break ? breakPack(original, args.break) : original;
    const size = (args.size || "320x240").split("x").map(Number);
    fs.mkdirSync(args.out, { recursive: true });

    const started = Date.now();
    const result = await runClient(chromium, client, served, kLibraries[client], path.resolve(args["node-modules"]),
        size, Number(args.timeout || 50), args.out);
    const seconds = ((Date.now() - started) / 1000).toFixed(1);
    problems.push(...judge(result, client, levels, expect, size));
    if (result.png) fs.writeFileSync(path.join(args.out, `${client}.png`), pngSize(result.png).png);
    fs.writeFileSync(path.join(args.out, `${client}.json`), JSON.stringify({ ...result, png: undefined }, null, 1));

    const t = result.textured;
    console.log(`summary: ${client} ${result.version || "?"}, ${seconds} s, levels ${levels.length}` +
        (result.lodEvents ? `, MSFT_lod levels received ${result.lodEvents.length} ` +
            `(indices ${result.lodEvents.map((e) => e.indices).join(" ")})` : "") +
        (t ? `, foreground ${(100 * t.foreground / t.pixels).toFixed(1)} %` : "") +
        (result.untextured ? `, against the untextured render: mean difference ` +
            `${result.texturedVsUntextured.toFixed(1)}, albedo variation ${result.albedo.variation.toFixed(3)}` : "") +
        (result.served ? `, pack requests ${result.served.packRequests}, bytes ${result.served.packBytes}` : ""));
    for (const line of result.console || []) console.log(`console ${line}`);
    for (const p of problems) console.error(`${label}: ${p}`);

    if (args["expect-failure"] !== undefined) {
        if (problems.some((p) => p.includes(args["expect-failure"]))) {
            console.log(`control: the ${args.break || "unbroken"} pack failed as expected ` +
                `("${args["expect-failure"]}")`);
            return 0;
        }
        console.error(`${label}: control: a failure containing "${args["expect-failure"]}" was expected`);
        return 1;
    }
    return problems.length ? 1 : 0;
}

async function main() {
    const args = parseArgs(process.argv.slice(2));
    const command = args._[0];
    if (command === "bake") return bake(args);
    if (command === "check") return check(args);
    throw new Error("usage: browser_check.js bake|check ... (see the header of this file)");
}

main().then((code) => process.exit(code), (error) => {
    console.error(`browser_check.js: ${error.message}`);
    process.exit(1);
});
