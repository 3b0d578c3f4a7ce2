#!/usr/bin/env node
// Validates a glTF/GLB file with the Khronos glTF validator (npm gltf-validator, installed into
// .tools/ by scripts/install-deps.sh). Prints the report's issue summary and every error as JSON
// on stdout. Exit: 0 = no errors, 1 = errors, 3 = the validator package is missing.
// Usage: node scripts/validate_gltf.js FILE [TOOLS_DIR]
'use strict';
const fs = require('fs');
const path = require('path');

const file = process.argv[2];
const tools = process.argv[3] || path.join(__dirname, '..', '.tools');
if (!file) {
  console.error('usage: validate_gltf.js FILE [TOOLS_DIR]');
  process.exit(2);
}
let validator;
try {
  validator = require(path.join(path.resolve(tools), 'node_modules', 'gltf-validator'));
} catch (e) {
  console.error('gltf-validator not found under ' + tools + ' (run scripts/install-deps.sh)');
  process.exit(3);
}
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, {
  uri: path.basename(file),
  maxIssues: 200,
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
      err ? reject(err.toString()) : resolve(new Uint8Array(data)));
  }),
}).then((report) => {
  const summary = {
    validatorVersion: report.validatorVersion,
    numErrors: report.issues.numErrors,
    numWarnings: report.issues.numWarnings,
    numInfos: report.issues.numInfos,
    errors: report.issues.messages.filter((m) => m.severity === 0),
    warnings: report.issues.messages.filter((m) => m.severity === 1),
  };
  console.log(JSON.stringify(summary, null, 2));
  process.exit(report.issues.numErrors === 0 ? 0 : 1);
}, (error) => {
  console.error('validation failed: ' + error);
  process.exit(1);
});
