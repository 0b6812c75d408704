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
        const cause = error && error.innerError;
        const inner = cause ? ": " + (cause.message || JSON.stringify(cause)) : "";
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

    // Foreground pixel count and mean colour.
    function measure(frame, background) {
        const d = frame.data;
        let foreground = 0;
        const mean = [0, 0, 0];
        for (let i = 0; i < d.length; i += 4) {
            if (!isForeground(d, i, background)) continue;
            ++foreground;
            mean[0] += d[i]; mean[1] += d[i + 1]; mean[2] += d[i + 2];
        }
        return {
            width: frame.width, height: frame.height, pixels: frame.width * frame.height, foreground,
            meanColor: mean.map((v) => (foreground ? v / foreground : 0)),
        };
    }

    // Mean absolute colour difference (0..255, over r, g, b) where both frames show the model.
    function difference(a, b, background) {
        let n = 0, sum = 0;
        for (let i = 0; i < a.data.length; i += 4) {
            if (!isForeground(a.data, i, background) || !isForeground(b.data, i, background)) continue;
            ++n;
            for (let c = 0; c < 3; ++c) sum += Math.abs(a.data[i + c] - b.data[i + c]) / 3;
        }
        return n ? sum / n : 0;
    }

    const toLinear = (v) => { const c = v / 255; return c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4; };

    // How much the surface's albedo varies, estimated from two renders that differ only in the base
    // colour texture: textured = albedo * shading and untextured (white base colour) = shading in
    // linear light, so their per-pixel ratio is the albedo. Returns the ratio's coefficient of
    // variation (standard deviation over mean) over well-lit pixels, averaged over r, g and b: near
    // 0 for one flat colour of any hue, large for a texture with detail.
    function albedoVariation(textured, untextured, background) {
        const a = textured.data, b = untextured.data;
        const sum = [0, 0, 0], sq = [0, 0, 0];
        let n = 0;
        for (let i = 0; i < a.length; i += 4) {
            if (!isForeground(a, i, background) || !isForeground(b, i, background)) continue;
            const shade = [toLinear(b[i]), toLinear(b[i + 1]), toLinear(b[i + 2])];
            if (Math.min(...shade) < 0.05) continue; // too dark for a stable ratio
            ++n;
            for (let c = 0; c < 3; ++c) {
                const ratio = toLinear(a[i + c]) / shade[c];
                sum[c] += ratio;
                sq[c] += ratio * ratio;
            }
        }
        if (!n) return { pixels: 0, variation: 0 };
        let variation = 0;
        for (let c = 0; c < 3; ++c) {
            const mean = sum[c] / n;
            variation += mean > 0 ? Math.sqrt(Math.max(0, sq[c] / n - mean * mean)) / mean / 3 : 0;
        }
        return { pixels: n, variation };
    }

    function backgroundOf(frame) {
        const d = frame.data;
        return [d[0], d[1], d[2]];
    }

    window.lodbakeProbe = {
        params, makeCanvas, readPixels, measure, difference, albedoVariation, backgroundOf, post, fail,
    };
})();
