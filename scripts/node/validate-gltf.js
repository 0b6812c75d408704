#!/usr/bin/env node
// Runs the Khronos glTF-Validator on each file given and prints one line per file:
//   <file>: errors N warnings N infos N hints N
// followed by every error and warning message. Exits 1 if any file has an error or a warning,
// 2 on usage errors. External resources (.bin, images) are read relative to the file.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
        uri: path.basename(file),
        maxIssues: 100,
        externalResourceFunction: (uri) =>
            new Promise((resolve, reject) => {
                fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
                    err ? reject(err.toString()) : resolve(new Uint8Array(data)));
            }),
    });
    const i = report.issues;
    console.log(`${file}: errors ${i.numErrors} warnings ${i.numWarnings} infos ${i.numInfos} hints ${i.numHints}`);
    for (const m of i.messages) {
        if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
    }
    return i.numErrors === 0 && i.numWarnings === 0;
}

(async () => {
    const files = process.argv.slice(2);
    if (files.length === 0) {
        console.error('usage: validate-gltf.js FILE.glb|FILE.gltf ...');
        process.exit(2);
    }
    let ok = true;
    for (const f of files) {
        try {
            ok = (await validate(f)) && ok;
        } catch (e) {
            console.log(`${f}: validator failed: ${e}`);
            ok = false;
        }
    }
    process.exit(ok ? 0 : 1);
})();
