#!/usr/bin/env node
// Validate glTF files with the Khronos glTF-Validator (npm package `gltf-validator`,
// installed by scripts/bootstrap.sh into .venv/gltf-validator; found through NODE_PATH).
// Usage: NODE_PATH=.venv/gltf-validator/node_modules node scripts/gltf_validate.js FILE...
// Prints one JSON line per file: {"file", "errors", "warnings", "infos", "hints", "messages"}
// (messages: the errors and warnings, code and pointer). Exit status 1 when any file has
// an error or a warning, 2 when the validator cannot be loaded or a file cannot be read.
"use strict";
const fs = require("fs");
const path = require("path");

let validator;
try {
    validator = require("gltf-validator");
} catch (e) {
    console.error("gltf_validate: cannot load the npm package gltf-validator (run scripts/bootstrap.sh): " + e.message);
    process.exit(2);
}

async function main(files) {
    let bad = 0;
    for (const file of files) {
        const data = new Uint8Array(fs.readFileSync(file));
        const report = await validator.validateBytes(data, {
            uri: path.basename(file),
            maxIssues: 0,
            externalResourceFunction: (uri) => Promise.reject(new Error("external resource " + uri + " not expected")),
        });
        const issues = report.issues;
        const messages = issues.messages
            .filter((m) => m.severity <= 1)
            .map((m) => ({ code: m.code, severity: m.severity, message: m.message, pointer: m.pointer }));
        console.log(JSON.stringify({
            file, errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos,
            hints: issues.numHints, messages: messages.slice(0, 20),
        }));
        if (issues.numErrors + issues.numWarnings > 0) bad = 1;
    }
    return bad;
}

main(process.argv.slice(2)).then((code) => process.exit(code), (err) => {
    console.error("gltf_validate: " + (err && err.message ? err.message : err));
    process.exit(2);
});
