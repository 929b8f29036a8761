// Runs the Khronos glTF-Validator on one .glb/.gltf file and prints its report as JSON.
// Usage: node tools/validate-gltf.mjs FILE
// Exit status: 0 when the report has no errors, 1 when it has some, 2 when the file can't be read.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate-gltf.mjs FILE');
  process.exit(2);
}
let bytes;
try {
  bytes = new Uint8Array(await readFile(file));
} catch (err) {
  console.error(`${file}: ${err.message}`);
  process.exit(2);
}
const dir = path.dirname(file);
const report = await validator.validateBytes(bytes, {
  uri: path.basename(file),
  maxIssues: 200,
  externalResourceFunction: (uri) =>
    readFile(path.join(dir, decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
});
console.log(JSON.stringify(report, null, 1));
process.exit(report.issues.numErrors > 0 ? 1 : 0);
