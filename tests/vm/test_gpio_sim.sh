#!/bin/bash
# The libgpiod board backend on the kernel's own GPIO chip (gpio-sim, in the
# test VM): the chip found by its label and its lines by name, a line held
# by another program reported busy with that program's name, a bouncing
# press pulled through sysfs counted once, every output read back from the
# chip while glint drives it (lights, LED blink, stepper pulses and their
# timing), one full press-to-fit run, its run fitted again through the
# queue by two real accounts (users.sh), and SIGTERM leaving outputs safe.
# usage: test_gpio_sim.sh GLINT DATA_DIR   (inside scripts/vm run)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
glint=$1
data=$2
need_vm
tmp=$(mktemp -d)
sampler=""
trap '[ -z "$sampler" ] || kill $sampler 2>/dev/null; rm -rf "$tmp"' EXIT

# The rig's lines, named as a board's device tree would name them.
chip=$(gpio_sim_chip glint glint-rig 32 17=glint-button 22=glint-lights \
	27=glint-led 23=glint-step 24=glint-dir 25=glint-enable) || {
	echo "FAIL gpio-sim chip not created" >&2
	exit 1
}
sys=$(gpio_sim_dir glint)
echo "gpio-sim: $chip ($sys)"
pull() { echo "$2" >"$sys/sim_gpio$1/pull"; }
pull 17 pull-up # the button idles high (active low)
# A released line goes back to its pull (gpio_sim_free() restores it, as a
# board's resistors would): the stepper's active-low enable is pulled up,
# the other outputs down, so that released means safe as on a real rig.
pull 25 pull-up

# A rig file: the simulated camera, the real chip by label, lines by name.
# The stepper is slowed to 10 Hz so that each 50 ms pulse is read back
# even on a loaded machine (the simulated camera's view depends on it).
rigfile() { # OUT OUTPUT_DIR [WIDTH HEIGHT]
	python3 - "$data/rig-sim.json" "$1" "$2" "${3:-160}" "${4:-120}" <<'PY'
import json, sys
src, dst, out, w, h = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
# The simulated camera sees what the real lines did (sample_lines.py --world).
r["camera"]["device"] = "sim:width=%s,height=%s,scene=rig,timescale=0.05,world=%s.world" % (w, h, out)
r["optics"]["focal_px"] = 2 * int(w)
b = r["board"]
b["backend"] = "gpiod"
del b["scenario"]
names = {"button": "glint-button", "lights": "glint-lights", "led": "glint-led",
         "turntable_step": "glint-step", "turntable_dir": "glint-dir",
         "turntable_enable": "glint-enable"}
for role, name in names.items():
    line = b["lines"][role]
    line["chip"] = "glint-rig"
    line["line"] = name
# Settling 0.5 s, as a loaded turntable would, also gives the sampler time
# to show the camera the new position on a slow host.
b["turntable"].update(steps_per_turn=40, step_hz=10, settle_s=0.5)
json.dump(r, open(dst, "w"), indent=1)
PY
}
# 96 x 72: the emulated CPU (TCG) renders the simulator's views and runs
# the fit some 50 times slower than the host; a ball of 29 px still fits.
rigfile "$tmp/rig.json" "$tmp/out" 96 72

run() { # EXPECTED_STATUS FRAGMENT ARGS...
	local want=$1 frag=$2
	shift 2
	"$glint" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
	local got=$?
	if [ "$got" != "$want" ]; then
		echo "  glint $*: exit $got, expected $want; stderr:" >&2
		tail -20 "$tmp/stderr" >&2
		return 1
	fi
	if [ -n "$frag" ] && ! grep -qF -- "$frag" "$tmp/stderr" "$tmp/stdout"; then
		echo "  glint $*: output lacks '$frag':" >&2
		cat "$tmp/stderr" "$tmp/stdout" | tail -20 >&2
		return 1
	fi
}

check "check-rig finds the chip by label and the lines by name" \
	run 0 "" check-rig --config "$tmp/rig.json" --json
check "... and says where each one is on the chip" python3 -c "
import json
d = json.load(open('$tmp/stdout'))['lines']
print('  ', d['lights'], '|', d['turntable_enable'])
assert d['lights'] == '$chip (glint-rig) line 22 \"glint-lights\"', d
assert d['button'] == '$chip (glint-rig) line 17 \"glint-button\"', d
"

# Another program holds the lights line: refused, naming it, before any
# output moves.
gpioset --mode=signal "$chip" 22=0 &
holder=$!
check "another consumer's line: gpioinfo shows it used" \
	wait_until 10 bash -c "gpioinfo $chip | grep -E 'line +22:.*\"gpioset\"'"
check "check-rig: the lights line is busy, held by gpioset" \
	run 1 'busy: in use by "gpioset"' check-rig --config "$tmp/rig.json"
kill $holder
wait $holder 2>/dev/null
check "... free again once gpioset is gone" \
	wait_until 10 "$glint" check-rig --config "$tmp/rig.json"

