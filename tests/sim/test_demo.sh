#!/usr/bin/env bash
# The README's main job, `glint demo`, end to end with no arguments but an
# output folder: it renders, writes an EXR and a PNG, and reports in JSON.
set -u
glint=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
if ! "$glint" demo --json >out.json 2>err.txt; then
	echo "FAIL: glint demo exited $?"; cat err.txt; exit 1
fi
python3 - <<'PY' || exit 1
import json, struct, zlib
r = json.load(open("out.json"))
assert r["output"] == "demo-out/render.exr", r["output"]
assert r["material_name"] == "yellow-plastic"
assert abs(r["material"]["diffuse"][0] - 0.292) < 1e-12
png = open("demo-out/render.png", "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n"
w, h = struct.unpack(">II", png[16:24])
assert (w, h) == (512, 512), (w, h)
exr = open("demo-out/render.exr", "rb").read(4)
assert exr == b"\x76\x2f\x31\x01", exr
print("1 passed, 0 failed")
PY
