// Khronos glTF-Validator (npm gltf-validator) over .glb files: prints each file's issue
// counts and every error/warning; exits 1 when any file has an error or a warning.
//   node web/tools/validate-gltf.mjs FILE.glb ...
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const validator = createRequire(import.meta.url)('gltf-validator');
const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate-gltf.mjs FILE.glb ...');
  process.exit(2);
}
let bad = 0;
for (const file of files) {
  const report = await validator.validateBytes(new Uint8Array(await readFile(file)), {
    uri: file,
    maxIssues: 100,
    // External resources: our .glb files have none.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const { numErrors, numWarnings, numInfos, numHints } = report.issues;
  const info = report.info || {};
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints; ` +
              `${info.totalVertexCount ?? '?'} vertices, ${info.totalTriangleCount ?? '?'} triangles, ` +
              `extensions used: ${(info.extensionsUsed || []).join(', ') || 'none'}`);
  for (const m of report.issues.messages)
    if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer}: ${m.message}`);
  if (numErrors > 0 || numWarnings > 0) ++bad;
}
process.exit(bad > 0 ? 1 : 0);
