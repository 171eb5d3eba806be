#!/bin/bash
# The libcamera backend on the kernel's vimc driver, in the test VM:
# libcamera 0.0.3's vimc pipeline handler (with its IPA module, and udev to
# find the media device) gives glint one camera.  glint cameras lists it;
# the handler offers processed RGB streams only (no Raw role) and no
# ExposureTime/AnalogueGain controls, so a bracket is refused naming the
# missing control, and frames stream and decode (test_libcamera).
# usage: test_vimc.sh TEST_LIBCAMERA GLINT   (inside scripts/vm run)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
test_libcamera=$1
glint=$2
need_vm
tmp=$(mktemp -d)
udevd=""
trap '[ -z "$udevd" ] || kill $udevd 2>/dev/null; rm -rf "$tmp"' EXIT
export LIBCAMERA_LOG_LEVELS='*:ERROR'

check "vimc loads (built from linux-source by scripts/vm)" load_module vimc
check "... its media device appears" wait_until 10 exists "/dev/media*"
# libcamera enumerates media devices through udev.
/lib/systemd/systemd-udevd >/dev/null 2>&1 &
udevd=$!
check "udev has seen the media device" udev_ready $(ls /dev/media*)

check "glint cameras --backend libcamera lists vimc's camera" \
	bash -c "'$glint' cameras --backend libcamera --json >'$tmp/cams.json' 2>'$tmp/err'"
check "... with its processed formats and no exposure control" python3 - "$tmp/cams.json" <<'PY'
import json, sys
cams = json.load(open(sys.argv[1]))["cameras"]
print("  ", json.dumps(cams)[:300])
assert len(cams) == 1 and "vimc" in cams[0]["device"], cams
c = cams[0]
assert c["formats"] and c["manual_exposure"] is False, c
PY
check "the backend on vimc: refusal, frames stream and decode" "$test_libcamera"
finish
