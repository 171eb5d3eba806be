#!/bin/bash
# The simulated rig end to end: a probe capture (unwrapped to env.exr), a
# sample capture (the sphere found, scene.json written), `glint fit
# SESSION`, and what must hold when two fits race or one is killed.
# usage: test_session_fit.sh GLINT
set -u
. "$(dirname "$0")/../wait.sh"
glint=$1
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$tmp"' EXIT
fails=0 checks=0
check() {
	local what=$1
	shift
	checks=$((checks + 1))
	if "$@"; then
		echo "ok   $what"
	else
		echo "FAIL $what"
		fails=$((fails + 1))
	fi
}
run() { # EXPECTED_STATUS FRAGMENT ARGS...
	local want=$1 frag=$2
	shift 2
	"$glint" "$@" >"$tmp/out" 2>"$tmp/err"
	local got=$?
	if [ "$got" != "$want" ]; then
		echo "  glint $*: exit $got, expected $want; stderr:" >&2
		cat "$tmp/err" >&2
		return 1
	fi
	if [ -n "$frag" ] && ! grep -qF -- "$frag" "$tmp/err"; then
		echo "  glint $*: stderr lacks '$frag':" >&2
		cat "$tmp/err" >&2
		return 1
	fi
}
rig() { # NAME SCENE W H
	cat >"$tmp/$1.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=$3,height=$4,scene=$2,timescale=0.02"},
 "optics": {"focal_px": $((2 * $3)), "psf_sigma_px": 0.86, "olpf": true},
 "sample": {"diameter_m": 0.1},
 "bracket": {"step_ev": 1, "max_frames": 24, "floor_dn": 16},
 "output": "$tmp/caps"}
JSON
}
rig probe probe 320 240
rig sample sample 160 120

check "sample before any probe: complete, says why there is no scene" run 0 "capture the probe first" capture sample --config "$tmp/sample.json"
first=$(ls -d "$tmp"/caps/sample-*)
check "... and fitting it names what is missing" run 1 "no scene.json" fit "$first"
check "probe capture" run 0 "probe ball at" capture probe --config "$tmp/probe.json"
check "sample capture finds the sphere, writes the scene" run 0 "sample sphere at" capture sample --config "$tmp/sample.json" --json
sess=$(python3 -c "import json; print(json.load(open('$tmp/out'))['session'])")
check "... scene.json lit by the probe's env.exr (relative path)" grep -q '"path": "../probe-.*/env.exr"' "$sess/scene.json"
# Truth: 0.35 of 120 px in radius, centred (sim/camera_sim.h).
check "... circle within 0.5 px of the truth" python3 -c "
import json, sys
c = json.load(open('$sess/scene.json'))['sphere']['circle_px']
print('  circle', c)
sys.exit(not (abs(c['cx'] - 80) < 0.5 and abs(c['cy'] - 60) < 0.5 and abs(c['r'] - 42) < 0.5))"

check "glint fit SESSION" run 0 "" fit "$sess" --json
cp "$tmp/out" "$tmp/fit1.json"
check "... into SESSION/fit" test -s "$sess/fit/params.json" -a -s "$sess/fit/compare.png"
# Through the whole rig (lens and OLPF blur, noise, Bayer, bracket, merge,
# unwrap with the sun as a point source, detection; the fit renders the
# camera's blur): diffuse within 0.01, roughness within 0.02, ior within
# 0.08, specular within 0.08 of yellow plastic (Table 1).  The sphere is
# 42 px in radius here, where the sun's highlight spans under two pixels
# and the roughness is at the photo's resolution (0.035 measured for
# 0.039); tests/sim/test_rig.sh checks the rig's 84 px sphere to 5 %.
check "... recovers yellow plastic (Table 1)" python3 -c "
import json, sys
d = json.load(open('$tmp/fit1.json'))
p = {q['name']: q['value'] for q in d['parameters']}
truth = {'diffuse.r': (0.292, .01), 'diffuse.g': (0.117, .01),
         'diffuse.b': (0.027, .01), 'specular.r': (0.292, .08),
         'specular.g': (0.267, .08), 'specular.b': (0.239, .08),
         'roughness': (0.039, .02), 'ior': (1.43, .08)}
