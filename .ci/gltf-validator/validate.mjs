// node validate.mjs FILE.glb|.gltf REPORT.json: the Khronos glTF validator's report on FILE, written as JSON;
// prints the counts and every error and warning. Exits 0 when the file was validated (whatever it found):
// the caller reads the counts.
import fs from 'fs';
import path from 'path';
import validator from 'gltf-validator';

const [file, report] = process.argv.slice(2);
const result = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
        new Promise((resolve, reject) =>
            fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)),
                        (err, data) => (err ? reject(err.toString()) : resolve(new Uint8Array(data))))),
});
fs.writeFileSync(report, JSON.stringify(result, null, 1));
const issues = result.issues;
console.log(`${file}: ${issues.numErrors} error(s), ${issues.numWarnings} warning(s), ${issues.numInfos} info(s)`);
for (const m of issues.messages)
    if (m.severity <= 1)
        console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer}: ${m.message}`);
