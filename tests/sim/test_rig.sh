#!/bin/bash
# The appliance on the simulated rig (sim camera scene=rig + sim board):
# a scripted press runs the whole sequence to a fit; a second press
# cancels; SIGTERM mid-capture stops cleanly; bad rig files are refused
# before any output moves; the job queue survives a killed worker.
# With FAKE_GPIO_LIB (the fake GPIO chip), the same daemon on the libgpiod
# backend.
# usage: test_rig.sh GLINT DATA_DIR [FAKE_GPIO_LIB|none]
# GLINT_RIG_PART=core runs all but the two-lamp run and its joint fit,
# =lamps that alone (test rig-lamps), unset both.
set -u
part=${GLINT_RIG_PART:-all}
. "$(dirname "$0")/../wait.sh"
glint=$1
data=$2
fakegpio=${3:-none}
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
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
		tail -20 "$tmp/err" >&2
		return 1
	fi
	if [ -n "$frag" ] && ! grep -qF -- "$frag" "$tmp/err"; then
		echo "  glint $*: stderr lacks '$frag':" >&2
		tail -20 "$tmp/err" >&2
		return 1
	fi
}
# rig NAME PRESSES [W H]: the shipped sim rig, output and log in $tmp.
rig() {
	echo "{\"presses\": [$2]}" >"$tmp/$1-press.json"
	python3 - "$data/rig-sim.json" "$tmp/$1.json" "$tmp/$1" "$tmp/$1-press.json" "$tmp/$1-board.log" "${3:-160}" "${4:-120}" "${5:-0.05}" <<'PY'
import json, sys
src, dst, out, press, log, w, h, ts = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
r["board"]["scenario"] = press
r["board"]["log"] = log
r["camera"]["device"] = "sim:width=%s,height=%s,scene=rig,timescale=%s" % (w, h, ts)
r["optics"]["focal_px"] = 2 * int(w)
json.dump(r, open(dst, "w"), indent=1)
PY
}
# outputs NAME: the final value of each output line in the board log
final() {
	python3 - "$tmp/$1-board.log" "$2" <<'PY'
import json, sys
last = {}
for l in open(sys.argv[1]):
    e = json.loads(l)
    last[e["line"]] = e["value"]
want = dict(kv.split("=") for kv in sys.argv[2].split(","))
bad = {k: last.get(k, 0) for k, v in want.items() if last.get(k, 0) != int(v)}
print("  final outputs", last)
sys.exit(1 if bad else 0)
PY
}

check "rig --help" run 0 "" rig --help
check "check-rig of the shipped sim rig" run 0 "" check-rig

if [ "$part" != lamps ]; then
# 1. One press -> complete run with a fit.
rig one '{"at_s": 0.3, "hold_s": 0.1, "bounces": 3}'
check "one press: run, capture, fit" run 0 "run complete" rig --config "$tmp/one.json" --once --json
cp "$tmp/out" "$tmp/one.out"
cp "$tmp/err" "$tmp/one.err"
check "... result names the run's sessions and the fit" python3 -c "
import json, os, sys
d = json.load(open('$tmp/one.out'))
for k in ('probe', 'sample'):
    s = json.load(open(os.path.join(d[k], 'session.json')))
    assert s['status'] == 'complete', (k, s['status'])
for f in ('probe.exr', 'env.exr', 'env-mask.png'):
    assert os.path.getsize(os.path.join(d['probe'], f)) > 0, f
for f in ('sample.exr', 'scene.json', 'fit/params.json', 'fit/compare.png'):
    assert os.path.getsize(os.path.join(d['sample'], f)) > 0, f
p = {q['name']: q['value'] for q in d['fit']['parameters']}
print('  fitted', {k: round(v, 3) for k, v in p.items()})
assert abs(p['diffuse.r'] - 0.292) < 0.02 and abs(p['diffuse.g'] - 0.117) < 0.02
"
probe_dir=$(python3 -c "import json; print(json.load(open('$tmp/one.out'))['probe'])")
check "... the probe's preview rings the light sources it found" python3 "$(dirname "$0")/../cli/check_probe_preview.py" "$probe_dir/env-preview.png" "$probe_dir/env-sources.json"
check "... the final render within half the fit's time, its noise measured and counted in the misfit" python3 -c "
import json, os
d = json.load(open('$tmp/one.out'))
p = json.load(open(os.path.join(d['sample'], 'fit', 'params.json')))
r = p['render']
print('  fit %.2f s; render' % p['seconds'], {k: r[k] for k in ('light_samples', 'brdf_samples', 'noise', 'seconds', 'budget_seconds')},
      'steps', [(s['light_samples'], round(s['noise'], 3), round(s['seconds'], 2)) for s in r['steps']],
      'misfit chi2 %.2f' % p['misfit']['chi2_per_value'])
