#!/usr/bin/env bash
# glint capture and glint cameras as a user meets them: on the simulated
# camera, and on the V4L2 backend through the fake device (LD_PRELOAD) with
# injected faults; every session on disk is checked whole.
# usage: test_capture_cli.sh GLINT FAKE_V4L2_SO|none CHECK_SESSION_PY
set -u
. "$(dirname "$0")/../wait.sh"
glint=$1
fake=$2
checker=$3
check_env=$4
data=$5
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"

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

# run EXPECTED_STATUS FRAGMENT ARGS... (env FAKE=1 preloads the fake)
run() {
	local want=$1 frag=$2
	shift 2
	if [ "${FAKE:-0}" = 1 ]; then
		LD_PRELOAD=$fake "$glint" "$@" >"$tmp/out" 2>"$tmp/err"
	else
		"$glint" "$@" >"$tmp/out" 2>"$tmp/err"
	fi
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

only_session() { # the one session directory under $1
	local d
	d=$(ls -d "$1"/*/ 2>/dev/null | head -1)
	echo "${d%/}"
}

check "capture --help" run 0 "" capture --help
check "cameras --help" run 0 "" cameras --help
check "capture without what: exit 2" run 2 "probe, reference or sample" capture
check "capture of something else: exit 2" run 2 "'teapot': expected one of probe, reference, sample" capture teapot

cat >"$tmp/rig.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,decades=4"},
 "bracket": {"step_ev": 1, "max_frames": 24},
 "roi": {"sample": [0, 0, 96, 64]},
 "output": "$tmp/caps"}
JSON
check "sim capture completes" run 0 "range covered" capture sample --config "$tmp/rig.json"
check "its session is complete and whole" python3 "$checker" "$(only_session "$tmp/caps")" complete 8
check "... with the merged HDR beside the frames" bash -c "cd '$(only_session "$tmp/caps")' && test -s sample.exr && test -s sample-variance.exr && test -s sample-weights.exr && test -s sample-mask.png"
check "... with the merged HDR beside the frames" bash -c "cd '$(only_session "$tmp/caps")' && test -s sample.exr && test -s sample-variance.exr && test -s sample-weights.exr && test -s sample-mask.png"
check "--json result" run 0 "" capture probe --config "$tmp/rig.json" -o "$tmp/caps2" --json
check "--json says complete" python3 -c "import json,sys; d=json.load(open('$tmp/out')); sys.exit(d['status']!='complete' or d['frames']<8)"

# glint hdr on that session, and on bad frame sets.
sess=$(only_session "$tmp/caps")
check "hdr of the session" run 0 "" hdr "$sess" --json
check "... writes radiance, variance, weights, mask" \
	bash -c "cd '$sess' && test -s hdr.exr && test -s variance.exr && test -s weights.exr && test -s mask.png && test -s hdr.json"
# The capture folded each frame into the merge as it arrived; glint hdr
# reads them back one at a time in the same order: the same bits.
check "... the capture's own merge, bit for bit" cmp "$sess/hdr.exr" "$sess/sample.exr"
check "... and its variance" cmp "$sess/variance.exr" "$sess/sample-variance.exr"
check "... still bracket, all valid" python3 -c "import json,sys; d=json.load(open('$tmp/out')); sys.exit(d['moved'] or d['valid_pixels'] != 96*64)"
# Raw frames are DNGs that raw tools open: dcraw and LibRaw decode glint's
# numbers bit for bit, with its exposure time, ISO and CFA pattern.
check "a DNG frame opens in dcraw and LibRaw, bit for bit" python3 "$(dirname "$checker")/check_raw_tools.py" "$sess/frame-003.dng" "$tmp"
check "hdr of files without -o: exit 2" run 2 "-o DIR" hdr "$sess/frame-000.dng"
cp "$sess/frame-003.dng" "$tmp/f3.dng"
head -c 2000 "$sess/frame-004.dng" >"$tmp/f4.dng"
check "hdr of a truncated frame: exit 1, named" run 1 "f4.dng" hdr "$tmp/f3.dng" "$tmp/f4.dng" -o "$tmp/hdrx"
check "... nothing written" test ! -e "$tmp/hdrx/hdr.exr"
sess2=$(only_session "$tmp/caps2")
cat >"$tmp/small.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=32,height=32,timescale=0.01"}, "output": "$tmp/small"}
JSON
"$glint" capture sample --config "$tmp/small.json" -q
check "hdr of frames of different sizes: exit 1" run 1 "must match" hdr "$sess/frame-003.dng" "$(only_session "$tmp/small")/frame-001.dng" -o "$tmp/hdry"
check "hdr of a missing session: exit 1" run 1 "nowhere" hdr "$tmp/nowhere"
# Bracket integrity: a frame copied over another, or one whose
# pixels were edited (a valid DNG, its metadata kept), is named.
cp -r "$sess" "$tmp/copied"
cp "$tmp/copied/frame-007.dng" "$tmp/copied/frame-002.dng"
check "hdr of a session with a frame copied over another: exit 1, named" \
	run 1 "frame-002.dng: holds frame 7 of the bracket, not frame 2" hdr "$tmp/copied"
# A frame of another session of the same scene (same index, exposure and
# camera sequence; the sensor's noise seeded otherwise) is not the one
# this session recorded.
sed -e 's/decades=4"/decades=4,seed=2"/' -e "s|$tmp/caps\"|$tmp/caps3\"|" "$tmp/rig.json" >"$tmp/rig3.json"
"$glint" capture sample --config "$tmp/rig3.json" -q
sess3=$(only_session "$tmp/caps3")
check "... the other session's frame 2: same exposure and sequence" python3 -c "
import json, sys
a, b = (json.load(open(d + '/frame-002.json')) for d in ('$sess', '$sess3'))
sys.exit(not (a['exposure_s'] == b['exposure_s'] and a['sequence'] == b['sequence'] and a['pixels_crc32'] != b['pixels_crc32']))"
cp -r "$sess" "$tmp/foreign"
cp "$sess3/frame-002.dng" "$tmp/foreign/frame-002.dng"
check "hdr of a session with another session's frame: exit 1, named" \
	run 1 "frame-002.dng: its pixels (CRC-32 " hdr "$tmp/foreign"
cp -r "$sess" "$tmp/edited"
python3 - "$tmp/edited/frame-004.dng" <<'PY'
import struct, sys
path = sys.argv[1]
data = bytearray(open(path, "rb").read())
assert data[:4] == b"II*\0", data[:4]
ifd, = struct.unpack("<I", data[4:8])
n, = struct.unpack("<H", data[ifd:ifd + 2])
for k in range(n):
    tag, typ, count, val = struct.unpack("<HHII", data[ifd + 2 + 12 * k:ifd + 14 + 12 * k])
    if tag == 273:  # StripOffsets: the first strip's
        first = val if count == 1 else struct.unpack("<I", data[val:val + 4])[0]
data[first + 2 * 40] ^= 0x10  # row 0, sample 40
open(path, "wb").write(data)
PY
check "hdr of a session with an edited frame: exit 1, named" \
	run 1 "frame-004.dng: the pixels do not match their checksum" hdr "$tmp/edited"

# A probe capture on the simulated rig: the merged probe.exr, the ball
# found in it and unwrapped to env.exr, which must match the map it
# reflects.
sed "s#\"captures\"#\"$tmp/probe\"#" "$data/rig-sim-probe.json" >"$tmp/probe.json"
check "probe capture: merged, ball found, unwrapped" run 0 "probe ball at" capture probe --config "$tmp/probe.json"
psess=$(only_session "$tmp/probe")
check "... env.exr, its mask and density" bash -c "cd '$psess' && test -s probe.exr && test -s env.exr && test -s env-mask.png && test -s env-density.exr"
check "... env.exr is the reflected map (median error <= 5 %)" "$check_env" "$psess/env.exr" "$psess/env-mask.png" sim-rig 0.05

echo '{"camera": {"backend": "sim"}, "bracket": {"stepev": 1}}' >"$tmp/typo.json"
check "misspelt rig key: exit 1, named" run 1 "stepev" capture sample --config "$tmp/typo.json"
echo '{"camera": {"backend": "gopro"}}' >"$tmp/nob.json"
check "unknown backend: exit 1, named" run 1 "gopro" capture sample --config "$tmp/nob.json" -o "$tmp/x"
check "missing config: exit 1, named" run 1 "nowhere.json" capture sample --config "$tmp/nowhere.json"
cat >"$tmp/auto.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:manual=0,timescale=0.01"}, "output": "$tmp/auto"}
JSON
check "no manual exposure: refused, named" run 1 "no manual exposure" capture sample --config "$tmp/auto.json"
check "the refused session is kept, incomplete" python3 "$checker" "$(only_session "$tmp/auto")" incomplete 0

# The first press: a stage that did not make what it promised stops the
# chain there, and the session says which stage and why.
cat >"$tmp/capped.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,decades=4"},
 "bracket": {"step_ev": 1, "max_frames": 2}, "output": "$tmp/capped"}
JSON
check "a bracket cut by the frame cap: exit 1, the cap named" run 1 "stopped by the frame cap (2 frames) before it covered" capture sample --config "$tmp/capped.json"
check "... the stage named" grep -q "the sample's bracket" "$tmp/err"
check "... its session incomplete, frames whole" python3 "$checker" "$(only_session "$tmp/capped")" incomplete 1
check "... nothing merged from it" bash -c "! ls '$(only_session "$tmp/capped")'/sample.exr 2>/dev/null"
cat >"$tmp/timecap.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,decades=4"},
 "bracket": {"step_ev": 1, "max_time_s": 0.05}, "output": "$tmp/timecap"}
JSON
check "a bracket cut by the time cap: exit 1, named" run 1 "the time cap (0.05 s of the camera's exposure and readout)" capture sample --config "$tmp/timecap.json"
check "... its session incomplete" python3 "$checker" "$(only_session "$tmp/timecap")" incomplete 1
# The lab dark (the rig scene with no world file: lights off, nothing in
# view): every frame black, the merge refuses, the session says failed.
cat >"$tmp/dark.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,scene=rig,world=$tmp/no-world"},
 "output": "$tmp/dark"}
JSON
check "a dark lab: exit 1, the merge names why" run 1 "the sample's merge: HDR merge: every frame is black" capture sample --config "$tmp/dark.json"
check "... its session failed at the merge" python3 "$checker" "$(only_session "$tmp/dark")" failed 1
check "... stage merge in session.json" python3 -c "import json,sys; d=json.load(open('$(only_session "$tmp/dark")/session.json')); sys.exit(d['stage'] != 'merge')"
check "glint fit of it: refused, with the stage and why" run 1 "a failed sample session (stopped at its merge stage: HDR merge: every frame is black" fit "$(only_session "$tmp/dark")"
check "glint sessions shows it failed" bash -c "'$glint' sessions --root '$tmp/dark' | grep -q failed"
# A write the file system refuses during the merge (the file-size limit
# stands in for a full disk: the same failed write): failed, not complete.
cat >"$tmp/full.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,decades=4"},
 "output": "$tmp/full"}
JSON
check "a write refused in the merge: exit 1" bash -c "(trap '' XFSZ; ulimit -f 40; exec '$glint' capture sample --config '$tmp/full.json') 2>'$tmp/err'; test \$? = 1 && grep -q \"the sample's merge\" '$tmp/err'"
check "... its session failed, no sample.exr called complete" python3 "$checker" "$(only_session "$tmp/full")" failed 1
# Frames of another scene among a bracket (a different card at the same
# exposures): refused by name, nothing merged.
cat >"$tmp/other.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=96,height=64,timescale=0.01,decades=2"},
 "output": "$tmp/other"}
JSON
"$glint" capture sample --config "$tmp/other.json" -q 2>/dev/null
osess=$(only_session "$tmp/other")
mixed=()
for f in "$sess"/frame-00[0-5].dng; do mixed+=("$f"); done
mixed+=("$osess/frame-000.dng")
check "a bracket with another scene's frame: exit 1, the pair named" run 1 "disagree beyond their noise" hdr "${mixed[@]}" -o "$tmp/mixed"
check "... refused, nothing merged" test ! -e "$tmp/mixed/hdr.exr"

check "cameras lists the sim" run 0 "" cameras --backend sim
check "... with its ranges" grep -q "exposure manual" "$tmp/out"
check "cameras --json" run 0 "" cameras --json
check "... parses" python3 -c "import json; json.load(open('$tmp/out'))"

# Interrupted: real-time sim, SIGINT once the first frame is on disk.
cat >"$tmp/slow.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=64,height=48"}, "output": "$tmp/slow"}
JSON
"$glint" capture sample --config "$tmp/slow.json" -q 2>"$tmp/err" &
pid=$!
wait_until 30 exists "$tmp/slow/*/frame-001.dng"
kill -INT $pid
wait $pid
st=$?
check "SIGINT: exit 130" test "$st" = 130
check "SIGINT: message says cancelled" grep -q "cancelled" "$tmp/err"
check "SIGINT: session incomplete with its frames" python3 "$checker" "$(only_session "$tmp/slow")" incomplete 1

if [ "$fake" != none ]; then
	v4l2_rig() { # name fake-options
		cat >"$tmp/$1.json" <<JSON
{"camera": {"backend": "v4l2", "device": "/dev/video0"}, "output": "$tmp/$1"}
JSON
	}
	v4l2_rig ok
	check "v4l2 (fake): cameras describes it" env FAKE=1 FAKE_V4L2=noise=0 bash -c "$(declare -f run); tmp=$tmp glint=$glint fake=$fake run 0 '' cameras --device /dev/video0"
	check "... by name" grep -q "glint fake camera" "$tmp/out"
	export FAKE_V4L2="timescale=0.01"
	check "v4l2 (fake): capture completes" env FAKE=1 bash -c "$(declare -f run); tmp=$tmp glint=$glint fake=$fake run 0 'range covered' capture sample --config $tmp/ok.json"
	check "... session whole" python3 "$checker" "$(only_session "$tmp/ok")" complete 8
	# FAKE_V4L2 fault:stderr fragment:frames the session must keep (the
	# counts are dequeues; metering and drops use ~20 before frame 0)
	for fault in "enodev_after=30:disappeared:1" "eio_at=30:Input/output error:1" \
		"stall_after=30:no frame within:1" "refuse=exposure:exposure_time_absolute:0" \
		"short_from=30:short frame:1"; do
		name=${fault%%=*}
		keep=${fault##*:}
		fault=${fault%:*}
		v4l2_rig "$name"
		export FAKE_V4L2="timescale=0.01,${fault%%:*}"
		check "v4l2 (fake) $name: exit 1, clear error" env FAKE=1 bash -c "$(declare -f run); tmp=$tmp glint=$glint fake=$fake run 1 '${fault#*:}' capture sample --config $tmp/$name.json"
		check "... says the session is kept" grep -q "incomplete" "$tmp/err"
		check "... session incomplete, frames whole" python3 "$checker" "$(only_session "$tmp/$name")" incomplete "$keep"
	done
	unset FAKE_V4L2
fi

# A gray/chrome pair on the probe stand (reference): the chrome ball found
# inside roi.probe, the gray one inside reference.roi, the map calibrated
# by the gray ball (capture/probe/probe_calibrate.h).  The sim's chrome is
# the one glint assumes, so the map's scale is 1 within its sigma.
gray_rig() { # NAME REFERENCE_ROI
	cat >"$tmp/$1.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=320,height=240,scene=rig,gray=0.18,timescale=0.01"},
 "optics": {"focal_px": 640, "psf_sigma_px": 0.86, "olpf": true},
 "reference": {"albedo": 0.18, "albedo_sigma": 0.005, "roi": $2},
 "roi": {"probe": [0, 0, 163, 240]},
 "output": "$tmp/$1"}
JSON
}
gray_rig gray "[163, 0, 320, 240]"
check "probe with a gray ball beside it: calibrated" run 0 "gray ball at" capture probe --config "$tmp/gray.json"
check "... its session complete, env-calibration.json among its files" python3 "$checker" "$(only_session "$tmp/gray")" complete 8
check "... the map's scale 1 within 3 sigma, sigma under 5 %" python3 -c "
import json, sys
d = json.load(open('$(only_session "$tmp/gray")/env-calibration.json'))
ok = all(abs(s - 1) < 3 * e and e < 0.05 for s, e in zip(d['scale'], d['scale_sigma']))
print(d['scale'], d['scale_sigma']); sys.exit(not ok)"
# The sample's scene then states the calibrated map's uncertainty, which
# the fit carries into the albedos' intervals (here the gray ball stands
# in for the sample: the camera does not move without a board).
sed 's/"roi": {"probe": \[0, 0, 163, 240\]}/"roi": {"probe": [0, 0, 163, 240], "sample": [163, 0, 320, 240]}/' "$tmp/gray.json" >"$tmp/graysample.json"
check "a sample after the calibrated probe" run 0 "" capture sample --config "$tmp/graysample.json" -q
check "... its scene.json states the map's relative uncertainty, the calibration's" python3 -c "
import glob, json, sys
cal = json.load(open('$(only_session "$tmp/gray")/env-calibration.json'))
scene = [json.load(open(p)) for p in glob.glob('$tmp/gray/sample-*/scene.json')]
assert len(scene) == 1, scene
got = scene[0]['environment']['scale_sigma']
want = [e / s for s, e in zip(cal['scale'], cal['scale_sigma'])]
print(got, want)
sys.exit(not all(abs(a - b) < 1e-6 * b for a, b in zip(got, want)))"
check "... and names the mosaic it was demosaiced from (the sim's RGGB) and the optics' blur" python3 -c "
import glob, json, sys
cam = json.load(open(glob.glob('$tmp/gray/sample-*/scene.json')[0]))['camera']
print(cam)
sys.exit(not (cam.get('cfa') == 'RGGB' and cam.get('psf_sigma_px') == 0.86 and cam.get('olpf') is True))"
check "capture reference on the pair (the probe's capture calibrated it): exit 1, named" run 1 "the gray ball is in the probe's photo (reference.roi)" capture reference --config "$tmp/gray.json"
gray_rig nogray "[0, 0, 60, 60]"
check "a reference ROI with no ball in it: exit 1, named" run 1 "the gray ball" capture probe --config "$tmp/nogray.json"


# The gray ball at its own turntable position (reference_deg): the probe
# keeps the whole frame, the gray ball has its own bracket ("capture
# reference"), and the probe session's map is calibrated into the
# reference session, which then lights the sample.
cat >"$tmp/own.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=320,height=240,scene=rig,reference=0.18,timescale=0.01"},
 "optics": {"focal_px": 640, "psf_sigma_px": 0.86, "olpf": true},
 "sample": {"diameter_m": 0.1},
 "reference": {"albedo": 0.18, "albedo_sigma": 0.005},
 "board": {"backend": "sim", "scenario": "$data/sim-press.json",
  "lines": {"button": {"chip": "gpiochip0", "line": 17, "active_low": true},
   "lights": {"chip": "gpiochip0", "line": 22},
   "turntable_step": {"chip": "gpiochip0", "line": 23},
   "turntable_dir": {"chip": "gpiochip0", "line": 24}},
  "turntable": {"mode": "stepper", "steps_per_turn": 400, "step_hz": 20000,
   "probe_deg": 0, "sample_deg": 180, "reference_deg": 90, "settle_s": 0}},
 "output": "$tmp/own"}
