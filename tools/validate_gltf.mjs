#!/usr/bin/env node
// Validate glTF 2.0 assets (.glb or .gltf) with the Khronos glTF validator.
//
// Usage: node tools/validate_gltf.mjs FILE...
//
// Prints one JSON object per file on its own line:
//   {"file", "ok", "numErrors", "numWarnings", "numInfos", "numHints",
//    "mimeType", "validatorVersion", "errors": [first few error messages]}
// Exit status: 0 when every file validates without errors, 1 when any file has
// errors (or could not be read / parsed), 2 on bad usage.

import { readFile } from 'node:fs/promises';
import path from 'node:path';
import * as validator from 'gltf-validator';

const MAX_REPORTED = 20;

function externalResources(baseFile) {
    const dir = path.dirname(path.resolve(baseFile));
    return async (uri) => {
        const resolved = path.resolve(dir, decodeURIComponent(uri));
        try {
            return new Uint8Array(await readFile(resolved));
        } catch (err) {
            throw `cannot read external resource ${uri}: ${err.message}`;
        }
    };
}

async function validateFile(file) {
    let bytes;
    try {
        bytes = new Uint8Array(await readFile(file));
    } catch (err) {
        return { file, ok: false, numErrors: 1, fatal: `cannot read file: ${err.message}` };
    }
    const lower = file.toLowerCase();
    const options = {
        uri: path.basename(file),
        maxIssues: 0, // no limit
        externalResourceFunction: externalResources(file),
    };
    if (lower.endsWith('.gltf')) options.format = 'gltf';
    else if (lower.endsWith('.glb')) options.format = 'glb';

    let report;
    try {
        report = await validator.validateBytes(bytes, options);
    } catch (err) {
        return { file, ok: false, numErrors: 1, fatal: `validator rejected the input: ${String(err)}` };
    }
    const issues = report.issues || {};
    const messages = Array.isArray(issues.messages) ? issues.messages : [];
    const errors = messages
        .filter((m) => m.severity === 0)
        .slice(0, MAX_REPORTED)
        .map((m) => `${m.code} at ${m.pointer ?? m.offset ?? '?'}: ${m.message}`);
    const numErrors = issues.numErrors ?? errors.length;
    return {
        file,
        ok: numErrors === 0,
        numErrors,
        numWarnings: issues.numWarnings ?? 0,
        numInfos: issues.numInfos ?? 0,
        numHints: issues.numHints ?? 0,
        mimeType: report.mimeType ?? null,
        validatorVersion: report.validatorVersion ?? validator.version(),
        errors,
    };
}

async function main(argv) {
    const files = argv.slice(2);
    if (files.length === 0 || files.includes('-h') || files.includes('--help')) {
        process.stderr.write('usage: node validate_gltf.mjs FILE...\n');
        return 2;
    }
    let failed = false;
    for (const file of files) {
        const summary = await validateFile(file);
        if (!summary.ok) failed = true;
        process.stdout.write(JSON.stringify(summary) + '\n');
    }
    return failed ? 1 : 0;
}

main(process.argv).then(
    (code) => { process.exitCode = code; },
    (err) => { process.stderr.write(`validate_gltf: ${err?.stack ?? err}\n`); process.exitCode = 1; },
);
