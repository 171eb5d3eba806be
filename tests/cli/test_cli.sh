#!/usr/bin/env bash
# The glint command as a user meets it: help, exit codes, one clear message
# per bad input, and nothing half-written when it fails.
# usage: test_cli.sh GLINT DATA_DIR [PART]
# PART 1 (help, render, convert, bad inputs, the first fit and its
# exports, the richer models, failed fits and the overwrite rule) or 2
# (model choice, the ladder, samples, joint fits, acceptance, 8-bit
# inputs, output folders): two halves meson runs side by side; without
# PART, both.
set -u
glint=$1
data=$2
part=${3:-all}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0

check() { # description, command...
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

# run EXPECTED_STATUS FRAGMENT ARGS...: status and a stderr fragment
run() {
	local want=$1 frag=$2
	shift 2
	"$glint" "$@" >"$tmp/out" 2>"$tmp/err"
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
	return 0
}


in_part() { [ "$part" = all ] || [ "$part" = "$1" ]; }

if in_part 1; then
check "glint --help lists the commands" run 0 "" --help
check "help names render" grep -q "render" "$tmp/out"
for c in demo render convert; do
	check "glint $c --help" run 0 "" "$c" --help
	check "$c help shows usage" grep -q "usage: glint $c" "$tmp/out"
done
check "no command: usage, exit 2" run 2 "usage: glint" 
check "unknown command: exit 2" run 2 "unknown command 'frobnicate'" frobnicate
check "render without a scene: exit 2" run 2 "expected one SCENE.json" render --paper copper
check "render with a bad option value: exit 2" run 2 "--spp 'lots'" render x.json --paper copper --spp lots

fi
# A small valid scene next to a small env map.
"$glint" convert "$data/env/venice_sunset_1k.hdr" "$tmp/env.exr" -q 2>/dev/null ||
	"$glint" convert "$data/env/venice_sunset_1k.hdr" "$tmp/env.exr"
cat >"$tmp/scene.json" <<JSON
{"camera": {"width": 64, "height": 48, "focal_length_mm": 100,
            "sensor_width_mm": 36},
 "sphere": {"diameter_m": 0.1, "circle_px": {"cx": 32, "cy": 24, "r": 15}},
 "environment": {"path": "env.exr", "rotation_deg": [0, 90, 0]},
 "render": {"samples_per_pixel": 2, "light_samples": 8, "brdf_samples": 8}}
JSON
if in_part 1; then
check "render a Table-1 material" run 0 "" render "$tmp/scene.json" --paper copper -o "$tmp/r.exr" --png "$tmp/r.png" --json
check "render --json is JSON with the outputs" python3 -c "
import json,sys; r=json.load(open('$tmp/out'))
assert r['output'].endswith('r.exr') and r['width']==64 and r['material']['model']=='torrance-sparrow', r"
check "render wrote a PNG" python3 -c "
import sys; b=open('$tmp/r.png','rb').read(8); assert b==b'\x89PNG\r\n\x1a\n', b"
check "render output converts back" run 0 "" convert "$tmp/r.exr" "$tmp/r.pfm"
check "... to a float TIFF and back, exactly" bash -c "'$glint' convert '$tmp/r.exr' '$tmp/r.tif' -q && '$glint' convert '$tmp/r.tif' '$tmp/r2.pfm' -q && cmp -s '$tmp/r.pfm' '$tmp/r2.pfm'"
# Relighting without a scene file: --env with the scene's own map and
# rotation is the scene's render, bit for bit; another rotation, another
# map or a scale is not; a missing map names --env.
check "render --env (the scene's own map and rotation)" run 0 "" render "$tmp/scene.json" --paper copper -o "$tmp/e1.exr" --env "$tmp/env.exr" --env-rotation 0,90,0
check "... equals the scene's render" cmp -s "$tmp/r.exr" "$tmp/e1.exr"
check "render --env-rotation 0,0,0" run 0 "" render "$tmp/scene.json" --paper copper -o "$tmp/e2.exr" --env-rotation 0,0,0
check "... relights it" bash -c "! cmp -s '$tmp/r.exr' '$tmp/e2.exr'"
check "render --env with another map" run 0 "" render "$tmp/scene.json" --paper copper -o "$tmp/e4.exr" --env "$data/env/venice_sunset_1k.hdr" --json
check "... says which map in --json" python3 -c "
import json; r=json.load(open('$tmp/out')); assert r['environment'].endswith('venice_sunset_1k.hdr'), r"
check "... relights it" bash -c "! cmp -s '$tmp/r.exr' '$tmp/e4.exr'"
check "render --env-scale 2 doubles the light" bash -c "'$glint' render '$tmp/scene.json' --paper copper -o '$tmp/s1.pfm' --no-background -q && '$glint' render '$tmp/scene.json' --paper copper -o '$tmp/s2.pfm' --no-background --env-scale 2 -q && python3 -c \"
import struct
def rd(p):
    b = open(p, 'rb').read()
    parts = b.split(b'\\n', 3)
    return struct.unpack('<%df' % ((len(parts[3])) // 4), parts[3])
a, b = rd('$tmp/s1.pfm'), rd('$tmp/s2.pfm')
sa, sb = sum(a), sum(b)
assert sa > 0 and abs(sb / sa - 2) < 1e-4, (sa, sb)
\""
check "render --env of a missing map: exit 1 naming --env" run 1 "--env: $tmp/nope.hdr" render "$tmp/scene.json" --paper copper -o "$tmp/x.exr" --env "$tmp/nope.hdr"
check "render --env-rotation 0,90: exit 2" run 2 "expected X,Y,Z" render "$tmp/scene.json" --paper copper --env-rotation 0,90

# Bad inputs: exit 1, one message naming what was wrong, no output.
check "missing scene file" run 1 "nope.json" render "$tmp/nope.json" --paper copper -o "$tmp/x.exr"
sed 's/"focal_length_mm": 100/"focal_length_mm": -5/' "$tmp/scene.json" >"$tmp/bad.json"
check "out-of-range field" run 1 "camera.focal_length_mm = -5" render "$tmp/bad.json" --paper copper -o "$tmp/x.exr"
sed 's/"diameter_m": 0.1, //' "$tmp/scene.json" >"$tmp/bad2.json"
check "missing field" run 1 "sphere.diameter_m is missing" render "$tmp/bad2.json" --paper copper -o "$tmp/x.exr"
check "unknown material" run 1 "no material named 'vibranium': it holds satin-paint, " render "$tmp/scene.json" --paper vibranium -o "$tmp/x.exr"
check "a misspelt material: did you mean" run 1 "no material named 'coper' (did you mean 'copper'?)" render "$tmp/scene.json" --paper coper -o "$tmp/x.exr"
echo '{"model": "torrance-sparrow", "roughness": -1}' >"$tmp/m.json"
check "material out of range" run 1 "roughness = -1" render "$tmp/scene.json" --material "$tmp/m.json" -o "$tmp/x.exr"

# An env map with a NaN (a 2x1 PFM written by hand).
printf 'PF\n2 1\n-1.0\n' >"$tmp/nan.pfm"
printf '\x00\x00\x80\x3f\x00\x00\xc0\x7f\x00\x00\x80\x3f\x00\x00\x80\x3f\x00\x00\x80\x3f\x00\x00\x80\x3f' >>"$tmp/nan.pfm"
sed 's/env.exr/nan.pfm/' "$tmp/scene.json" >"$tmp/nan.json"
check "NaN in the env map" run 1 "nan.pfm: pixel (0, 0) channel G is nan" render "$tmp/nan.json" --paper copper -o "$tmp/x.exr"
check "NaN image refused by convert" run 1 "channel G is nan" convert "$tmp/nan.pfm" "$tmp/x.exr"

# Truncated and corrupt images.
head -c 20000 "$data/env/venice_sunset_1k.hdr" >"$tmp/trunc.hdr"
sed 's/env.exr/trunc.hdr/' "$tmp/scene.json" >"$tmp/trunc.json"
check "truncated HDR env map" run 1 "trunc.hdr: truncated in pixel row" render "$tmp/trunc.json" --paper copper -o "$tmp/x.exr"
head -c 5000 "$tmp/env.exr" >"$tmp/trunc.exr"
check "truncated EXR" run 1 "trunc.exr" convert "$tmp/trunc.exr" "$tmp/x.pfm"
echo "garbage" >"$tmp/garbage.exr"
check "not an EXR" run 1 "garbage.exr: not a readable OpenEXR file" convert "$tmp/garbage.exr" "$tmp/x.pfm"
check "unreadable path" run 1 "cannot open" convert "$tmp/no/such.hdr" "$tmp/x.pfm"
check "no output from any failure" test ! -e "$tmp/x.exr" -a ! -e "$tmp/x.pfm"
check "no temporary files left" bash -c "! ls '$tmp' | grep -q '\.tmp\.'"

# A failed write leaves the previous file intact.
cp "$tmp/r.exr" "$tmp/keep.exr"
check "write into a missing folder fails" run 1 "no/dir/out.exr" render "$tmp/scene.json" --paper copper -o "$tmp/no/dir/out.exr"
check "existing output untouched" cmp -s "$tmp/r.exr" "$tmp/keep.exr"

fi
# glint fit: a small photo of satin paint rendered by `glint render`.
cat >"$tmp/fscene.json" <<JSON
{"camera": {"width": 96, "height": 96, "focal_length_mm": 100,
            "sensor_width_mm": 36},
 "sphere": {"diameter_m": 0.1, "circle_px": {"cx": 48, "cy": 48, "r": 30}},
 "environment": {"path": "env.exr", "rotation_deg": [0, -114, 0]},
 "render": {"samples_per_pixel": 2, "light_samples": 16, "brdf_samples": 16}}
JSON
check "render a photo to fit" run 0 "" render "$tmp/fscene.json" --paper satin-paint -o "$tmp/photo.exr" -q
if in_part 1; then
check "fit it, exporting to every renderer" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fit1" --export gltf,mitsuba,pbrt,blender,materialx --json -q
check "a sphere 30 px in radius: its intervals' terms are said to be extrapolated" grep -q "measured down to 38 px and are extrapolated" "$tmp/err"
check "fit --json has values, errors, passes" python3 -c "
import json; r=json.load(open('$tmp/out'))
names=[p['name'] for p in r['parameters']]
assert names==['diffuse.r','diffuse.g','diffuse.b','specular.r','specular.g','specular.b','roughness','ior'], names
assert r['method']['name']=='three-pass' and len(r['passes'])>=3, r['passes']
assert abs(r['material']['diffuse'][0]-0.124)<0.02, r['material']
assert all('stderr' in p for p in r['parameters'])"
check "fit wrote params.json, render.exr, compare.png, report.html" test -s "$tmp/fit1/params.json" -a -s "$tmp/fit1/render.exr" -a -s "$tmp/fit1/compare.png" -a -s "$tmp/fit1/report.html"
check "... and the exports, listed with their residuals" python3 -c "
import json, os; r=json.load(open('$tmp/fit1/params.json'))
e={x['format']: x for x in r['exports']}
assert sorted(e)==['blender','gltf','materialx','mitsuba','pbrt'], e
assert r['inputs']['sphere_diameter_m'] > 0, r['inputs']
for f, x in e.items():
    assert 0 <= x['refit_relative_rms'] < 0.3, x
    assert os.path.getsize('$tmp/fit1/' + x['file']) > 0, x"
for f in gltf xml pbrt py mtlx; do
	check "... material.$f matches glint's BRDF within its stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/fit1/material.$f"
done
# A photo or weights with NaN, infinity or (weights) a negative value is a
# broken file, named with its first bad pixel in the file's coordinates.
"$glint" convert "$tmp/photo.exr" "$tmp/photo.pfm" -q
python3 - "$tmp" <<'PY2'
import struct, sys
t = sys.argv[1]
d = open(t + "/photo.pfm", "rb").read()
head = d[:d.index(b"\n", d.index(b"\n", 3) + 1) + 1]
px = bytearray(d[len(head):])
# PFM rows run bottom-up: row 48 from the top, column 40, channel G
off = ((95 - 48) * 96 + 40) * 12 + 4
px[off:off + 4] = struct.pack("<f", float("inf"))
open(t + "/inf.pfm", "wb").write(head + bytes(px))
w = bytearray(struct.pack("<f", 1.0) * (96 * 96 * 3))
off = ((95 - 50) * 96 + 41) * 12
w[off:off + 4] = struct.pack("<f", -0.5)
open(t + "/negw.pfm", "wb").write(head + bytes(w))
PY2
"$glint" convert "$tmp/inf.pfm" "$tmp/inf.exr" --allow-nonfinite -q
"$glint" convert "$tmp/negw.pfm" "$tmp/negw.exr" -q
check "fit refuses a photo with infinity, naming the pixel" run 1 "inf.exr: pixel (40, 48) channel G is inf" fit "$tmp/fscene.json" "$tmp/inf.exr" -o "$tmp/fitinf"
check "fit refuses negative weights, naming the pixel" run 1 "negw.exr: pixel (41, 50) channel R is -0.5: expected a finite, non-negative" fit "$tmp/fscene.json" "$tmp/photo.exr" --weights "$tmp/negw.exr" -o "$tmp/fitneg"
check "... and writes no result" test ! -e "$tmp/fitinf" -a ! -e "$tmp/fitneg"
check "fit --export of an unknown format: exit 2, nothing done" run 2 "did you mean 'mitsuba'" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitx" --export gltf,mitsuba3
check "... no folder" test ! -e "$tmp/fitx"
check "render the fitted material from params.json" run 0 "" render "$tmp/fscene.json" --material "$tmp/fit1/params.json" -o "$tmp/refit.exr" -q
check "... wrote it" test -s "$tmp/refit.exr"
cp -r "$tmp/fit1" "$tmp/fit1.keep"
# The naive method (every parameter at once, one pass) on a subsample:
# its code under the sanitizers (naive-vs-three-pass compares the two).
check "fit --method naive" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" --method naive --max-pixels 600 -o "$tmp/naive" --json -q
check "... one pass, named naive" python3 -c "
import json; r = json.load(open('$tmp/out'))
assert r['method']['name'] == 'naive', r['method']"
# Export: glTF refitted to the fitted BRDF, checked by an independent
# evaluation of both models from their published equations.
check "export the fit to glTF" run 0 "relative RMS difference" export "$tmp/fit1/params.json" --to gltf -o "$tmp/m.gltf"
check "... the glTF BRDF matches glint's within the stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/m.gltf"
diam=$(python3 -c "import json; print(json.load(open('$tmp/fit1/params.json'))['inputs']['sphere_diameter_m'])")
check "... a closed sphere of the fit's diameter carrying the material, named after the fit's folder" python3 "$here/check_gltf_mesh.py" "$tmp/m.gltf" fit1 "$diam"
check "... the fit's own export the same, its params.json naming the material" python3 -c "
import json, subprocess, sys
assert json.load(open('$tmp/fit1/params.json'))['material']['name'] == 'fit1'
subprocess.run([sys.executable, '$here/check_gltf_mesh.py', '$tmp/fit1/material.gltf', 'fit1', '$diam'], check=True)"
# A session's fit (SESSION/fit/params.json) without a name of its own is
# named after the session; --name names it.
mkdir -p "$tmp/lab-teflon/fit"
python3 -c "
import json; d = json.load(open('$tmp/fit1/params.json')); del d['material']['name']
json.dump(d, open('$tmp/lab-teflon/fit/params.json', 'w'))"
check "export of a session's fit names the material after the session" run 0 "" export "$tmp/lab-teflon/fit/params.json" --to gltf -o "$tmp/session.gltf" -q
check "... 'lab-teflon'" python3 "$here/check_gltf_mesh.py" "$tmp/session.gltf" lab-teflon "$diam"
check "export --name names it (as an identifier)" run 0 "" export "$tmp/lab-teflon/fit/params.json" --to gltf -o "$tmp/named.gltf" --name "Teflon sheet/2" -q
check "... 'Teflon_sheet_2'" python3 "$here/check_gltf_mesh.py" "$tmp/named.gltf" Teflon_sheet_2 "$diam"
check "export the fit to Mitsuba 3" run 0 "mitsuba" export "$tmp/fit1/params.json" --to mitsuba -o "$tmp/m.xml"
check "... Mitsuba's BRDF matches glint's within the stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/m.xml"
check "export the fit to pbrt-v4" run 0 "pbrt" export "$tmp/fit1/params.json" --to pbrt -o "$tmp/m.pbrt"
check "... pbrt's BRDF matches glint's within the stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/m.pbrt"
check "export the fit to Blender" run 0 "blender" export "$tmp/fit1/params.json" --to blender -o "$tmp/m.py"
check "... the node material's BRDF matches glint's within the stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/m.py"
check "... the script is valid Python" python3 -m py_compile "$tmp/m.py"
check "export refuses to replace a file" run 1 "exists: refusing to replace it" export "$tmp/fit1/params.json" --to gltf -o "$tmp/m.gltf"
check "export --force replaces it" run 0 "" export "$tmp/fit1/params.json" --to gltf -o "$tmp/m.gltf" --force --json
check "export --json states the residual" python3 -c "
import json; r=json.load(open('$tmp/out')); assert r['format']=='gltf' and 0<=r['refit_relative_rms']<0.3, r"
check "export without --to: exit 2" run 2 "--to FORMAT is required" export "$tmp/fit1/params.json" -o "$tmp/x.gltf"
check "export --to an unknown format: exit 2" run 2 "gltf" export "$tmp/fit1/params.json" --to usd -o "$tmp/x.gltf"
check "export the fit to MaterialX" run 0 "materialx" export "$tmp/fit1/params.json" --to materialx -o "$tmp/m.mtlx"
check "... standard_surface's BRDF matches glint's within the stated residual" python3 "$here/check_export.py" "$tmp/fit1/params.json" "$tmp/m.mtlx"
# A quartz sphere carries across: absorption per metre from the
# transmission per diameter, checked per format from the file's numbers.
check "export of a transparent sphere needs its diameter" run 1 "needs the sphere's diameter" export "$data/paper-table1.json" --entry blue-quartz --to gltf -o "$tmp/x.gltf"
check "... writing nothing" test ! -e "$tmp/x.gltf"
python3 - "$data/paper-table1.json" "$tmp/quartz.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
m = [x for x in d["materials"] if x["name"] == "blue-quartz"][0]
json.dump({"model": m["model"], "material": m, "parameters": [],
           "inputs": {"sphere_diameter_m": 0.06}}, open(sys.argv[2], "w"))
PY
for f in gltf:gltf mitsuba:xml pbrt:pbrt blender:py materialx:mtlx; do
	check "export quartz to ${f%%:*} (the diameter from params.json)" run 0 "" export "$tmp/quartz.json" --to "${f%%:*}" -o "$tmp/q.${f#*:}" -q
	check "... its interior and interface are the material's" python3 "$here/check_export.py" "$tmp/quartz.json" "$tmp/q.${f#*:}"
done
check "export --diameter-m overrides the record" run 0 "" export "$tmp/quartz.json" --to gltf -o "$tmp/q2.gltf" --diameter-m 0.05 -q
check "... and is what the file holds" python3 "$here/check_export.py" "$tmp/quartz.json" "$tmp/q2.gltf" 0.05
check "export --diameter-m 0: exit 2" run 2 "diameter-m" export "$tmp/quartz.json" --to gltf -o "$tmp/q3.gltf" --diameter-m 0
# The richer models: a material file of each renders; one is fitted.
cat >"$tmp/on.json" <<JSON
{"model": "oren-nayar", "diffuse": [0.3, 0.3, 0.3], "specular": [0.2, 0.2, 0.2],
 "roughness": 0.2, "ior": 1.5, "diffuse_roughness": 0.6}
JSON
echo '{"model": "ggx", "diffuse": [0.3, 0.2, 0.1], "roughness": 0.1}' >"$tmp/ggx.json"
echo '{"model": "two-lobe", "specular2": [0.1, 0.1, 0.1], "roughness2": 0.4}' >"$tmp/two.json"
check "render a ggx material" run 0 "" render "$tmp/fscene.json" --material "$tmp/ggx.json" -o "$tmp/ggx.exr" -q
check "render a two-lobe material" run 0 "" render "$tmp/fscene.json" --material "$tmp/two.json" -o "$tmp/two.exr" -q
check "render an oren-nayar material" run 0 "" render "$tmp/fscene.json" --material "$tmp/on.json" -o "$tmp/on.exr" -q
check "fit --model oren-nayar" run 0 "" fit "$tmp/fscene.json" "$tmp/on.exr" -o "$tmp/fiton" --model oren-nayar --json -q
check "... its parameters and conventions in params.json" python3 -c "
import json; r=json.load(open('$tmp/out'))
assert r['model']=='oren-nayar' and 'Oren-Nayar' in r['conventions'], r['model']
names=[p['name'] for p in r['parameters']]
assert names[-1]=='diffuse_roughness' and len(names)==9, names
assert abs(r['material']['diffuse'][0]-0.3)<0.03, r['material']
assert abs(r['material']['diffuse_roughness']-0.6)<0.15, r['material']"
echo '{"model": "ggx", "roughness2": 0.3}' >"$tmp/ggx-bad.json"
check "a material key of another model is refused" run 1 "roughness2" render "$tmp/fscene.json" --material "$tmp/ggx-bad.json" -o "$tmp/x.exr"
python3 - "$tmp" <<'PY'
import struct, sys
d = sys.argv[1]
def pfm(name, vals):
    with open(d + "/" + name, "wb") as f:
        f.write(b"PF\n96 96\n-1.0\n")
        f.write(struct.pack("<%df" % len(vals), *vals))
pfm("black.pfm", [0.0] * (96 * 96 * 3))
pfm("zeros_w.pfm", [0.0] * (96 * 96 * 3))
PY
check "fit: an all-black photo" run 1 "black where the scene puts the sphere" fit "$tmp/fscene.json" "$tmp/black.pfm" -o "$tmp/fit1" --force
check "fit: every pixel saturated (zero weight)" run 1 "no usable pixel on the sphere" fit "$tmp/fscene.json" "$tmp/photo.exr" --weights "$tmp/zeros_w.pfm" -o "$tmp/fit1" --force
sed 's/env.exr/nan.pfm/' "$tmp/fscene.json" >"$tmp/fnan.json"
check "fit: NaN in the env map" run 1 "nan.pfm: pixel (0, 0) channel G is nan" fit "$tmp/fnan.json" "$tmp/photo.exr" -o "$tmp/fit1" --force
check "fit: bad method" run 2 "--method 'best': expected one of three-pass, naive, varpro" fit "$tmp/fscene.json" "$tmp/photo.exr" --method best
check "failed fits left the old results whole" diff -r "$tmp/fit1" "$tmp/fit1.keep"
check "no half-written result folders" bash -c "! ls '$tmp' | grep -q 'fit1.tmp'"

# One overwrite rule for every output (core/output.h): an existing output
# is refused unless --force, and --force replaces only what glint wrote,
# never an input.
mkdir -p "$tmp/ow"
cp "$tmp/r.exr" "$tmp/ow/in.exr"
check "convert to a new file" run 0 "" convert "$tmp/ow/in.exr" "$tmp/ow/out.exr" -q
check "convert onto it again: refused" run 1 "out.exr exists: refusing to replace it (--force" convert "$tmp/ow/in.exr" "$tmp/ow/out.exr"
check "... --force replaces glint's own EXR" run 0 "" convert "$tmp/ow/in.exr" "$tmp/ow/out.exr" --force -q
for ext in exr png hdr tif json gltf; do
	echo "a user's notes" >"$tmp/ow/user.$ext"
done
check "convert --force onto a user's .exr: refused, naming why" run 1 "user.exr: no record of glint as its writer, so not known to be glint's output" convert "$tmp/ow/in.exr" "$tmp/ow/user.exr" --force
check "convert --force onto its own input: refused" run 1 "is an input of this command" convert "$tmp/ow/in.exr" "$tmp/ow/in.exr" --force
"$glint" convert "$tmp/ow/in.exr" "$tmp/ow/o.pfm" -q
check "convert --force onto a PFM: refused (a PFM cannot say who wrote it)" run 1 "a PFM holds no record of its writer" convert "$tmp/ow/in.exr" "$tmp/ow/o.pfm" --force
python3 -c "
open('$tmp/ow/cam.png', 'wb').write(open('$tmp/r.png', 'rb').read().replace(b'Software', b'Softwarf'))"
check "render --png --force onto another program's PNG: refused" run 1 "cam.png: a PNG without glint as its" render "$tmp/scene.json" --paper copper -o "$tmp/ow/r2.exr" --png "$tmp/ow/cam.png" --force
check "... and nothing written (checked before any work)" test ! -e "$tmp/ow/r2.exr"
check "render onto glint's own PNG and EXR: refused without --force" run 1 "exists: refusing" render "$tmp/scene.json" --paper copper -o "$tmp/ow/out.exr" --png "$tmp/r.png"
check "... replaced with it" run 0 "" render "$tmp/scene.json" --paper copper -o "$tmp/ow/out.exr" --png "$tmp/r.png" --force -q
ln -s "$tmp/ow/out.exr" "$tmp/ow/link.exr"
check "--force onto a symbolic link: refused" run 1 "link.exr is a symbolic link" convert "$tmp/ow/in.exr" "$tmp/ow/link.exr" --force
check "export --force onto a user's .gltf: refused" run 1 "user.gltf: no record of glint as its writer" export "$tmp/fit1/params.json" --to gltf -o "$tmp/ow/user.gltf" --force
check "... export --force onto glint's own: replaced" run 0 "" export "$tmp/fit1/params.json" --to gltf -o "$tmp/m.gltf" --force -q
check "convert to .hdr and a TIFF, then --force onto each: glint's, replaced" bash -c "'$glint' convert '$tmp/ow/in.exr' '$tmp/ow/o.hdr' -q && '$glint' convert '$tmp/ow/in.exr' '$tmp/ow/o.tif' -q && '$glint' convert '$tmp/ow/in.exr' '$tmp/ow/o.hdr' --force -q && '$glint' convert '$tmp/ow/in.exr' '$tmp/ow/o.tif' --force -q"
check "... a user's .hdr and .tif are not" bash -c "! '$glint' convert '$tmp/ow/in.exr' '$tmp/ow/user.hdr' --force -q 2>/dev/null && ! '$glint' convert '$tmp/ow/in.exr' '$tmp/ow/user.tif' --force -q 2>/dev/null"
check "every user's file as it was" bash -c "for e in exr png hdr tif json gltf; do [ \"\$(cat '$tmp/ow/user.'\$e)\" = \"a user's notes\" ] || exit 1; done"
check "fit into a previous result: refused" run 1 "holds a previous result: refusing to replace it" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/naive" --method naive --max-pixels 600
check "... --force replaces it" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/naive" --method naive --max-pixels 600 --force -q
fi
if in_part 2; then
# Inputs are regular files: a pipe (here a process substitution) is
# refused by name, as a FIFO planted where a file belongs would be.
check "a pipe as an input is refused, named" run 1 "a FIFO, not a regular file" render "$tmp/fscene.json" --material <(echo '{"model": "ggx", "roughness": 0.3}') -o "$tmp/x.exr"
# --model auto (its choice between the opaque and the transparent
# model, under the sanitizers here; model-auto tests what it picks).
check "fit --model auto on an opaque photo: Torrance-Sparrow chosen" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitauto" --model auto --max-pixels 600 --json -q
check "... and said why" python3 -c "
import json; d = json.load(open('$tmp/out'))['model_choice']
assert d['chosen'] == 'torrance-sparrow', d"
check "fit --select-model" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitsel" --select-model --json -q
check "--select-model reports every candidate with AIC, BIC, errors" python3 -c "
import json; r=json.load(open('$tmp/out'))['model_selection']
names=[c['name'] for c in r['candidates']]
assert len(names)==7 and r['chosen'] in names and 'BIC' in r['why'], r
assert [c['model'] for c in r['candidates']][4:]==['ggx','oren-nayar','two-lobe'], r
for c in r['candidates']:
    assert c['bic']==c['bic'] and c['aic']==c['aic'] and c['k'] in (3,6,7,8,9,12), c
    assert all('stderr' in v for v in c['parameters'].values()), c"
check "fit --ladder-knobs env,samples" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitlad" --ladder-knobs env,samples --json -q
check "--ladder reports each knob's levels, choice and why" python3 -c "
import json; r=json.load(open('$tmp/out'))['fidelity']
names=[k['name'] for k in r['knobs']]
assert names==['depth of field','samples per pixel','image resolution','env-map resolution','shading samples'], names
assert r['final']['effect_se'] < 1 and r['threshold_se']==0.5, r['final']
for k in r['knobs']:
    assert k['why'] and k['chosen'] in [l['value'] for l in k['levels']], k
assert [d['name'] for d in r['decided']]==['bounce depth','stand'], r['decided']"
# A light whose scale is known to 5 % (environment.scale_sigma, as a
# probe calibrated by a gray ball states it): a photo under a light 5 %
# brighter than the map says is fitted with every albedo 5 % high; the
# intervals with the light's term cover the material, without it red's
# does not, and roughness and ior do not move with the light's scale.
python3 - "$tmp" <<'PY'
import json, sys
d = sys.argv[1]
s = json.load(open(d + "/fscene.json"))
s["environment"]["scale"] = 1.05
json.dump(s, open(d + "/bright.json", "w"))
s["environment"]["scale"] = 1
s["environment"]["scale_sigma"] = 0.05
json.dump(s, open(d + "/lsigma.json", "w"))
s["environment"]["scale_sigma"] = [0.05, 2, 0.05]
json.dump(s, open(d + "/lbad.json", "w"))
PY
check "render a photo under a light 5 % brighter" run 0 "" render "$tmp/bright.json" --paper satin-paint -o "$tmp/bright.exr" -q
check "fit it with the light taken as exact" run 0 "" fit "$tmp/fscene.json" "$tmp/bright.exr" -o "$tmp/fitbright" --json -q
check "fit it with the light's scale known to 5 %" run 0 "" fit "$tmp/lsigma.json" "$tmp/bright.exr" -o "$tmp/fitlsig"
check "... its intervals say they hold the light's scale" grep -qF "the light's scale (5.0 / 5.0 / 5.0 %" "$tmp/out"
check "... the diffuse albedos 5 % high; the light's term covers them, only it" python3 -c "
import json
truth = [0.124, 0.026]
a = {p['name']: p for p in json.load(open('$tmp/fitbright/params.json'))['parameters']}
r = json.load(open('$tmp/fitlsig/params.json'))
b = {p['name']: p for p in r['parameters']}
u = r['uncertainty']
assert u['light_scale_sigma'] == [0.05, 0.05, 0.05], u['light_scale_sigma']
names = [p['name'] for p in r['parameters']]
for c, t in zip(['diffuse.r', 'diffuse.g'], truth):
    lo, hi = a[c]['interval']
    assert abs(a[c]['value'] / t - 1.05) < 0.03, (c, a[c])
    assert c != 'diffuse.r' or not lo <= t <= hi, (c, a[c])
    lo, hi = b[c]['interval']
    assert lo <= t <= hi, (c, b[c])
    ls = u['light_stderr'][names.index(c)]
    assert abs(ls - 0.05 * b[c]['value']) < 1e-9, (c, ls)
for c in ['roughness', 'ior']:
    assert u['light_stderr'][names.index(c)] == 0, c
    assert abs(a[c]['value'] - b[c]['value']) < 0.2 * b[c]['stderr'] + 1e-9, (c, a[c], b[c])
print('  diffuse.r', a['diffuse.r']['interval'], 'with the light', b['diffuse.r']['interval'])"
check "environment.scale_sigma above 1: refused, named" run 1 "environment.scale_sigma" fit "$tmp/lbad.json" "$tmp/bright.exr" -o "$tmp/fitlbad"
# At 1 + 1 samples the fit's own noise limits this photo: it raises them
# (to 4 + 4 here) unless --max-samples holds it lower.
check "fit --samples 1 raises its samples" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitraise" --samples 1 -q
check "--samples 1: params.json states more than 2 + 2" python3 -c "
import json; m=json.load(open('$tmp/fitraise/params.json'))['method']
assert m['light_samples']>2 and m['lobe_samples']>2, m"
check "fit --max-samples caps the samples it raises" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fitcap" --samples 1 --max-samples 2 -q
check "--max-samples 2: params.json states 2 + 2 samples" python3 -c "
import json; m=json.load(open('$tmp/fitcap/params.json'))['method']
assert m['light_samples']==2 and m['lobe_samples']==2, m"
check "--max-samples out of range" run 2 "--max-samples '0'" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/x" --max-samples 0
check "--render-seconds out of range" run 2 "--render-seconds '0'" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/x" --render-seconds 0
check "--ladder-limit out of range" run 2 "--ladder-limit" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/x" --ladder-limit 0
check "--ladder-knobs unknown" run 2 "expected knobs among dof" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/x" --ladder-knobs env,focus

cat >"$tmp/wide.json" <<JSON
{"camera": {"width": 100, "height": 96, "focal_length_mm": 100,
            "sensor_width_mm": 36},
 "sphere": {"diameter_m": 0.1, "circle_px": {"cx": 48, "cy": 48, "r": 30}},
 "environment": {"path": "env.exr"}}
JSON
check "fit: photo and scene sizes differ" run 1 "photo is 96x96: expected the scene camera's 100x96" fit "$tmp/wide.json" "$tmp/photo.exr" -o "$tmp/fit1" --force
sed 's/"cx": 48, "cy": 48, "r": 30/"cx": 14, "cy": 14, "r": 10/' "$tmp/fscene.json" >"$tmp/elsewhere.json"
check "fit: no sphere where the scene says" run 1 "the photo shows the backdrop, not a sphere" fit "$tmp/elsewhere.json" "$tmp/photo.exr" -o "$tmp/fit1" --force
check "a refused fit's diagnostics go beside the output" python3 -c "
import json; r=json.load(open('$tmp/fit1.refused/params.json'))
assert r['accepted'] is False and 'backdrop' in r['acceptance']['verdict'], r['acceptance']
assert r['acceptance']['backdrop_relative_rmse'] < r['acceptance']['relative_rmse'], r['acceptance']"
# A joint fit: the same sphere under the map turned 180 degrees, fitted
# with the first photo at once.
sed 's/"rotation_deg": \[0, -114, 0\]/"rotation_deg": [0, 66, 0]/' "$tmp/fscene.json" >"$tmp/fscene2.json"
check "render a second photo, the light turned" run 0 "" render "$tmp/fscene2.json" --paper satin-paint -o "$tmp/photo2.exr" -q
check "fit two photos jointly" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" -o "$tmp/joint" --json -q
check "... one material, each photo's fit in params.json, render-2.exr, compare-2.png" python3 -c "
import json, os; r=json.load(open('$tmp/joint/params.json'))
ph=r['photos']
assert [p['photo'] for p in ph]==['$tmp/photo.exr', '$tmp/photo2.exr'], ph
assert [p['render'] for p in ph]==['render.exr', 'render-2.exr'], ph
assert all(p['acceptance']['accepted'] and p['pixels'] > 100 for p in ph), ph
assert r['pixels']==sum(p['pixels'] for p in ph), r['pixels']
assert abs(r['material']['diffuse'][0]-0.124)<0.02, r['material']
for f in ['render-2.exr', 'compare-2.png', 'render.exr', 'compare.png']:
    assert os.path.getsize('$tmp/joint/' + f) > 0, f"
check "a joint fit's folder is replaced by the next" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" -o "$tmp/joint" --force -q --max-pixels 256 --sample-sets 1
check "--select-model on a joint fit" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" -o "$tmp/jointsel" --select-model --max-pixels 256 --sample-sets 1 --json -q
check "... every candidate fitted to both photos, the chosen one's result per photo" python3 -c "
import json; r=json.load(open('$tmp/jointsel/params.json'))
sel=r['model_selection']
assert len(sel['candidates'])==7 and 'BIC' in sel['why'], sel
ph=r['photos']
assert len(ph)==2 and all(p['acceptance']['accepted'] for p in ph), ph
assert r['pixels']==sum(p['pixels'] for p in ph), r['pixels']
print('  chosen', sel['chosen'], r['model'])"
check "fit: --ladder refused for a joint fit" run 1 "the fidelity ladder works on one photo" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" --ladder -o "$tmp/jx"
check "fit: an odd number of scene and photo arguments" run 2 "several such pairs" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json"
check "fit: --weights once for two photos" run 2 "--weights given 1 times for 2 photos" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" --weights "$tmp/w.exr" -o "$tmp/jx"
check "fit: --model auto refused for a joint fit" run 1 "name the model for a joint fit" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/fscene2.json" "$tmp/photo2.exr" --model auto -o "$tmp/jx"
check "fit: a joint fit with a photo that does not show its scene's sphere is refused, naming it" run 1 "photo.exr (photo 2 of 2): fit refused: the photo shows the backdrop" fit "$tmp/fscene.json" "$tmp/photo.exr" "$tmp/elsewhere.json" "$tmp/photo.exr" -o "$tmp/jx"
check "... its evidence beside the output, per photo" python3 -c "
import json; r=json.load(open('$tmp/jx.refused/params.json'))
assert r['accepted'] is False, r['accepted']
assert [p['acceptance']['accepted'] for p in r['photos']]==[True, False], r['photos']"
check "--accept-rmse replaces the rule" run 1 "relative RMSE 0.1" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fit1" --force --accept-rmse 0.001
check "--accept-rmse must be a positive number" run 2 "--accept-rmse 'no'" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/fit1" --accept-rmse no
python3 -c "
import random, struct
random.seed(1)
with open('$tmp/other.pfm', 'wb') as f:
    f.write(b'PF\\n96 96\\n-1.0\\n')
    f.write(struct.pack('<%df' % (96 * 96 * 3), *[random.random() for _ in range(96 * 96 * 3)]))"
check "a photo of something else is refused" run 1 "does not show this scene's sphere" fit "$tmp/fscene.json" "$tmp/other.pfm" -o "$tmp/fit1" --force
# One radiance policy: every command that takes light or a photo to fit
# refuses an 8-bit image with the same message, unless --srgb.
"$glint" convert "$tmp/photo.exr" "$tmp/photo8.png" -q
"$glint" convert "$tmp/env.exr" "$tmp/env8.png" -q
msg="an 8-bit image holds camera-encoded values, not radiance"
check "fit of an 8-bit photo: refused as radiance" run 1 "photo8.png: $msg" fit "$tmp/fscene.json" "$tmp/photo8.png" -o "$tmp/fit8"
check "... nothing written" test ! -e "$tmp/fit8"
check "fit --srgb: the photo linearised, a result" run 0 "8-bit, taken as sRGB-encoded" fit "$tmp/fscene.json" "$tmp/photo8.png" -o "$tmp/fit8" --srgb
check "render --env of an 8-bit map: refused" run 1 "env8.png: $msg" render "$tmp/fscene.json" --paper copper --env "$tmp/env8.png" -o "$tmp/r8.exr"
check "render --env MAP --srgb: done" run 0 "" render "$tmp/fscene.json" --paper copper --env "$tmp/env8.png" --srgb -o "$tmp/r8.exr" -q
check "convert 8-bit to a float format: refused" run 1 "photo8.png: $msg" convert "$tmp/photo8.png" "$tmp/x8.exr"
check "... with --srgb: done" run 0 "" convert "$tmp/photo8.png" "$tmp/x8.exr" --srgb -q
check "... 8-bit to 8-bit: copied" run 0 "" convert "$tmp/photo8.png" "$tmp/x8.png" -q
check "probe convert of an 8-bit map: refused" run 1 "env8.png: $msg" probe convert "$tmp/env8.png" "$tmp/a8.exr" --from latlong --to angular
check "probe register of an 8-bit map: refused" run 1 "env8.png: $msg" probe register "$tmp/env8.png" "$tmp/env.exr" -o "$tmp/b8.exr"
# An output folder holding a user's files is refused before any work.
mkdir -p "$tmp/mine" "$tmp/here"
echo "my notes" >"$tmp/mine/notes.txt"
check "-o DIR holding a user's file is refused" run 1 "holds files glint did not write ('notes.txt')" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/mine"
check "the user's file is still there" grep -q "my notes" "$tmp/mine/notes.txt"
check "-o . (the current folder) is refused" bash -c "cd '$tmp/here' && { '$glint' fit '$tmp/fscene.json' '$tmp/photo.exr' -o . 2>'$tmp/err'; test \$? = 1; } && grep -q 'is the current folder' '$tmp/err'"
check "--force writes the result beside it" run 0 "" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/mine" --force -q
check "--force wrote a result, and the user's file is kept" bash -c "test -s '$tmp/mine/params.json' && grep -q 'my notes' '$tmp/mine/notes.txt'"
check "... the folder lists glint's own files in its manifest" bash -c "grep -qx params.json '$tmp/mine/glint-outputs.txt' && ! grep -q notes '$tmp/mine/glint-outputs.txt'"
# The output folder holds the run's own inputs and a user's notes
# (glint fit d/s.json d/photo.exr -o d --force): the result goes in
# beside them, and the inputs and notes are the same bytes after.
mkdir -p "$tmp/d"
cp "$tmp/fscene.json" "$tmp/d/s.json"
cp "$tmp/env.exr" "$tmp/d/env.exr"
cp "$tmp/photo.exr" "$tmp/d/photo.exr"
echo "lab notes: sphere 3, batch 7" >"$tmp/d/notes.txt"
(cd "$tmp/d" && sha256sum s.json env.exr photo.exr notes.txt) >"$tmp/d.sums"
check "-o DIR holding the run's inputs: refused without --force" run 1 "holds files glint did not write" fit "$tmp/d/s.json" "$tmp/d/photo.exr" -o "$tmp/d"
check "-o DIR holding the run's inputs and notes, --force: done" run 0 "" fit "$tmp/d/s.json" "$tmp/d/photo.exr" -o "$tmp/d" --force --export gltf -q
check "... the inputs and the notes untouched, byte for byte" bash -c "cd '$tmp/d' && sha256sum -c --quiet '$tmp/d.sums' && test -s params.json && test -s material.gltf"
check "... again (no export this time): glint's old export replaced, the rest kept" run 0 "" fit "$tmp/d/s.json" "$tmp/d/photo.exr" -o "$tmp/d" --force -q
check "... material.gltf gone, inputs and notes still whole" bash -c "cd '$tmp/d' && test ! -e material.gltf && sha256sum -c --quiet '$tmp/d.sums' && test -s params.json"
# An input under a name the result writes would be replaced: refused,
# even with --force, before any work.
mkdir -p "$tmp/e"
cp "$tmp/photo.exr" "$tmp/e/render.exr"
check "an input named like an output (render.exr): refused even with --force" run 1 "is an input of this run, and the result writes a file of that name" fit "$tmp/fscene.json" "$tmp/e/render.exr" -o "$tmp/e" --force
check "... it is untouched" cmp "$tmp/photo.exr" "$tmp/e/render.exr"
mkdir -p "$tmp/f/sub"
check "a sub-folder of the user's: refused even with --force" run 1 "not a plain file" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/f" --force
check "... it is still there" test -d "$tmp/f/sub"
mkdir -p "$tmp/theirs"
echo "their notes" >"$tmp/theirs/notes.txt"
ln -s "$tmp/theirs" "$tmp/link"
check "-o LINK (a symbolic link to a folder) is refused, even with --force" run 1 "is a symbolic link" fit "$tmp/fscene.json" "$tmp/photo.exr" -o "$tmp/link" --force
check "... the folder it points to is untouched" bash -c "test -L '$tmp/link' && grep -q 'their notes' '$tmp/theirs/notes.txt'"
check "render a near-mirror (copper) from the same scene" run 0 "" render "$tmp/fscene.json" --paper copper -o "$tmp/copper.exr" -q
check "the near-mirror is fitted, not refused" run 0 "" fit "$tmp/fscene.json" "$tmp/copper.exr" -o "$tmp/fitcu" --json -q
check "its params.json states the rule and the verdict" python3 -c "
import json; r=json.load(open('$tmp/out'))
a=r['accepted'], r['acceptance']
assert r['accepted'] is True and r['acceptance']['relative_rmse'] < r['acceptance']['limit'], a
assert 'flat disc' in r['acceptance']['rule'] and r['acceptance']['verdict'], a"
check "the refused fits wrote no result folder" test ! -e "$tmp/fit1"
fi

echo "$((checks - fails)) passed, $fails failed"
[ "$fails" = 0 ]