# Outputs read back from the chip while glint drives them.
# The sampler reads the kernel's own record of every value set (trace
# events), so it misses no 50 ms step pulse however the VM's vCPUs are
# scheduled on a loaded host; at a real-time priority it writes the
# simulated camera's world as soon as the kernel has the change.
start_sampler() { # LOG WORLD
	chrt -f 50 python3 "$here/sample_lines.py" --world "$2" 40 "$1" lights="$sys/sim_gpio22/value" \
		led="$sys/sim_gpio27/value" dir="$sys/sim_gpio24/value" \
		step="$sys/sim_gpio23/value" enable="$sys/sim_gpio25/value" &
	sampler=$!
	wait_until 10 test -s "$1"
}
stop_sampler() {
	kill $sampler
	wait $sampler 2>/dev/null
	sampler=""
}
# press [BOUNCES]: the button pulled low through sysfs, with contact bounce
press() {
	local i
	for ((i = 0; i < ${1:-0}; i++)); do
		pull 17 pull-down
		pull 17 pull-up
	done
	pull 17 pull-down
	python3 -c 'import time; time.sleep(0.1)' # held for 100 ms
	pull 17 pull-up
}

# One press with bounce: one whole run to a fit.
start_sampler "$tmp/one.lines" "$tmp/out.world"
"$glint" rig --config "$tmp/rig.json" --once --json >"$tmp/one.out" 2>"$tmp/one.err" &
pid=$!
ready() { grep -q "waiting for the capture button" "$1" || ! kill -0 $pid; }
check "rig: ready for the button" wait_until 300 ready "$tmp/one.err" ||
	tail -5 "$tmp/one.err"
press 3
wait $pid
st=$?
# The chip holds the last values glint set until it releases the lines;
# the sampler has them.
stop_sampler
check "one bouncing press: run complete (exit $st)" test "$st" = 0
if [ "$st" != 0 ]; then
	tail -15 "$tmp/one.err"
	# What the simulated camera was shown, and when (the sampler's record).
	python3 "$here/sample_lines.py" --explain "$tmp/one.lines" "$tmp/one.err"
fi
check "... the bounces were one press" \
	test "$(grep -c 'button pressed: starting' "$tmp/one.err")" = 1
check "... fitted from the captured sessions" python3 -c "
import json
d = json.load(open('$tmp/one.out'))
p = {q['name']: q['value'] for q in d['fit']['parameters']}
print('  fitted', {k: round(v, 3) for k, v in p.items()})
assert abs(p['diffuse.r'] - 0.292) < 0.03 and abs(p['diffuse.g'] - 0.117) < 0.03
"
check "... outputs read back from the chip: lights, LED, 20 step pulses, safe at the end" \
	python3 - "$tmp/one.lines" <<'PY'
import json, sys
ev = [e for e in map(json.loads, open(sys.argv[1])) if "line" in e]
def changes(name):
    return [(e["t"], e["value"]) for e in ev if e["line"] == name]
last = {e["line"]: e["value"] for e in ev}
print("  final levels", last)
lights = changes("lights")
assert any(v == 1 for _, v in lights), "lights never on"
t_on = [t for t, v in lights if v == 1][0]
t_off = [t for t, v in lights if v == 0 and t > t_on][0]
# 180 degrees at 40 steps a turn: 20 rising edges on the step line while
# the (active-low) enable line is low, the direction line set.
rises = [t for t, v in changes("step") if v == 1]
print("  step pulses", len(rises))
assert len(rises) == 20, len(rises)
d = sorted(b - a for a, b in zip(rises, rises[1:]))
print("  step period median %.4f s (10 Hz: 0.1)" % d[len(d) // 2])
assert abs(d[len(d) // 2] - 0.1) < 0.02
en = changes("enable")
assert any(v == 0 for _, v in en), "stepper never enabled (active low)"
led = [t for t, _ in changes("led") if t_on < t < t_off]
dl = sorted(b - a for a, b in zip(led, led[1:]))
print("  LED toggles while busy", len(led), "median %.3f s (4 Hz: 0.125)" % dl[len(dl) // 2])
assert len(led) > 4 and abs(dl[len(dl) // 2] - 0.125) < 0.03
# Safe: lights off, stepper disabled (enable high: active low), step low.
assert last["lights"] == 0 and last["enable"] == 1 and last["step"] == 0, last
PY

# The job queue shared by two real accounts, on this press's run.
check "the queue shared by two accounts (tests/vm/users.sh)" \
	bash "$here/users.sh" "$glint" "$(ls -d "$tmp"/out/run-* | head -1)"

# SIGTERM mid-capture: every output safe before the lines are released.
rigfile "$tmp/term.json" "$tmp/term" 80 60 # no fit: a smaller scene to render
start_sampler "$tmp/term.lines" "$tmp/term.world"
"$glint" rig --config "$tmp/term.json" 2>"$tmp/term.err" &
pid=$!
wait_until 300 ready "$tmp/term.err"
press
check "rig: capturing after the press" wait_until 120 exists "$tmp/term/run-*/probe-*/frame-001.dng"
kill -TERM $pid
wait $pid
st=$?
stop_sampler
check "SIGTERM mid-capture: clean exit (status $st)" test "$st" = 0
check "... says so" grep -q "stopping: outputs safe" "$tmp/term.err"
check "... lights were on and then off, stepper disabled, LED off" python3 - "$tmp/term.lines" <<'PY'
import json, sys
ev = [e for e in map(json.loads, open(sys.argv[1])) if "line" in e]
last = {e["line"]: e["value"] for e in ev}
print("  final levels", last)
assert any(e["line"] == "lights" and e["value"] == 1 for e in ev)
assert last["lights"] == 0 and last["enable"] == 1 and last["led"] == 0 and last["step"] == 0, last
PY
finish
