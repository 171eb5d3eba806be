#!/usr/bin/env bash
# params.json's "misfit" (fit/misfit.h): the residual binned by the angle
# from the view direction and from the mirror direction of the map's
# brightest light.  The true model on a reference-renderer photo leaves no
# structure; a Lambert fit of the same glossy sphere must be called
# structured, in both angles, in params.json and in the text output.
# usage: test_misfit.sh GLINT DATA_DIR
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
check "demo (yellow plastic, reference renderer)" bash -c "'$glint' demo -o d -q >/dev/null 2>d.err"
check "the true model leaves no structure" python3 -c "
import json
m = json.load(open('d/fit/params.json'))['misfit']
print('  ', m['verdict'])
assert not m['structured'], m['verdict']
bands = m['by_view_angle']
assert len(bands) == 9 and bands[0]['deg'] == [0, 10] and bands[-1]['deg'] == [80, 90]
n = sum(b['pixels'] for b in bands)
assert n == sum(b['pixels'] for b in m['by_mirror_angle']) and n > 10000, n
# every band with pixels is within 5 standard errors of zero
for b in bands + m['by_mirror_angle']:
    if b['pixels'] >= 20:
        assert abs(b['mean_residual']) <= 5 * b['standard_error'], b
"
check "... without a noise model the render keeps the scene's samples, and says so" python3 -c "
import json
r = json.load(open('d/fit/params.json'))['render']
assert r['light_samples'] == r['brdf_samples'] == 32 and r['noise'].startswith('not compared'), r
"
check "a Lambert fit of the glossy sphere" bash -c "'$glint' fit '$data/demo-scene.json' d/photo.exr --model lambert --accept-rmse 10 -o lam >lam.txt 2>lam.err"
check "... is called structured in both angles" python3 -c "
import json
m = json.load(open('lam/params.json'))['misfit']
print('  ', m['verdict'])
assert m['structured']
assert 'view direction' in m['verdict'] and 'mirror direction' in m['verdict']
worst = max(abs(b['mean_residual']) / b['standard_error'] for b in m['by_view_angle'] if b['pixels'] >= 20)
assert worst > 5, worst
"
check "... and the text output says so" grep -q '^  residual: structured residual' lam.txt
check "... its intervals take the model error over regions" python3 -c "
import json
d = json.load(open('lam/params.json'))
u = d['uncertainty']
print('   regions', u['model_error_regions'], 'stderr', u['model_error_stderr'])
assert u['model_error_regions'] >= 3, u['model_error_regions']
for p, e in zip(d['parameters'], u['model_error_stderr']):
    assert e > 0 and p['stderr'] >= e * (1 - 1e-9), (p, e)
assert any('model is too simple' in f for f in u['findings']), u['findings']
"
check "... and the text output names them" grep -q '^  the model error over [0-9]* regions' lam.txt
check "... and a model discrepancy scaled by the structure's share of the signal" python3 -c "
import json
d = json.load(open('lam/params.json'))
u = d['uncertainty']
share, md = u['misfit_share'], u['model_discrepancy_stderr']
print('   share', share, 'discrepancy', md)
assert 0.01 < share < 1, share
# Lambert's parameters are all diffuse albedos: C x share x the larger of
# the albedo and the three's mean (fit.c, discrepancy())
mean = sum(p['value'] for p in d['parameters']) / 3
for p, e in zip(d['parameters'], md):
    want = 1.15 * share * max(p['value'], mean)
    assert abs(e - want) <= 1e-9 + 1e-6 * e, (p, e, want)
    assert p['stderr'] >= e * (1 - 1e-9), (p, e)
assert any('model discrepancy' in f for f in u['findings']), u['findings']
"
check "... which the text output names" grep -q '^  a model discrepancy (the residual.s structure: [0-9.]* % of the signal)' lam.txt
check "the true model's fit: no model-error term, the structure's share at the noise" python3 -c "
import json
u = json.load(open('d/fit/params.json'))['uncertainty']
print('   share', u['misfit_share'])
assert u['model_error_regions'] == 0 and not any(u['model_error_stderr']), u
# the share is debiased (each region's noise taken off): about 0 for the
# right model, and no finding below 1 %
assert 0 <= u['misfit_share'] < 0.01, u['misfit_share']
assert not any('model discrepancy' in f for f in u['findings']), u['findings']
"
check "the fast render's gain term is stated per parameter, within the systematic part" python3 -c "
import json
d = json.load(open('d/fit/params.json'))
u = d['uncertainty']
g, s = u['render_gain_stderr'], u['systematic_stderr']
print('   gain term', g)
assert len(g) == len(d['parameters']) == len(s), g
assert all(0 <= e <= x * (1 + 1e-9) for e, x in zip(g, s)), (g, s)
# the varying lobe's albedos and ior carry it, within 5 % of their value
# for the true model; roughness none (fit/render_gain.c)
for p, e in zip(d['parameters'], g):
    if p['name'].startswith('specular') or p['name'] == 'ior':
        assert 0 < e < 0.05 * p['value'], (p, e)
    if p['name'] == 'roughness':
        assert e == 0, (p, e)
"
check "the sampling lean taken off is stated per parameter, within its interval" python3 -c "
import json
d = json.load(open('d/fit/params.json'))
lean = d['uncertainty']['sampling_lean_removed']
print('   lean removed', lean)
assert len(lean) == len(d['parameters']), lean
for p, l in zip(d['parameters'], lean):
    assert p['stderr'] is None or abs(l) <= 2 * p['stderr'], (p, l)
"
[ "$fails" -eq 0 ] || { echo "$fails check(s) failed"; exit 1; }
