// Validates glTF files with Khronos' validator; prints one JSON object per
// file: {"file", "errors", "warnings", "infos", "issues" (the first 20),
// "info" (the validator's summary of the asset: counts, extensions)}.
// Usage: node validate.mjs FILE.glb ...
import { readFile } from 'node:fs/promises';
import validator from 'gltf-validator';

for (const file of process.argv.slice(2)) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, { maxIssues: 20 });
  console.log(JSON.stringify({
    file,
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    infos: report.issues.numInfos,
    issues: report.issues.messages,
    info: report.info,
  }));
}
