#!/bin/bash
# Renders, on the host, the simulated rig's views that a test in the VM
# will photograph, then runs the VM with them.  Under the VM's emulated CPU
# (TCG) the simulator's reference renderer runs some 30 times slower than
# here, and the views are what the sim camera spends most of a capture on;
# its cache (sim/camera_sim.c, keyed by the view, its size, the lamps, the
# material, the map, the table and glint's own file) is read the same way
# inside the VM, which sees the host's /tmp.  A view the VM asks for that is
# not here (other lamps, another material) is rendered there as before.
#   with_sim_views.sh GLINT DATA_DIR WxH[,WxH...] -- COMMAND...
set -eu
glint=$1 data=$2 sizes=$3
shift 3
[ "${1:-}" = -- ] && shift
cache=$(mktemp -d "${TMPDIR:-/tmp}/glint-vm-views.XXXXXX")
trap 'rm -rf "$cache"' EXIT
IFS=, read -ra list <<<"$sizes"
for size in "${list[@]}"; do
	w=${size%x*} h=${size#*x}
	# One probe capture renders both of the rig's views (probe and sample).
	python3 - "$data/rig-sim.json" "$cache/rig-$size.json" "$cache/out-$size" "$w" "$h" <<'PY'
import json, os, sys
src, dst, out, w, h = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
r["camera"]["device"] = "sim:width=%s,height=%s,scene=rig,timescale=0.01" % (w, h)
r["optics"]["focal_px"] = 2 * int(w)
r["board"]["scenario"] = os.path.join(os.path.dirname(os.path.abspath(src)), r["board"]["scenario"])
json.dump(r, open(dst, "w"))
PY
	GLINT_SIM_CACHE=$cache "$glint" capture probe --config "$cache/rig-$size.json" -q >/dev/null ||
		echo "with_sim_views: the ${size} views were not rendered here; the VM renders them" >&2
	rm -rf "$cache/out-$size" "$cache/rig-$size.json"
done
echo "with_sim_views: $(find "$cache" -name '*.exr' | wc -l) views rendered on the host"
GLINT_SIM_CACHE=$cache "$@"
