#!/bin/bash
# vivid, the kernel's virtual V4L2 capture driver, in the test VM: glint
# cameras lists it with its formats and controls, glint capture refuses it
# (no exposure control) naming what is missing, and test_vivid runs the
# backend's protocol and vivid's faults (test_vivid.c).
# usage: test_vivid.sh TEST_VIVID GLINT   (inside scripts/vm run)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
test_vivid=$1
glint=$2
need_vm
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# One capture node only (no output, VBI, radio, SDR or touch nodes).
check "vivid loads" modprobe vivid n_devs=1 node_types=0x1
check "... its capture node appears" wait_until 10 vivid_node
dev=$(vivid_node)

check "glint cameras --backend v4l2 lists it" \
	bash -c "'$glint' cameras --backend v4l2 --json >'$tmp/cams.json' 2>'$tmp/err'"
check "... with its formats and its gain control, and no manual exposure" python3 - "$tmp/cams.json" "$dev" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
cams = d["cameras"] if isinstance(d, dict) else d
cam = [c for c in cams if c.get("device") == sys.argv[2]]
assert cam, cams
c = cam[0]
print("  ", json.dumps(c)[:400])
s = json.dumps(c)
assert "vivid" in s, "not named vivid"
assert len(c["formats"]) > 4 and any("16" in f for f in c["formats"]), c["formats"]
assert c["manual_exposure"] is False, c
PY

# The rig file of a user with this camera: refused before any frame, with
# the reason.
python3 - "$tmp/rig.json" "$dev" "$tmp/out" <<'PY'
import json, sys
r = {"camera": {"backend": "v4l2", "device": sys.argv[2]},
     "optics": {"focal_px": 640}, "output": sys.argv[3]}
json.dump(r, open(sys.argv[1], "w"))
PY
"$glint" capture probe --config "$tmp/rig.json" >"$tmp/out.txt" 2>"$tmp/err"
st=$?
check "glint capture on vivid: refused (exit $st)" test "$st" != 0
check "... naming the missing exposure control" grep -q "no manual exposure" "$tmp/err"
sed 's/^/  /' "$tmp/err" | tail -3
check "... no session presented as whole" bash -c "! grep -rqs '\"status\": \"complete\"' '$tmp/out'"

check "the backend on vivid: bars, buffer errors, drops, disconnect" "$test_vivid" "$dev"
finish
