// The Khronos glTF validator on each FILE: one line of JSON per file with
// its error, warning, info and hint counts and its messages.
// usage: node gltf_validate.js VALIDATOR_DIR FILE...
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require(path.resolve(process.argv[2]));
(async () => {
	for (const f of process.argv.slice(3)) {
		const r = await validator.validateBytes(
			new Uint8Array(fs.readFileSync(f)), { uri: f });
		const i = r.issues;
		console.log(JSON.stringify({
			file: f, validator: r.validatorVersion,
			errors: i.numErrors, warnings: i.numWarnings,
			infos: i.numInfos, hints: i.numHints,
			messages: i.messages.map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`),
		}));
	}
})().catch((e) => { console.error(e); process.exit(1); });
