#!/usr/bin/env bash
# A fit's report.html in a headless browser (Debian's chromium; the
# renderers suite): it opens from the result folder without a server, its
# picture loads, its table holds every parameter with its interval; with
# compare.png gone the page says so where the picture was.
# usage: test_report.sh GLINT DATA_DIR
set -uo pipefail
glint=$1
data=$2
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
	echo "skip: chromium is not installed (scripts/setup-renderers installs it)"
	exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
check() {
	local what=$1
	shift
	if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fails=$((fails + 1)); fi
}
cat >"$tmp/scene.json" <<JSON
{"camera": {"width": 96, "height": 96, "focal_length_mm": 100,
            "sensor_width_mm": 36},
 "sphere": {"diameter_m": 0.1, "circle_px": {"cx": 48, "cy": 48, "r": 30}},
 "environment": {"path": "$data/env/venice_sunset_1k.hdr", "rotation_deg": [0, -114, 0]},
 "render": {"samples_per_pixel": 2, "light_samples": 16, "brdf_samples": 16}}
JSON
"$glint" render "$tmp/scene.json" --paper yellow-plastic -o "$tmp/photo.exr" -q
"$glint" fit "$tmp/scene.json" "$tmp/photo.exr" -o "$tmp/yellow" --name "yellow <plastic> & co" --export gltf -q >/dev/null
# The browser's own state stays in the test's folder.
page() { # FOLDER OUT: the page's DOM after load, and a screenshot
	timeout 120 "$browser" --headless --no-sandbox --disable-gpu \
		--user-data-dir="$tmp/profile" --hide-scrollbars --window-size=900,1300 \
		--dump-dom "file://$1/report.html" >"$2.html" 2>"$2.log" &&
		timeout 120 "$browser" --headless --no-sandbox --disable-gpu \
			--user-data-dir="$tmp/profile" --hide-scrollbars --window-size=900,1300 \
			--screenshot="$2.png" "file://$1/report.html" >>"$2.log" 2>&1
}
opened() { page "$1" "$2" && grep -q '<title>glint fit: ' "$2.html"; }
check "chromium opens report.html from the folder" opened "$tmp/yellow" "$tmp/a"
check "... its table: every parameter with an interval, the name escaped" python3 - "$tmp/a.html" "$tmp/yellow/params.json" <<'PY'
import json, re, sys
dom = open(sys.argv[1]).read()
d = json.load(open(sys.argv[2]))
names = [p["name"] for p in d["parameters"]]
rows = re.findall(r"<tr><td>([a-z.]+)</td><td>([0-9.]+)</td><td>[0-9.]+</td>"
                  r"<td>\[([0-9.]+), ([0-9.]+)\]</td>", dom)
assert [r[0] for r in rows] == names, (rows, names)
for r, p in zip(rows, d["parameters"]):
    assert abs(float(r[1]) - p["value"]) < 1e-4, (r, p["value"])
    assert abs(float(r[2]) - p["interval"][0]) < 1e-4, (r, p["interval"])
assert "<h1>yellow &lt;plastic&gt; &amp; co</h1>" in dom, "name not escaped"
assert "<b>Accepted</b>" in dom
assert 'href="material.gltf"' in dom
print(f"  {len(rows)} parameters, as params.json states them")
PY
check "... its picture loaded (the img kept, not replaced by a note)" bash -c "grep -q '<img src=\"compare.png\"' '$tmp/a.html' && ! grep -q '<figure>compare.png is missing' '$tmp/a.html'"
check "... a screenshot of it" bash -c "[ \$(stat -c %s '$tmp/a.png') -gt 20000 ]"
cp -r "$tmp/yellow" "$tmp/gone"
rm "$tmp/gone/compare.png"
said_missing() { opened "$1" "$2" && grep -q '<figure>compare.png is missing from this folder' "$2.html" && ! grep -q '<img src="compare.png"' "$2.html"; }
check "compare.png gone: the page says so where the picture was" said_missing "$tmp/gone" "$tmp/b"
[ "$fails" = 0 ]
