#!/usr/bin/env bash
# glint's glTF exports open as-is in other tools (the renderers suite):
# the Khronos glTF validator finds nothing to report (no error, warning,
# info or hint), and Blender's own glTF importer brings in one sphere of
# the stated diameter carrying the named material with the file's values.
# usage: test_gltf.sh GLINT DATA_DIR
set -euo pipefail
glint=$1
data=$2
here=$(cd "$(dirname "$0")" && pwd)
validator=${XDG_CACHE_HOME:-$HOME/.cache}/glint/gltf-validator/node_modules/gltf-validator
if ! command -v node >/dev/null || ! [ -f "$validator/package.json" ]; then
	echo "skip: the glTF validator is not installed (scripts/setup-renderers installs it)"
	exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() {
	echo "FAIL $*"
	fails=$((fails + 1))
}

# A plastic, a metal, a GGX material file and a transparent sphere.
cat >"$tmp/ggx-red.json" <<JSON
{"model": "ggx", "name": "red GGX", "diffuse": [0.4, 0.05, 0.03],
 "specular": [0.3, 0.3, 0.3], "roughness": 0.15, "ior": 1.45}
JSON
"$glint" export "$data/paper-table1.json" --entry yellow-plastic --to gltf -o "$tmp/yellow-plastic.gltf" -q >/dev/null
"$glint" export "$data/paper-table1.json" --entry copper --to gltf -o "$tmp/copper.gltf" -q >/dev/null
"$glint" export "$tmp/ggx-red.json" --to gltf -o "$tmp/red_GGX.gltf" -q >/dev/null
"$glint" export "$data/paper-table1.json" --entry purple-quartz --diameter-m 0.05 --to gltf -o "$tmp/purple-quartz.gltf" -q >/dev/null
names=(yellow-plastic copper red_GGX purple-quartz)

files=()
for n in "${names[@]}"; do files+=("$tmp/$n.gltf"); done
node "$here/gltf_validate.js" "$validator" "${files[@]}" >"$tmp/valid.jsonl" 2>"$tmp/valid.err" ||
	{ cat "$tmp/valid.err"; fail "the validator did not run"; }
while read -r line; do
	if python3 - "$line" <<'PY'; then
import json, os, sys
r = json.loads(sys.argv[1])
counts = [r[k] for k in ("errors", "warnings", "infos", "hints")]
print(f"{os.path.basename(r['file'])}: glTF validator {r['validator']}: "
      f"{counts[0]} errors, {counts[1]} warnings, {counts[2]} infos, "
      f"{counts[3]} hints")
for m in r["messages"]:
    print("   ", m)
assert counts == [0, 0, 0, 0]
PY
		echo "ok   validator: nothing to report"
	else
		fail "validator: $line"
	fi
done <"$tmp/valid.jsonl"
[ "$(wc -l <"$tmp/valid.jsonl")" = "${#names[@]}" ] || fail "the validator reported on $(wc -l <"$tmp/valid.jsonl") of ${#names[@]} files"

if ! command -v blender >/dev/null; then
	echo "skip: Blender is not installed (scripts/setup-renderers installs it); the validator's checks passed"
	[ "$fails" = 0 ] && exit 77
	exit 1
fi
export HOME=$tmp # Blender's user folders stay in the test's own
for n in "${names[@]}"; do
	if ! blender --background --factory-startup --python "$here/blender_gltf_check.py" \
		-- "$tmp/$n.gltf" "$tmp/$n.blender.json" >"$tmp/$n.log" 2>&1 ||
		! [ -s "$tmp/$n.blender.json" ]; then
		tail -20 "$tmp/$n.log"
		fail "$n: Blender's importer failed"
		continue
	fi
	if python3 - "$tmp/$n.gltf" "$tmp/$n.blender.json" "$n" <<'PY'; then
import json, sys
g = json.load(open(sys.argv[1]))
b = json.load(open(sys.argv[2]))
name = sys.argv[3]
gm = g["materials"][0]
pbr = gm["pbrMetallicRoughness"]
ext = gm["extensions"]
(obj,) = [o for o in b["objects"] if o["type"] == "MESH"]
(mat,) = b["materials"]
r = g["accessors"][0]["max"][0]
assert obj["materials"] == [name] == [mat["name"]], (obj, mat["name"])
assert obj["faces"] > 1000, obj
assert abs(obj["radius"][0] / r - 1) < 1e-5 and abs(obj["radius"][1] / r - 1) < 1e-5, (obj["radius"], r)
assert "BSDF_PRINCIPLED" in mat["nodes"] and not mat["linked"], mat
close = lambda a, x: abs(a - x) < 1e-6 * max(1, abs(x))
want = {"Base Color": pbr["baseColorFactor"],
        "Roughness": pbr["roughnessFactor"],
        "Metallic": pbr["metallicFactor"],
        "IOR": ext["KHR_materials_ior"]["ior"],
        "Transmission": ext.get("KHR_materials_transmission", {}).get(
            "transmissionFactor", 0)}
for k, v in want.items():
    got = mat[k]
    ok = all(close(a, x) for a, x in zip(got, v)) if isinstance(v, list) else close(got, v)
    assert ok, (k, got, v)
if "KHR_materials_volume" in ext:
    assert "VOLUME_ABSORPTION" in mat["nodes"], mat["nodes"]
print(f"{name}: Blender {b['blender']}: one sphere of radius {r:.4f} m, "
      f"{obj['faces']} faces, material '{mat['name']}': base colour, "
      f"roughness, metallic, ior, transmission as the file states"
      + (", a volume absorption" if "KHR_materials_volume" in ext else ""))
PY
		echo "ok   $n: Blender's importer brings in the sphere and its material"
	else
		fail "$n: what Blender imported differs from the file"
	fi
done
[ "$fails" = 0 ]