bad = [(k, p[k], t) for k, (t, tol) in truth.items() if abs(p[k] - t) > tol]
print('  recovered', {k: round(v, 4) for k, v in p.items()})
sys.exit(1 if bad else 0)"

# Two sample sessions fitted jointly (on a rig with several lights, one
# per light; here the same light twice): their merges' weights, -o needed.
check "a second sample capture" run 0 "sample sphere at" capture sample --config "$tmp/sample.json" --json
sess2=$(python3 -c "import json; print(json.load(open('$tmp/out'))['session'])")
check "glint fit SESSION SESSION2 without -o: exit 2, says why" run 2 "give -o DIR" fit "$sess" "$sess2"
check "glint fit SESSION SESSION2 -o DIR: one material from both samples" run 0 "" fit "$sess" "$sess2" -o "$tmp/joint" --json -q --sample-sets 1
check "... each session's sample and weights, both photos accepted" python3 -c "
import json, sys
d = json.load(open('$tmp/joint/params.json'))
ph = d['photos']
print('  photos', [(p['photo'], round(p['relative_rmse'], 4)) for p in ph])
assert [p['photo'] for p in ph] == ['$sess/sample.exr', '$sess2/sample.exr'], ph
assert d['weighting'] == 'weight image', d['weighting']
assert all(p['acceptance']['accepted'] for p in ph), ph
p = {q['name']: q['value'] for q in d['parameters']}
assert abs(p['diffuse.r'] - 0.292) < 0.01, p"
check "... and no session's fit folder touched" test ! -e "$sess2/fit"

check "a probe session is not fittable: named" run 1 "expected a complete sample session" fit "$(ls -d "$tmp"/caps/probe-*)"

# Two fits of one session: the second is refused, naming the holder; with
# --wait it waits and takes the result the first one left.
"$glint" fit "$sess" -q --threads 1 --samples 32 &
pid=$!
# The holder writes its pid into the lock once it holds it (probing
# with flock would take the lock itself and could make the fit fail).
wait_until 30 grep -q "pid $pid:" "$sess/fit.lock"
check "a second fit of the session is refused" run 1 "is being fitted" fit "$sess"
check "... naming the holder" grep -q "pid $pid" "$tmp/err"
check "... --wait waits, then takes the result of the fit it waited for" run 0 "was fitted by the fit waited for" fit "$sess" --wait --json
check "... its --json is that result (not a second fit)" python3 -c "
import json, sys
a = json.load(open('$tmp/out'))
b = json.load(open('$sess/fit/params.json'))
sys.exit(a['parameters'] != b['parameters'])"
wait $pid
check "the first fit also completed" test $? = 0

# A fit killed mid-way (SIGKILL: no clean-up) leaves the previous result
# whole, and the next fit completes.
"$glint" fit "$sess" -q --threads 1 --samples 64 &
pid=$!
# The holder writes its pid into the lock once it holds it (probing
# with flock would take the lock itself and could make the fit fail).
wait_until 30 grep -q "pid $pid:" "$sess/fit.lock"
kill -KILL $pid
wait $pid 2>/dev/null
check "killed fit: the previous result is intact" python3 -c "import json; json.load(open('$sess/fit/params.json'))"
check "re-run after SIGKILL completes" run 0 "" fit "$sess"
# What a power cut leaves at the worst moments: a half-written result
# folder, and the old result moved aside before the new one was put in
# place.  The next fit restores, cleans up and completes.
mkdir "$sess/fit.tmp.Xy12ab" && echo partial >"$sess/fit.tmp.Xy12ab/params.json"
mv "$sess/fit" "$sess/fit.old.4242"
check "fit after a cut mid-commit: cleans up and completes" run 0 "cleaned up after an interrupted fit" fit "$sess"
check "... one whole result, no leftovers" bash -c "python3 -c \"import json; json.load(open('$sess/fit/params.json'))\" && ! ls -d '$sess'/fit.tmp.* '$sess'/fit.old.* 2>/dev/null"

echo "$((checks - fails)) passed, $fails failed"
[ "$fails" = 0 ]
