#!/usr/bin/env bash
# The demo, `glint demo`, end to end: the simulated rig
# photographs a Table-1 sphere, glint fits it, and the result files exist
# and hold the truth within the demo's tolerances.
set -u
glint=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
if ! "$glint" demo --json >out.json 2>err.txt; then
	echo "FAIL: glint demo exited with an error"; cat err.txt; exit 1
fi
python3 - <<'PY' || exit 1
import json, struct
r = json.load(open("out.json"))
assert r["material_name"] == "yellow-plastic", r["material_name"]
truth, fit = r["truth"], r["material"]
# Noise-free simulated photo at 256x256 (docs/tests.md: tolerances and why).
checks = []
for i in range(3):
    checks.append(("diffuse", i, abs(fit["diffuse"][i] - truth["diffuse"][i]), 0.01))
    checks.append(("specular", i, abs(fit["specular"][i] - truth["specular"][i]), 0.02))
checks.append(("roughness", -1, abs(fit["roughness"] / truth["roughness"] - 1), 0.10))
checks.append(("ior", -1, abs(fit["ior"] - truth["ior"]), 0.05))
bad = [c for c in checks if not c[2] <= c[3]]
for c in checks:
    print("%-9s %2d error %.4f tolerance %.3f %s" % (c[0], c[1], c[2], c[3], "ok" if c[2] <= c[3] else "FAIL"))
assert not bad, bad
for f in ("demo-out/photo.exr", "demo-out/fit/render.exr"):
    assert open(f, "rb").read(4) == b"\x76\x2f\x31\x01", f
p = json.load(open("demo-out/fit/params.json"))
# The fit covers the sphere's window of the 256x256 frame; render.exr
# keeps the frame as its display window, compare.png shows the window.
win = p["render"]["window"]
assert (win["frame_width"], win["frame_height"]) == (256, 256), win
assert win["width"] < 256 and win["x"] > 0, win
png = open("demo-out/fit/compare.png", "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n"
w, h = struct.unpack(">II", png[16:24])
assert w == 3 * win["width"] + 12 and h > win["height"], (w, h)
assert [q["name"] for q in p["parameters"]][6:] == ["roughness", "ior"]
assert p["method"]["name"] == "three-pass" and len(p["passes"]) >= 3
print("1 passed, 0 failed")
PY