JSON
check "a reference before any probe: exit 1, named" run 1 "a reference calibrates a probe (capture the probe first" capture reference --config "$tmp/own.json"
check "the probe at its position (the whole frame)" run 0 "probe ball at" capture probe --config "$tmp/own.json"
check "... no calibration in the probe session (the reference's own step does it)" test ! -e "$(only_session "$tmp/own")/env-calibration.json"
probe_dir=$(only_session "$tmp/own")
check "the gray ball at its own position: the probe's map calibrated" run 0 "gray ball at" capture reference --config "$tmp/own.json"
ref_dir=$(ls -d "$tmp"/own/reference-* 2>/dev/null | head -1)
check "... the reference session complete, env.exr and env-calibration.json in it" python3 -c "
import json, os, sys
d = json.load(open('$ref_dir/session.json'))
print(d['status'], d['kind'])
sys.exit(not (d['status'] == 'complete' and d['kind'] == 'reference' and
	all(os.path.getsize('$ref_dir/' + f) > 0 for f in ('env.exr', 'env-calibration.json', 'reference.exr'))))"
check "... the map's scale 1 within 3 sigma, sigma under 5 %" python3 -c "
import json, sys
d = json.load(open('$ref_dir/env-calibration.json'))
ok = all(abs(s - 1) < 3 * e and e < 0.05 for s, e in zip(d['scale'], d['scale_sigma']))
print(d['scale'], d['scale_sigma']); sys.exit(not ok)"
check "... the gray ball found at the probe's place, the size of the probe's ball" python3 -c "
import re, sys
m = re.search(r'gray ball at \(([-\d.]+), ([-\d.]+)\), radius ([\d.]+)', open('$tmp/err').read())
print('  ', m and m.groups())
sys.exit(not (m and abs(float(m[1]) - 160) < 1 and abs(float(m[2]) - 120) < 1 and abs(float(m[3]) - 96) < 2))"
check "a sample lit by the reference session" run 0 "" capture sample --config "$tmp/own.json" --probe "$ref_dir" -q
check "... its scene names the calibrated map and states its uncertainty" python3 -c "
import glob, json, sys
scene = [json.load(open(p)) for p in glob.glob('$tmp/own/sample-*/scene.json')]
assert len(scene) == 1, scene
env = scene[0]['environment']
print(env)
sys.exit(not (env['path'].startswith('../reference-') and len(env['scale_sigma']) == 3))"
sed 's/"mode": "stepper"/"mode": "relay"/; s/"output"/"sequence": ["capture probe", "turntable reference", "capture reference"], "output"/' "$tmp/own.json" >"$tmp/relay.json"
check "a reference position on a relay table: refused at load, named" run 1 "a relay turntable has two positions" capture probe --config "$tmp/relay.json"
sed 's/"reference": {"albedo": 0.18, "albedo_sigma": 0.005},//' "$tmp/own.json" >"$tmp/noref.json"
check "capture reference without a reference section: exit 1, named" run 1 "no \"reference\" section" capture reference --config "$tmp/noref.json"

echo "$((checks - fails)) passed, $fails failed"
[ "$fails" = 0 ]
