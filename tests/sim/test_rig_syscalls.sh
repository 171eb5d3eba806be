#!/usr/bin/env bash
# The rig daemon's system-call filter (scripts/systemd/glint-rig.service.in)
# against what the daemon does: one press on the simulated rig (96 x 72,
# capture, merge, unwrap, the queued fit in its own process) under
# strace -f, and every call it made must pass the unit's SystemCallFilter=
# lines as systemd reads them (allow lines add, ~ lines remove, in order;
# groups expanded by systemd-analyze).  A call outside would fail with
# EPERM under systemd.  The test VM has no systemd to run the unit itself.
#   test_rig_syscalls.sh GLINT UNIT DATA_DIR
set -uo pipefail
glint=$1 unit=$2 data=$3
for t in strace systemd-analyze; do
	command -v $t >/dev/null || {
		echo "skip: $t is not installed (scripts/setup installs it)" >&2
		exit 77
	}
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$data/rig-sim.json" "$tmp" "$data" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
r["camera"]["device"] = r["camera"]["device"].replace("width=320,height=240", "width=96,height=72")
r["output"] = sys.argv[2] + "/captures"
r["board"]["scenario"] = sys.argv[3] + "/sim-press.json"
json.dump(r, open(sys.argv[2] + "/rig.json", "w"))
PY
(cd "$tmp" && strace -f -qq -o "$tmp/trace" "$glint" rig --config "$tmp/rig.json" --once -q >"$tmp/out" 2>&1) || {
	echo "FAIL the press under strace:"
	tail -5 "$tmp/out"
	exit 1
}
python3 - "$unit" "$tmp/trace" <<'PY'
import re, subprocess, sys
def expand(name, seen=None):
    seen = seen or set()
    if not name.startswith("@"):
        return {name}
    if name in seen:
        return set()
    seen.add(name)
    out = subprocess.run(["systemd-analyze", "syscall-filter", name],
                         capture_output=True, text=True, check=True).stdout
    calls = set()
    for line in out.splitlines()[1:]:
        w = line.strip()
        if w and not w.startswith("#"):
            calls |= expand(w.split()[0], seen)
    return calls
allowed = None
for line in open(sys.argv[1]):
    if not line.startswith("SystemCallFilter="):
        continue
    v = line.split("=", 1)[1].strip()
    deny = v.startswith("~")
    names = set()
    for w in v.lstrip("~").split():
        names |= expand(w)
    if allowed is None:
        allowed = set() if not deny else None
    if deny:
        allowed -= names
    else:
        allowed |= names
assert allowed, "no SystemCallFilter= allow list in the unit"
used = set()
for line in open(sys.argv[2]):
    m = re.match(r"\d+\s+([a-z0-9_]+)\(", line)
    if m:
        used.add(m.group(1))
bad = sorted(used - allowed)
print(f"{len(used)} distinct system calls in one press; {len(allowed)} allowed by the unit")
if bad:
    print("FAIL outside the unit's filter (EPERM under systemd):", " ".join(bad))
    sys.exit(1)
print("ok   every call the press made passes the unit's SystemCallFilter")
PY
