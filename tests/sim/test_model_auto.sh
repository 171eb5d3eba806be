#!/usr/bin/env bash
# glint fit --model auto, and glint demo with a transparent material: the
# demo simulates a blue-quartz sphere (reference renderer) and fits it;
# --model auto must pick dielectric for it, and torrance-sparrow for an
# opaque sphere, and say why.
# usage: test_model_auto.sh GLINT DATA_DIR
set -u
glint=$1
data=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
fails=0
check() {
	local what=$1
	shift
	if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fails=$((fails + 1)); fi
}
check "demo of a transparent material" bash -c "'$glint' demo --material blue-quartz -o bq --json >bq.json 2>bq.err"
check "... recovers it (ior 0.01, transmission 0.02)" python3 -c "
import json
r = json.load(open('bq.json'))
t, f = r['truth'], r['material']
print('  truth', t, 'fit', f)
assert abs(f['ior'] - t['ior']) < 0.01
assert all(abs(a - b) < 0.02 for a, b in zip(f['transmission'], t['transmission']))
assert r['model'] == 'dielectric' and r['optimizer'] == 'auto'
assert [p['name'] for p in r['passes']] == ['anneal', 'lm-polish']
"
check "--model auto picks dielectric for it" bash -c "'$glint' fit '$data/demo-scene.json' bq/photo.exr --model auto -o auto-bq --json >a1.json 2>a1.err && grep -q 'auto: dielectric' a1.err"
check "... and says why in params.json" python3 -c "
import json
d = json.load(open('a1.json'))['model_choice']
print('  ', d)
assert d['chosen'] == 'dielectric' and d['dielectric_rel_rmse'] < d['torrance_sparrow_rel_rmse']
"
check "an opaque photo" bash -c "'$glint' render '$data/demo-scene.json' --paper copper -o cu.exr 2>/dev/null"
check "--model auto picks torrance-sparrow for it" bash -c "'$glint' fit '$data/demo-scene.json' cu.exr --model auto -o auto-cu 2>a2.err && grep -q 'auto: torrance-sparrow' a2.err"
check "--optimizer anneal on an opaque model runs and polishes" bash -c "'$glint' fit '$data/demo-scene.json' cu.exr --optimizer anneal --anneal-evals 30 --max-pixels 512 -o ann --json >ann.json 2>/dev/null && python3 -c \"
import json
d = json.load(open('ann.json'))
print('  passes', [p['name'] for p in d['passes']])
assert [p['name'] for p in d['passes']][:2] == ['anneal', 'anneal-polish']
\""
check "bad --optimizer: exit 2, named" bash -c "'$glint' fit '$data/demo-scene.json' cu.exr --optimizer genetic 2>&1 | grep -q 'genetic'"
echo "$fails failed"
[ "$fails" = 0 ]