assert abs(r['budget_seconds'] - max(0.5 * p['seconds'], 1.0)) < 1e-6, r
# the first pair is always made; a second only within the budget
assert r['seconds'] <= max(r['budget_seconds'], r['steps'][0]['seconds']) * 1.15 + 0.3, r
assert 0 < r['noise'] and (r['below_target'] or r['limited_by'].startswith('time')), r
assert r['values'] > 1000, r
assert abs(p['misfit']['render_noise'] - r['noise']) < 1e-9, p['misfit']
"
check "... bounces were debounced into one press" bash -c "test \$(grep -c 'button pressed: starting' '$tmp/one.err') = 1"
check "... outputs safe at the end (lights off, stepper disabled, LED off)" final one "lights=0,turntable_enable=0,led=0,turntable_step=0"
check "... lights were on while capturing, turntable went to 180 deg" python3 -c "
import json
ev = [json.loads(l) for l in open('$tmp/one-board.log')]
on = [e for e in ev if e['line'] == 'lights' and e['value'] == 1]
assert on, 'lights never on'
assert max(e['turntable_deg'] for e in ev) > 179.9, 'turntable never at the sample'
"
check "... LED: idle, busy, done (logged)" python3 -c "
import json
leds = [json.loads(l)['msg'][5:] for l in open('$tmp/one.err') if '\"led: ' in l]
print('  led', leds)
assert leds[:3] == ['idle', 'busy', 'done'], leds
"
check "... LED blinked at 4 Hz while busy" python3 -c "
import json
ev = [json.loads(l) for l in open('$tmp/one-board.log')]
t_on = [e['t'] for e in ev if e['line'] == 'lights' and e['value'] == 1][0]
t_off = [e['t'] for e in ev if e['line'] == 'lights' and e['value'] == 0][-1]
led = [e['t'] for e in ev if e['line'] == 'led' and t_on < e['t'] < t_off]
d = sorted(b - a for a, b in zip(led, led[1:]))
print('  busy toggles', len(led), 'median interval %.3f s' % d[len(d) // 2])
assert len(led) > 10 and abs(d[len(d) // 2] - 0.125) < 0.03
"
check "sessions lists the run's sessions" run 0 "" sessions --root "$tmp/one"
check "... complete, fitted" bash -c "grep -q 'sample .*complete *yes' '$tmp/out' && grep -q 'probe .*complete' '$tmp/out'"
check "jobs lists the done job" run 0 "" jobs --root "$tmp/one"
check "... done" grep -q " done " "$tmp/out"
# A FIFO planted as a job file: its open would wait for a writer forever;
# glint jobs must pass it by (timeout: a hang fails the check).
mkdir -p "$tmp/one/queue/pending" && mkfifo "$tmp/one/queue/pending/planted.json"
check "... a FIFO planted in the queue does not hang glint jobs" timeout 20 "$glint" jobs --root "$tmp/one"
rm -f "$tmp/one/queue/pending/planted.json"
# A record planted with terminal escapes (clear the screen, retitle the
# window): glint jobs shows them as \x1b, never sends them.
printf '{"id": "20261128T000000Z-1-1", "kind": "fit", "session": "/x/s\\u001b[2J", "error": "boom\\u001b]0;owned\\u0007"}\n' >"$tmp/one/queue/failed/20261128T000000Z-1-1.json"
check "... a record's terminal escapes are shown, not sent" bash -c "'$glint' jobs --root '$tmp/one' >'$tmp/jobs.txt' && ! grep -q \$'\\x1b' '$tmp/jobs.txt' && grep -qF 'boom\\x1b]0;owned\\x07' '$tmp/jobs.txt'"
rm -f "$tmp/one/queue/failed/20261128T000000Z-1-1.json"
check "... its record holds the parameters, relative RMSE and the fit's peak memory" bash -c "'$glint' jobs --root '$tmp/one' --json | python3 -c 'import json,sys; j=[x for x in json.load(sys.stdin)[\"jobs\"] if x[\"state\"] == \"done\"]; m=[x.get(\"peak_rss_mib\") for x in j]; print(\"  peak MiB\", m); sys.exit(not j or not all(v and 10 < v < 4096 for v in m) or not all(len(x.get(\"parameters\") or []) >= 4 and x.get(\"relative_rmse\", 0) > 0 for x in j))'"

# 1a. A probe bracket cut short by its cap: the run stops at that step,
# naming it and the cap; the session is incomplete, nothing is unwrapped,
# no sample is captured, no fit is queued.
rig capped '{"at_s": 0.3, "hold_s": 0.1}'
python3 - "$tmp/capped.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
r["bracket"]["max_frames"] = 2
json.dump(r, open(sys.argv[1], "w"))
PY
check "a bracket cut short: rig --once exits 1 naming the step and the cap" run 1 "step 3/7 (capture probe): the probe's bracket: the bracket was stopped by the frame cap (2 frames)" rig --config "$tmp/capped.json" --once
check "... the probe session incomplete, not unwrapped; no sample, no job" python3 -c "
import glob, json, os
runs = glob.glob('$tmp/capped/run-*')
assert len(runs) == 1, runs
p = glob.glob(runs[0] + '/probe-*')
assert len(p) == 1, p
s = json.load(open(p[0] + '/session.json'))
assert s['status'] == 'incomplete' and s['stage'] == 'bracket', (s['status'], s.get('stage'))
assert s['bracket']['truncated'] and s['bracket']['stopped_by'] == 'frame', s['bracket']
assert not os.path.exists(p[0] + '/env.exr'), 'unwrapped'
assert not glob.glob(runs[0] + '/sample-*'), 'a sample was captured'
assert not glob.glob('$tmp/capped/queue/*.json') and not glob.glob('$tmp/capped/queue/*/*.json'), 'a fit was queued'
"

# 1b. With a position sensor (the sim reports the probe in view at 0 deg),
# the moves are checked against it.
rig pos '{"at_s": 0.2}'
python3 -c "
import json
r = json.load(open('$tmp/pos.json'))
r['board']['lines']['position'] = {'chip': 'gpiochip0', 'line': 5}
r['sequence'] = ['lights on', 'turntable sample', 'turntable probe', 'capture probe', 'lights off']
json.dump(r, open('$tmp/pos.json', 'w'))"
check "position sensor agrees with the moves" run 0 "run complete" rig --config "$tmp/pos.json" --once

# 1b. The gray reference ball at its own turntable position
# (data/rig-sim-gray.json's sequence): the probe, the gray ball at 90 deg
# calibrating the probe's map into its session, the sample lit by it.
rig gray '{"at_s": 0.2}'
python3 -c "
import json
r = json.load(open('$tmp/gray.json'))
g = json.load(open('$data/rig-sim-gray.json'))
r['camera']['device'] += ',reference=0.18'
r['reference'] = g['reference']
r['sequence'] = g['sequence']
r['board']['turntable']['reference_deg'] = g['board']['turntable']['reference_deg']
json.dump(r, open('$tmp/gray.json', 'w'))"
check "gray ball at its own position: run, calibration, fit" run 0 "run complete" rig --config "$tmp/gray.json" --once --json
check "... the reference session calibrated the probe's map and lit the sample" python3 -c "
import glob, json, os
d = json.load(open('$tmp/out'))
ref = glob.glob(os.path.join(os.path.dirname(d['sample']), 'reference-*'))
assert len(ref) == 1, ref
cal = json.load(open(os.path.join(ref[0], 'env-calibration.json')))
print('  scale', cal['scale'], '+-', cal['scale_sigma'])
assert all(abs(s - 1) < 3 * e for s, e in zip(cal['scale'], cal['scale_sigma']))
env = json.load(open(os.path.join(d['sample'], 'scene.json')))['environment']
assert env['path'] == '../' + os.path.basename(ref[0]) + '/env.exr', env
assert 'scale_sigma' in env
ev = [json.loads(l) for l in open('$tmp/gray-board.log')]
assert any(abs(e['turntable_deg'] - 90) < 0.5 for e in ev), 'turntable never at the reference'
"

fi # core

if [ "$part" != core ]; then
# 1c. Two lamps on lines of their own: the default sequence captures the
# probe and the sample under each alone and fits one material to both
# photos (the sim's lamp 2 lights the sphere from behind: its Fresnel rim).
rig lamps '{"at_s": 0.2}' 320 240
python3 -c "
import json
r = json.load(open('$tmp/lamps.json'))
r['board']['lines']['lights'] = [{'chip': 'gpiochip0', 'line': 22}, {'chip': 'gpiochip0', 'line': 26}]
del r['sequence']
json.dump(r, open('$tmp/lamps.json', 'w'))"
check "two lamps: a run per lamp, one joint fit" run 0 "one material from the 2 samples" rig --config "$tmp/lamps.json" --once --json
cp "$tmp/out" "$tmp/lamps.out"
check "... run.json names both samples, each lit by its own probe" python3 -c "
import json, os
d = json.load(open('$tmp/lamps.out'))
run = json.load(open(os.path.join(d['run'], 'run.json')))
assert [s['light'] for s in run['samples']] == [1, 2], run
probes = set()
for s in run['samples']:
    sc = json.load(open(os.path.join(d['run'], s['session'], 'scene.json')))
    probes.add(json.dumps(sc['environment'] if 'environment' in sc else sc.get('env')))
assert len(probes) == 2, probes
assert [s['light'] for s in d['samples']] == [1, 2], d['samples']
"
check "... each lamp on alone, and never both" python3 -c "
import json
ev = [json.loads(l) for l in open('$tmp/lamps-board.log')]
on = {'lights': 0, 'lights[1]': 0}
seen = set()
for e in ev:
    if e['line'] in on:
        on[e['line']] = e['value']
        assert sum(on.values()) <= 1, ('both lamps on', e)
        if e['value']:
            seen.add(e['line'])
assert seen == {'lights', 'lights[1]'}, seen
assert on == {'lights': 0, 'lights[1]': 0}, on
"
check "... the joint fit: both photos, every 95 % interval holds the truth" python3 -c "
import json, os
d = json.load(open('$tmp/lamps.out'))
r = json.load(open(os.path.join(d['run'], 'fit', 'params.json')))
assert len(r['photos']) == 2 and all(p['acceptance']['accepted'] for p in r['photos'])
truth = {'diffuse.r': 0.292, 'diffuse.g': 0.117, 'diffuse.b': 0.027, 'specular.r': 0.292, 'specular.g': 0.267, 'specular.b': 0.239, 'roughness': 0.039, 'ior': 1.43}
for q in r['parameters']:
    lo, hi = q['interval']
    print('  %-10s %.4f [%.4f, %.4f] truth %.3f' % (q['name'], q['value'], lo, hi, truth[q['name']]))
    assert lo <= truth[q['name']] <= hi, q['name']
for f in ('render.exr', 'render-2.exr', 'compare.png', 'compare-2.png'):
    assert os.path.getsize(os.path.join(d['run'], 'fit', f)) > 0, f
"
check "... each lamp fitted alone too: one material explains both, no drift" python3 -c "
import json, os
d = json.load(open('$tmp/lamps.out'))
pl = json.load(open(os.path.join(d['run'], 'fit', 'params.json')))['per_light']
print('  ' + pl['verdict'])
for l in pl['lights']:
    print('  photo %d: light %.1f deg from the view, roughness %.4f' % (l['photo'], l['light_angle_deg'], l['values']['roughness']))
assert len(pl['lights']) == 2 and len(pl['trends']) == 8, pl
assert not any(t['drifts'] for t in pl['trends']), pl['verdict']
"
check "... sessions shows the samples fitted by their run" run 0 "" sessions --root "$tmp/lamps"
check "... (FIT: run)" bash -c "test \$(grep -c '^sample .* complete *run ' '$tmp/out') = 2"
run_dir=$(ls -d "$tmp"/lamps/run-*)
check "... glint fit RUN fits it again, into RUN/fit" run 0 "" fit "$run_dir" -q
check "... glint queue add RUN takes it" run 0 "" queue add "$run_dir" --root "$tmp/lamps"
mkdir -p "$tmp/lamps/bad-run"
echo '{"samples": [{"session": "../one", "light": 1}]}' >"$tmp/lamps/bad-run/run.json"
check "... a run.json naming a folder outside its run is refused" run 1 "samples[0]" fit "$tmp/lamps/bad-run"

fi # lamps

if [ "$part" != lamps ]; then
# 2. A second press during the run cancels it.
# (In camera time: the probe's bracket takes seconds, so the second press
# lands inside it however loaded the machine is.)
rig two '{"at_s": 0.3, "hold_s": 0.1}, {"at_s": 1.5, "hold_s": 0.1}' 160 120 1
check "second press cancels the run" run 1 "cancelled (button)" rig --config "$tmp/two.json" --once
check "... the probe session is kept, incomplete" bash -c "grep -q '\"status\": \"incomplete\"' '$tmp'/two/run-*/probe-*/session.json"
check "... no sample captured, no fit queued" bash -c "! ls -d '$tmp'/two/run-*/sample-* 2>/dev/null && ! ls '$tmp'/two/queue/pending/*.json 2>/dev/null"
check "... outputs safe" final two "lights=0,turntable_enable=0,led=0"

# 3. SIGTERM mid-capture: clean stop.
rig term '{"at_s": 0.2, "hold_s": 0.1}'
"$glint" rig --config "$tmp/term.json" 2>"$tmp/term.err" &
pid=$!
wait_until 30 exists "$tmp/term/run-*/probe-*/frame-001.dng"
kill -TERM $pid
wait $pid
st=$?
check "SIGTERM mid-capture: exit 0 (clean shutdown)" test "$st" = 0
check "... says so" grep -q "stopping: outputs safe" "$tmp/term.err"
check "... the session is incomplete with its frames" python3 -c "
import glob, json
s = glob.glob('$tmp/term/run-*/probe-*/session.json')[0]
d = json.load(open(s))
print('  status', d['status'], 'frames', len(d['frames']))
assert d['status'] == 'incomplete' and len(d['frames']) >= 1
"
check "... outputs safe" final term "lights=0,turntable_enable=0,led=0,turntable_step=0"

# 4. Bad rig files: refused before any output moves (no board log).
bad() { # NAME EXPECTED-FRAGMENT PYTHON-EDIT
	rig "$1" '{"at_s": 0.2}'
	python3 -c "
import json
r = json.load(open('$tmp/$1.json'))
$3
json.dump(r, open('$tmp/$1.json', 'w'))"
	check "bad rig ($1): refused, named" run 1 "$2" rig --config "$tmp/$1.json" --once
	check "... no output touched" test ! -s "$tmp/$1-board.log"
}
bad role "board.lines.fan: unknown role" "r['board']['lines']['fan'] = {'chip': 'gpiochip0', 'line': 3}"
bad twice "are the same line" "r['board']['lines']['lights']['line'] = 27"
bad nocam "/dev/video9" "r['camera'] = {'backend': 'v4l2', 'device': '/dev/video9'}"
bad nobutton "board.lines.button: missing" "del r['board']['lines']['button']"
bad mode "turntable.mode" "r['board']['turntable']['mode'] = 'spin'"
bad step "sequence[1]" "r['sequence'] = ['lights on', 'dance']"
bad lamp "the board has 1 light line" "r['sequence'] = ['light 2', 'capture probe']"
bad lampkey "board.lines.lights[1]: unknown role" "r['board']['lines']['lights[1]'] = {'chip': 'gpiochip0', 'line': 3}"
bad lamps5 "a list of 1..4 lines" "r['board']['lines']['lights'] = [{'chip': 'gpiochip0', 'line': 30 + k} for k in range(5)]"
bad lampsame "are the same line" "r['board']['lines']['lights'] = [{'chip': 'gpiochip0', 'line': 22}, {'chip': 'gpiochip0', 'line': 17}]"

# 5. The queue: a worker killed mid-fit leaves its job re-runnable.
sess=$(ls -d "$tmp"/one/run-*/sample-*)
check "queue add" run 0 "" queue add "$sess" --root "$tmp/one"
"$glint" queue run --until-empty --root "$tmp/one" -q &
wpid=$!
wait_until 30 exists "$tmp/one/queue/running/*.json"
# The worker's own child, the fit (this test's processes only).
wait_until 30 pgrep -P $wpid
child=$(pgrep -P $wpid)
kill -KILL $wpid
wait $wpid 2>/dev/null
# The fit dies with its worker, by itself (left running, the next worker
# would fit the session again beside it).
check "the killed worker's fit dies with it" wait_until 5 bash -c "! kill -0 $child"
check "killed worker: its job is still listed as running" bash -c "'$glint' jobs --root '$tmp/one' | grep -q ' running '"
check "a new worker re-runs it" run 0 "put back in the queue" queue run --until-empty --root "$tmp/one"
check "... and it is done" bash -c "'$glint' jobs --root '$tmp/one' --json | python3 -c 'import json,sys; j=json.load(sys.stdin)[\"jobs\"]; s=[x[\"state\"] for x in j]; print(\"  states\", s); sys.exit(s.count(\"done\") != 2 or \"running\" in s or \"pending\" in s)'"
check "a relative session path is stored absolute" bash -c "cd '$(dirname "$sess")' && '$glint' queue add '$(basename "$sess")' --root '$tmp/one' >/dev/null && grep -Eq '\"session\": ?\"/' '$tmp'/one/queue/pending/*.json"
check "... and runs from another folder" bash -c "cd / && '$glint' queue run --until-empty --root '$tmp/one' -q && '$glint' jobs --root '$tmp/one' | grep -c ' done ' | grep -qx 3"
# The session is opened where it is checked: one swapped for a link to
# another folder while its fit runs is still the one fitted, and the
# other folder is not written.
swap="$(dirname "$sess")/swap"
cp -a "$sess" "$swap" && rm -rf "$swap/fit"
mkdir -p "$tmp/one/decoy"
check "queue add of a session to be swapped" run 0 "" queue add "$swap" --root "$tmp/one"
"$glint" queue run --until-empty --root "$tmp/one" -q &
wpid=$!
wait_until 30 pgrep -P $wpid
mv "$swap" "$swap.moved" && ln -s "$tmp/one/decoy" "$swap"
wait $wpid
check "a session swapped for a link mid-fit: the folder checked is fitted, the link's target untouched" bash -c "'$glint' jobs --root '$tmp/one' | grep -c ' done ' | grep -qx 4 && test -f '$swap.moved/fit/params.json' && test -z \"\$(ls -A '$tmp/one/decoy')\""
check "... its params.json names the inputs by the path checked" python3 -c "
import json
d = json.load(open('$swap.moved/fit/params.json'))
print('  ', d['inputs'])
assert d['inputs']['photo'] == '$swap/sample.exr', d['inputs']
"
rm -rf "$swap" "$swap.moved" "$tmp/one/decoy"
mkdir -p "$tmp/linkrun" && ln -s "$sess" "$tmp/linkrun/s1"
echo '{"samples": [{"session": "s1", "light": 1}]}' >"$tmp/linkrun/run.json"
check "a run whose sample is a link: refused, named" run 1 "sample $tmp/linkrun/s1 is not a folder in the run" fit "$tmp/linkrun"
rm -rf "$tmp/linkrun"
# Links planted where the worker writes a job's output (the queue is
# shared over SSH) are removed, never followed: the victim keeps its text.
echo "my notes" >"$tmp/victim.txt"
mkdir -p "$tmp/one/not-a-session"
echo '{"id": "zz-link", "kind": "fit", "session": "'"$tmp"'/one/not-a-session"}' >"$tmp/one/queue/pending/zz-link.json"
ln -s "$tmp/victim.txt" "$tmp/one/queue/running/zz-link.out"
ln -s "$tmp/victim.txt" "$tmp/one/queue/running/zz-link.err"
check "links planted at a job's output files: not followed" bash -c "'$glint' queue run --until-empty --root '$tmp/one' -q && [ \"\$(cat '$tmp/victim.txt')\" = 'my notes' ] && '$glint' jobs --root '$tmp/one' | grep -q 'zz-link *failed'"
# A file whose name is not a job id (over 63 characters) is not a job:
# no worker claims it (it would be claimed under one name and finished
# under another), no listing shows it.
long=$(printf 'zz-long-%070d' 0)
echo '{"kind": "fit", "session": "'"$tmp"'/one/not-a-session"}' >"$tmp/one/queue/pending/$long.json"
check "a job file named past 63 characters is left alone" bash -c "'$glint' queue run --until-empty --root '$tmp/one' -q && test -f '$tmp/one/queue/pending/$long.json' && ! ls '$tmp'/one/queue/{running,failed,done} | grep -q zz-long && ! '$glint' jobs --root '$tmp/one' | grep -q zz-long"
rm -f "$tmp/one/queue/pending/$long.json"
# A job may only fit a session under the folder holding its queue.
mkdir -p "$tmp/elsewhere"
echo '{"id": "zz-out", "kind": "fit", "session": "'"$tmp"'/elsewhere"}' >"$tmp/one/queue/pending/zz-out.json"
check "a job naming a session outside the captures root fails" bash -c "'$glint' queue run --until-empty --root '$tmp/one' -q && '$glint' jobs --root '$tmp/one' | grep 'zz-out' | grep -q 'failed.*outside the captures root'"
# Two users (root and nobody, no accounts made): one may not have the
# other's session fitted, by glint queue add or by a job file written by
# hand; the submitter is the job file's owner.
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null; then
	nobody=(setpriv --reuid=65534 --regid=65534 --clear-groups)
	chmod 0755 "$tmp"
	q="$tmp/one/queue"
	check "the queue's state folders are sticky (a user moves only his own jobs)" bash -c "[ \$(( 0\$(stat -c %a '$q/pending') & 01000 )) != 0 ]"
	chmod 1777 "$q/pending" "$q/running" "$q/cancelled"
	# The queue folder itself, shared and not sticky (as a queue made
	# by hand, or before glint made it sticky): another user is refused,
	# told the fix; its owner's next glint makes it sticky; then the
	# kernel refuses another user's rename of pending/.
	chmod 0777 "$q" && chmod -t "$q"
	check "a shared queue folder that is not sticky: another user's glint jobs refused, the fix named" bash -c "! ${nobody[*]} '$glint' jobs --root '$tmp/one' 2>'$tmp/err' && grep -q 'writable by others and not sticky.*chmod +t' '$tmp/err'"
	check "... its owner's glint makes it sticky" bash -c "'$glint' jobs --root '$tmp/one' >/dev/null && [ \$(( 0\$(stat -c %a '$q') & 01000 )) != 0 ]"
	check "... and another user cannot rename pending/" bash -c "! ${nobody[*]} mv '$q/pending' '$q/pending.x' 2>/dev/null && [ -d '$q/pending' ]"
	chmod 0755 "$q"
	check "another user's session: queue add refuses" bash -c "! ${nobody[*]} '$glint' queue add '$sess' --root '$tmp/one' 2>'$tmp/err' && grep -q 'is not shared with the job.s submitter (uid 65534)' '$tmp/err'"
	# A queue whose worker (its owner, uid 65533) cannot write the
	# submitter's session: queue add refuses at once, naming the fix.
	mkdir -p "$tmp/nq" && cp -r "$sess" "$tmp/nq/s1"
	"$glint" queue add "$tmp/nq/s1" --root "$tmp/nq" >/dev/null 2>&1 || true
	rm -f "$tmp"/nq/queue/pending/*.json
	chown -R 65533:65533 "$tmp/nq/queue" && chmod 1777 "$tmp/nq/queue/pending"
	chown -R 65534:65534 "$tmp/nq/s1" && chmod 0755 "$tmp/nq/s1" "$tmp/nq"
	check "a session the queue's worker cannot write: queue add refuses" bash -c "! ${nobody[*]} '$glint' queue add '$tmp/nq/s1' --root '$tmp/nq' 2>'$tmp/err' && grep -q 'the queue.s worker (uid 65533) cannot write its fit there' '$tmp/err' && ! ls '$tmp/nq/queue/pending' | grep -q json"
	${nobody[@]} bash -c "echo '{\"id\": \"zz-other\", \"kind\": \"fit\", \"session\": \"$sess\"}' >'$tmp/one/queue/pending/zz-other.json'"
	# A finished record claims its submitter; only the worker's own
	# (the queue owner's, not group-writable) is believed.
	echo '{"id": "zz-claim", "kind": "fit", "session": "/x", "state": "done", "submitter_uid": 0}' >"$q/done/zz-claim.json"
	chown 65534:65534 "$q/done/zz-claim.json"
	echo '{"id": "zz-claim2", "kind": "fit", "session": "/x", "state": "done", "submitter_uid": 65534}' >"$q/done/zz-claim2.json"
	chmod 0660 "$q/done/zz-claim2.json"
	check "a finished record planted by another user, or rewritable by the group: its claimed submitter is not believed" bash -c "'$glint' jobs --root '$tmp/one' >'$tmp/jobs.txt' && grep -q 'zz-claim  *done *fit  nobody' '$tmp/jobs.txt' && grep -q 'zz-claim2  *done *fit  root' '$tmp/jobs.txt'"
	rm -f "$q/done/zz-claim.json" "$q/done/zz-claim2.json"
	check "... and a job file written by hand fails, its submitter named" bash -c "'$glint' queue run --until-empty --root '$tmp/one' -q && '$glint' jobs --root '$tmp/one' | grep 'zz-other' | grep -q 'failed *fit  nobody .*belongs to uid 0 and is not shared'"
	# Another user may not steer a job: cancel it, move it, hold its
	# lock, or ask its worker to stop it.
	id=$("$glint" queue add "$sess" --root "$tmp/one")
	check "another user's glint queue cancel: refused, the submitter named" bash -c "! ${nobody[*]} '$glint' queue cancel '$id' --root '$tmp/one' 2>'$tmp/err' && grep -q 'submitted by uid 0: only it' '$tmp/err' && [ -e '$q/pending/$id.json' ]"
	check "... and the kernel refuses his mv of it (sticky folder)" bash -c "! ${nobody[*]} mv '$q/pending/$id.json' '$q/cancelled/' 2>/dev/null && [ -e '$q/pending/$id.json' ]"
	${nobody[@]} flock -o "$q/running/$id.lock" sleep 120 &
	holder=$!
	wait_until 10 exists "$q/running/$id.lock"
	check "a lock planted by another user to hold a job hostage is removed" bash -c "'$glint' queue run --until-empty --root '$tmp/one' 2>'$tmp/err' && grep -q 'removing a lock file of uid 65534' '$tmp/err' && '$glint' jobs --root '$tmp/one' | grep -q '$id *done'"
	pkill -P $holder
	kill $holder 2>/dev/null
	wait $holder 2>/dev/null
	id=$("$glint" queue add "$sess" --root "$tmp/one")
	"$glint" queue run --until-empty --root "$tmp/one" 2>"$tmp/werr" &
	wpid=$!
	wait_until 30 exists "$q/running/$id.err"
	${nobody[@]} touch "$q/running/$id.cancel"
	wait $wpid
	check "a cancel request by another user is ignored: the job is done" bash -c "grep -q 'ignoring a cancel request by uid 65534' '$tmp/werr' && '$glint' jobs --root '$tmp/one' | grep -q '$id *done'"
	# A worker running as root runs a job as its submitter: nobody's
	# session whose scene.json names a root-only light probe is not
	# fitted with it (as root it would be rendered into his fit/), and
	# his own session's fit is written as him.
	mine="$tmp/one/nobody-sess"
	cp -r "$sess" "$mine" && rm -rf "$mine/fit"
	# scene.json's probe paths made absolute (the copy is elsewhere);
	# with SECRET, a root-only copy of the probe.
	env_to() { # SCENE [SECRET]
		python3 - "$sess" "$@" <<'PY'
import json, os, shutil, sys
orig, scene = sys.argv[1:3]
d = json.load(open(scene))
env = os.path.join(orig, d["environment"]["path"])
if len(sys.argv) > 3:
    shutil.copy(env, sys.argv[3])
    os.chmod(sys.argv[3], 0o600)
    env = sys.argv[3]
d["environment"]["path"] = os.path.abspath(env)
if "sources" in d["environment"]:
    d["environment"]["sources"] = os.path.abspath(os.path.join(orig, d["environment"]["sources"]))
json.dump(d, open(scene, "w"), indent=1)
PY
	}
	env_to "$mine/scene.json" "$tmp/secret.exr"
	chown -R 65534:65534 "$mine"
	check "a root worker runs nobody's job as nobody: a root-only file his scene names is not read" bash -c "id=\$(${nobody[*]} '$glint' queue add '$mine' --root '$tmp/one') && '$glint' queue run --until-empty --root '$tmp/one' 2>'$tmp/werr' && grep -q 'as uid 65534' '$tmp/werr' && '$glint' jobs --root '$tmp/one' | grep \"\$id\" | grep -q 'failed.*secret.exr.*ermission denied' && ! ls '$mine/fit' 2>/dev/null | grep -q png"
	rm -rf "$mine" && cp -r "$sess" "$mine" && rm -rf "$mine/fit"
	env_to "$mine/scene.json"
	chown -R 65534:65534 "$mine"
	check "... and his own session is fitted, its results his" bash -c "id=\$(${nobody[*]} '$glint' queue add '$mine' --root '$tmp/one') && '$glint' queue run --until-empty --root '$tmp/one' -q && '$glint' jobs --root '$tmp/one' | grep -q \"\$id *done\" && [ \"\$(stat -c %u '$mine/fit/params.json')\" = 65534 ]"
	chmod 0700 "$tmp"
else
	echo "skip two-user checks: not root or no setpriv"
fi
# A link in place of one of the queue's folders is refused.
mkdir -p "$tmp/linkq/queue" "$tmp/linkq/elsewhere"
ln -s "$tmp/linkq/elsewhere" "$tmp/linkq/queue/running"
check "a queue whose running/ is a link: refused" run 1 "running: not a folder (a link?)" queue run --until-empty --root "$tmp/linkq"
# A job file is data, never options: "--help" as its session fails the job.
echo '{"id": "zz-evil", "kind": "fit", "session": "--help"}' >"$tmp/one/queue/pending/zz-evil.json"
check "a job whose session is '--help' fails as a bad job" bash -c "'$glint' queue run --until-empty --root '$tmp/one' -q && '$glint' jobs --root '$tmp/one' --json | python3 -c 'import json,sys; j=[x for x in json.load(sys.stdin)[\"jobs\"] if x[\"id\"] == \"zz-evil\"]; print(\"  \", j); sys.exit(j[0][\"state\"] != \"failed\")'"
id=$("$glint" queue add "$sess" --root "$tmp/one")
check "queue add of a session already waiting: refused, the job named" run 1 "is already queued: job $id (pending)" queue add "$sess" --root "$tmp/one"
check "cancel a pending job" run 0 "" queue cancel "$id" --root "$tmp/one"
check "... listed as cancelled" bash -c "'$glint' jobs --root '$tmp/one' | grep -q '$id *cancelled'"
check "... and says what it cancelled" grep -q "cancelled pending job $id" "$tmp/out"
check "cancel of an unknown job: named" run 1 "nosuchjob" queue cancel nosuchjob --root "$tmp/one"
# Hard links carry their target's owner: a lock file that is a link to
# the job's own file is removed (never truncated), and a cancel request
# that is a link to it is ignored.
hq="$tmp/one/queue"
id=$("$glint" queue add "$sess" --root "$tmp/one")
ln "$hq/pending/$id.json" "$hq/running/$id.lock"
check "a lock file hard-linked to the job's file: removed, the job runs whole" bash -c "'$glint' queue run --until-empty --root '$tmp/one' 2>'$tmp/werr' && grep -q 'removing a lock file of uid' '$tmp/werr' && '$glint' jobs --root '$tmp/one' | grep -q '$id *done'"
id=$("$glint" queue add "$sess" --root "$tmp/one")
"$glint" queue run --until-empty --root "$tmp/one" 2>"$tmp/werr" &
wpid=$!
wait_until 30 exists "$hq/running/$id.err"
ln "$hq/running/$id.json" "$hq/running/$id.cancel"
wait $wpid
check "a cancel request hard-linked to the job's file: ignored, the job done" bash -c "grep -q 'ignoring a cancel request by uid 0 (not its submitter, or a hard link: 2 names)' '$tmp/werr' && '$glint' jobs --root '$tmp/one' | grep -q '$id *done'"
probe=$(ls -d "$tmp"/one/run-*/probe-* | head -1)
check "queue add of a probe session: refused with the reason" run 1 "a probe session is the light of a sample's scene" queue add "$probe" --root "$tmp/one"
# A job that fails when it runs keeps its reason as text.
cp -r "$sess" "$tmp/one/broken"
rm -rf "$tmp/one/broken/fit"
echo "not an image" >"$tmp/one/broken/sample.exr"
check "queue add of a session whose photo is damaged" run 0 "" queue add "$tmp/one/broken" --root "$tmp/one"
check "... the worker runs it" run 0 "" queue run --until-empty --root "$tmp/one" -q
check "... glint jobs shows why it failed, as text" bash -c "'$glint' jobs --root '$tmp/one' | grep ' failed ' | tee /dev/stderr | grep -q -- '-- .*sample.exr: not a readable OpenEXR' && ! '$glint' jobs --root '$tmp/one' | grep -q '{\"level'"

# The systemd unit is valid (with this build's glint in ExecStart).
if command -v systemd-analyze >/dev/null; then
	sed "s#^ExecStart=[^ ]*glint #ExecStart=$glint #" "$(dirname "$glint")/../glint-rig.service" >"$tmp/glint-rig.service"
	check "systemd unit verifies" bash -c "systemd-analyze verify '$tmp/glint-rig.service' 2>&1 | tee '$tmp/verify' >&2; ! grep -q . '$tmp/verify'"
fi

# 6. The same appliance on the libgpiod backend, through the fake chip.
if [ "$fakegpio" != none ]; then
	rig gpio '{"at_s": 0.3}'
	python3 -c "
import json
r = json.load(open('$tmp/gpio.json'))
r['board']['backend'] = 'gpiod'
del r['board']['scenario'], r['board']['log']
json.dump(r, open('$tmp/gpio.json', 'w'))"
	gpio() { # EXPECTED FRAGMENT FAKE_GPIO ARGS...
		local want=$1 frag=$2 opts=$3
		shift 3
		FAKE_GPIO="$opts" LD_PRELOAD="$fakegpio" run "$want" "$frag" "$@"
	}
	check "gpiod: check-rig finds the lines free" gpio 0 "line(s) present and free" "" check-rig --config "$tmp/gpio.json"
	check "gpiod: a busy line is named with its consumer" gpio 1 "in use by \"pigpiod\"" "busy=22:pigpiod" check-rig --config "$tmp/gpio.json"
	check "gpiod: one press runs the whole sequence" gpio 0 "run complete" "press=0.3:0.1:2,log=$tmp/gpio.log" rig --config "$tmp/gpio.json" --once
	check "... lights (line 22) ended off, enable (25, active low) high" python3 -c "
import json
last = {}
for l in open('$tmp/gpio.log'):
    e = json.loads(l)
    last[e['offset']] = (e['value'], e['phys'])
print('  final (logical, physical)', last)
assert last[22] == (0, 0) and last[25] == (0, 1) and last[27][0] == 0
"
fi

fi # core

echo "$((checks - fails)) passed, $fails failed"
[ "$fails" = 0 ]
