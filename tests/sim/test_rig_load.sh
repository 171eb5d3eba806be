#!/bin/bash
# The README's main job under load: glint rig --once on the shipped
# simulated rig with 6 CPU-bound processes beside it (on a 2-core machine,
# load 7 and more), from a cold view cache.  The bracket's caps count the
# camera's own time, so a busy host does not cut it short: the run must
# complete, with whole sessions and a fit.  The test stops only the
# processes it started.
# usage: test_rig_load.sh GLINT DATA_DIR
set -u
glint=$1
data=$2
tmp=$(mktemp -d)
burners=()
cleanup() {
	for p in "${burners[@]}"; do kill "$p" 2>/dev/null; done
	wait 2>/dev/null
	rm -rf "$tmp"
}
trap cleanup EXIT
export GLINT_SIM_CACHE="$tmp/cache" # cold: the views are rendered first
python3 - "$data/rig-sim.json" "$tmp/rig.json" "$tmp/out" "$data/sim-press.json" <<'PY'
import json, os, sys
src, dst, out, press = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
r["board"]["scenario"] = press
json.dump(r, open(dst, "w"))
PY
for _ in 1 2 3 4 5 6; do
	(while :; do :; done) &
	burners+=($!)
done
start=$(date +%s)
"$glint" rig --config "$tmp/rig.json" --once --json >"$tmp/res.json" 2>"$tmp/err"
st=$?
echo "rig --once beside 6 CPU-bound processes: exit $st in $(($(date +%s) - start)) s (load $(cut -d' ' -f1 /proc/loadavg))"
for p in "${burners[@]}"; do kill "$p" 2>/dev/null; done
burners=()
if [ "$st" != 0 ]; then
	tail -20 "$tmp/err"
	exit 1
fi
python3 - "$tmp/res.json" <<'PY'
import json, os, sys
d = json.load(open(sys.argv[1]))
for k in ("probe", "sample"):
    s = json.load(open(os.path.join(d[k], "session.json")))
    assert s["status"] == "complete", (k, s["status"], s.get("error"))
    b = s["bracket"]
    assert not b["truncated"], (k, b)
    print(f"  {k}: {b['frames']} frames, {b['seconds']:.1f} s of the camera's time, {b['wall_seconds']:.1f} s here")
p = {q["name"]: q["value"] for q in d["fit"]["parameters"]}
print("  fitted", {k: round(v, 3) for k, v in p.items()})
assert abs(p["diffuse.r"] - 0.292) < 0.03, p
PY
