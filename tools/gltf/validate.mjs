// Validates glTF / GLB files with the Khronos glTF validator (npm package gltf-validator).
// Usage: node tools/gltf/validate.mjs FILE.glb [...] [--json]
// Prints a summary (and every message) per file; exits 1 if any file has an error, 2 on bad
// usage or an unreadable file. Warnings and infos are printed but do not fail.
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const args = process.argv.slice(2);
const json = args.includes('--json');
const files = args.filter((a) => a !== '--json');
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.glb [...] [--json]');
  process.exit(2);
}

let failed = false;
for (const file of files) {
  let bytes;
  try {
    bytes = new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`${file}: cannot read (${e.message})`);
    process.exit(2);
  }
  let report;
  try {
    report = await validator.validateBytes(bytes, { uri: file, maxIssues: 0, writeTimestamp: false });
  } catch (e) {
    console.error(`${file}: not a glTF asset (${e})`);
    failed = true;
    continue;
  }
  const issues = report.issues;
  if (json) {
    console.log(JSON.stringify(report, null, 2));
  } else {
    console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
                `${issues.numInfos} infos, ${issues.numHints} hints ` +
                `(gltf-validator ${validator.version()})`);
    for (const m of issues.messages) {
      const severity = ['error', 'warning', 'info', 'hint'][m.severity] ?? m.severity;
      console.log(`  ${severity} ${m.code} at ${m.pointer ?? m.offset ?? ''}: ${m.message}`);
    }
  }
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
