// Shared by the client pages: reads the query parameters, makes the canvas, measures rendered
// frames and posts the result back to the harness (tests/browser/browser_check.js), which judges it.
(function () {
    "use strict";
    const query = new URLSearchParams(location.search);
    const params = {
        pack: query.get("pack"),
        width: Number(query.get("width")),
        height: Number(query.get("height")),
    };
    const consoleLines = [];
    for (const level of ["warn", "error"]) {
        const original = console[level].bind(console);
        console[level] = (...args) => {
            consoleLines.push(level + ": " + args.map(String).join(" ").slice(0, 300));
            original(...args);
        };
    }
    let posted = false;
    function post(result) {
        if (posted) return;
        posted = true;
        result.console = consoleLines.slice(0, 40);
        fetch("/result", { method: "POST", body: JSON.stringify(result) });
    }
    function fail(error) {
        // Babylon wraps the cause of a failed load in innerError.
        const inner = error && error.innerError ? ": " + (error.innerError.message || JSON.stringify(error.innerError)) : "";
        post({ error: (String(error && error.stack ? error.stack : error) + inner).slice(0, 2000) });
    }
    window.addEventListener("error", (e) => fail(e.error || e.message));
    window.addEventListener("unhandledrejection", (e) => fail(e.reason));

    function makeCanvas() {
        const canvas = document.createElement("canvas");
        canvas.width = params.width;
        canvas.height = params.height;
        canvas.style.width = params.width + "px";
        canvas.style.height = params.height + "px";
        canvas.style.display = "block";
        document.body.style.margin = "0";
        document.body.appendChild(canvas);
        return canvas;
    }

    // The WebGL canvas (drawn with preserveDrawingBuffer) copied into a 2D canvas and read back.
    function readPixels(glCanvas) {
        const copy = document.createElement("canvas");
        copy.width = glCanvas.width;
        copy.height = glCanvas.height;
        const ctx = copy.getContext("2d", { willReadFrequently: true });
        ctx.drawImage(glCanvas, 0, 0);
        const data = ctx.getImageData(0, 0, copy.width, copy.height).data;
        return { width: copy.width, height: copy.height, data, png: copy.toDataURL("image/png") };
    }

    const kBackgroundTolerance = 8; // per channel, 8-bit: swiftshader's clear is exact, blending is not

    function isForeground(data, i, background) {
        return Math.abs(data[i] - background[0]) > kBackgroundTolerance ||
            Math.abs(data[i + 1] - background[1]) > kBackgroundTolerance ||
            Math.abs(data[i + 2] - background[2]) > kBackgroundTolerance;
    }

    // Foreground pixel count and the spread of chromaticity over lit foreground pixels: a surface of
    // one flat colour under white light keeps one chromaticity (shading scales r, g and b alike),
    // so a texture shows as a larger spread.
    function measure(frame, background) {
        const d = frame.data;
        let foreground = 0, lit = 0, sr = 0, sg = 0, srr = 0, sgg = 0;
        const mean = [0, 0, 0];
        for (let i = 0; i < d.length; i += 4) {
            if (!isForeground(d, i, background)) continue;
            ++foreground;
            mean[0] += d[i]; mean[1] += d[i + 1]; mean[2] += d[i + 2];
            const sum = d[i] + d[i + 1] + d[i + 2];
            if (sum < 60) continue; // too dark for a stable chromaticity
            const r = d[i] / sum, g = d[i + 1] / sum;
            ++lit; sr += r; sg += g; srr += r * r; sgg += g * g;
        }
        const spread = lit ? Math.sqrt(Math.max(0, srr / lit - (sr / lit) ** 2) + Math.max(0, sgg / lit - (sg / lit) ** 2)) : 0;
        return {
            width: frame.width, height: frame.height, pixels: frame.width * frame.height, foreground,
            litForeground: lit, chromaSpread: spread,
            meanColor: mean.map((v) => (foreground ? v / foreground : 0)),
        };
    }

    // Mean absolute colour difference (0..255, over r, g, b) where both frames show the model.
    function difference(a, b, background) {
        let n = 0, sum = 0;
        for (let i = 0; i < a.data.length; i += 4) {
            if (!isForeground(a.data, i, background) || !isForeground(b.data, i, background)) continue;
            ++n;
            sum += (Math.abs(a.data[i] - b.data[i]) + Math.abs(a.data[i + 1] - b.data[i + 1]) + Math.abs(a.data[i + 2] - b.data[i + 2])) / 3;
        }
        return n ? sum / n : 0;
    }

    function backgroundOf(frame) {
        const d = frame.data;
        return [d[0], d[1], d[2]];
    }

    window.lodbakeProbe = { params, makeCanvas, readPixels, measure, difference, backgroundOf, post, fail };
})();
