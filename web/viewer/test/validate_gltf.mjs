// Usage: node test/validate_gltf.mjs FILE.glb
// Runs the Khronos glTF validator; prints a JSON summary; exit 0 only when the
// asset has no errors and no warnings (infos and hints are reported, not fatal).
import { readFile } from 'node:fs/promises';
import { basename } from 'node:path';
import validator from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node test/validate_gltf.mjs FILE.glb');
  process.exit(2);
}

let report;
try {
  const bytes = new Uint8Array(await readFile(file));
  report = await validator.validateBytes(bytes, {
    uri: basename(file),
    maxIssues: 0, // 0 = unlimited
    writeTimestamp: false,
    // A glb made by the exporter is self-contained; any external URI is a bug.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource not allowed: ${uri}`)),
  });
} catch (err) {
  console.error(`validate_gltf: cannot validate ${file}: ${err && err.message ? err.message : err}`);
  process.exit(1);
}

const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
const pick = (severity) =>
  messages.filter((m) => m.severity === severity).map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`);
const summary = {
  file,
  validatorVersion: report.validatorVersion,
  numErrors,
  numWarnings,
  numInfos,
  numHints,
  errors: pick(0),
  warnings: pick(1),
  infos: pick(2),
  hints: pick(3),
  info: report.info,
};
console.log(JSON.stringify(summary));
if (numErrors > 0 || numWarnings > 0) {
  console.error(`validate_gltf: ${file}: ${numErrors} error(s), ${numWarnings} warning(s)`);
  process.exit(1);
}
