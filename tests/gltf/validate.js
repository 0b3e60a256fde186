// validate.js FILE.glb: the Khronos glTF validator (npm's gltf-validator)
// on a file `tumble run --gltf` wrote. Prints the validator's counts and
// every message of severity error or warning; exits 1 on any error or
// warning (a hint or an info, such as an unused material, passes), 2 when
// the validator cannot be loaded (npm install it: see dev.sh).
'use strict';
const fs = require('fs');
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('validate.js: cannot load gltf-validator (' + e.message.split('\n')[0] + ')');
  process.exit(2);
}
const file = process.argv[2];
if (!file) {
  console.error('usage: node validate.js FILE.glb');
  process.exit(2);
}
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, { maxIssues: 100 }).then((report) => {
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints (gltf-validator ${report.validatorVersion})`);
  for (const m of issues.messages)
    if (m.severity <= 1)
      console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer || '-'}: ${m.message}`);
  process.exit(issues.numErrors + issues.numWarnings > 0 ? 1 : 0);
}, (e) => {
  console.error('validate.js: ' + e);
  process.exit(1);
});
