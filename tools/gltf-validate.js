// Runs the Khronos glTF-Validator (npm install gltf-validator) over the files given and prints
// errors/warnings per file; exits normally. Used for docs/export.md; the test suite does not need it.
const validator = require('gltf-validator');
const fs = require('fs');
const path = require('path');
(async () => {
  let bad = 0;
  for (const f of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(f));
    try {
      const r = await validator.validateBytes(data, { uri: path.basename(f), maxIssues: 50 });
      const i = r.issues;
      const msgs = i.messages.filter(m => m.severity <= 1).map(m => `${m.severity==0?'E':'W'} ${m.code} ${m.pointer||''} ${m.message}`);
      console.log(`${f}: errors ${i.numErrors} warnings ${i.numWarnings} infos ${i.numInfos} hints ${i.numHints}`);
      for (const m of msgs.slice(0, 8)) console.log('   ' + m);
      if (i.numErrors > 0) bad++;
    } catch (e) { console.log(`${f}: validator failed: ${e}`); bad++; }
  }
  console.log(`files with errors: ${bad}`);
})();
