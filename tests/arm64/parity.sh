#!/usr/bin/env bash
# The arm64 build against the native one (scripts/setup-arm64 --test): the
# same render of the demo scene (Embree's NEON path through sse2neon on
# arm64, SSE/AVX on amd64; each libm) and the same fit of one photo, with
# each side's time (the arm64 one emulated by qemu: a ratio of instruction
# mix, not a board's speed).
#   parity.sh NATIVE_GLINT ARM64_GLINT SYSROOT DATA_DIR
set -euo pipefail
native=$1 arm=$2 sysroot=$3 data=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
qemu=(qemu-aarch64-static -L "$sysroot")
fails=0

timed() { # OUT_SECONDS_FILE COMMAND...: run it, its wall time in the file
	local t0=$EPOCHREALTIME
	"${@:2}"
	python3 -c "print($EPOCHREALTIME - $t0)" >"$1"
}

# The demo scene at 128 x 128 (the same sphere, a quarter of the pixels:
# emulation is slow).
python3 - "$data/demo-scene.json" "$tmp/scene.json" "$data" <<'PY'
import json, os, sys
s = json.load(open(sys.argv[1]))
s["camera"]["width"] = s["camera"]["height"] = 128
s["environment"]["path"] = os.path.abspath(
    os.path.join(sys.argv[3], s["environment"]["path"]))
json.dump(s, open(sys.argv[2], "w"))
PY
scene=$tmp/scene.json

for m in satin-paint copper; do
	timed "$tmp/tn" "$native" render "$scene" --paper "$m" \
		-o "$tmp/$m.native.pfm" -q
	timed "$tmp/ta" "${qemu[@]}" "$arm" render "$scene" \
		--paper "$m" -o "$tmp/$m.arm64.pfm" -q
	python3 - "$tmp/$m.native.pfm" "$tmp/$m.arm64.pfm" "$m" \
		"$(cat "$tmp/tn")" "$(cat "$tmp/ta")" <<'PY' || fails=$((fails + 1))
import math, struct, sys

def pfm(path):
    f = open(path, "rb")
    kind = f.readline().strip()
    w, h = map(int, f.readline().split())
    scale = float(f.readline())
    n = w * h * (3 if kind == b"PF" else 1)
    fmt = ("<" if scale < 0 else ">") + "%df" % n
    return w, h, struct.unpack(fmt, f.read(4 * n))

wa, ha, a = pfm(sys.argv[1])
wb, hb, b = pfm(sys.argv[2])
assert (wa, ha) == (wb, hb), ((wa, ha), (wb, hb))
mean = sum(a) / len(a)
d2 = sum((x - y) ** 2 for x, y in zip(a, b))
rel = math.sqrt(d2 / sum(x * x for x in a))
worst = max(abs(x - y) for x, y in zip(a, b)) / mean
same = sum(x == y for x, y in zip(a, b)) / len(a)
tn, ta = float(sys.argv[4]), float(sys.argv[5])
print(f"render {sys.argv[3]} {wa}x{ha}: arm64 against amd64 relative RMS "
      f"{rel:.2e}, worst value {worst:.2e} of the mean, {100 * same:.1f} % "
      f"bit-identical; {tn:.2f} s native, {ta:.2f} s under qemu "
      f"({ta / tn:.1f}x)")
if not (rel < 1e-4 and worst < 1e-2):
    sys.exit("FAIL the arm64 render differs from the amd64 one")
PY
done

# One fit of the native render of satin paint, on each side.
photo=$tmp/satin-paint.native.pfm
timed "$tmp/tn" "$native" fit "$scene" "$photo" -o "$tmp/fit.native" -q >/dev/null
timed "$tmp/ta" "${qemu[@]}" "$arm" fit "$scene" "$photo" -o "$tmp/fit.arm64" -q >/dev/null
python3 - "$tmp/fit.native/params.json" "$tmp/fit.arm64/params.json" \
	"$(cat "$tmp/tn")" "$(cat "$tmp/ta")" <<'PY' || fails=$((fails + 1))
import json, sys
a = {p["name"]: p for p in json.load(open(sys.argv[1]))["parameters"]}
b = {p["name"]: p for p in json.load(open(sys.argv[2]))["parameters"]}
worst = max(abs(a[k]["value"] - b[k]["value"]) / max(a[k]["stderr"], 1e-12)
            for k in a)
tn, ta = float(sys.argv[3]), float(sys.argv[4])
print("fit satin-paint: " + ", ".join(
    f"{k} {a[k]['value']:.4f}/{b[k]['value']:.4f}" for k in a)
    + f" (amd64/arm64); largest difference {worst:.3f} standard errors; "
    f"{tn:.2f} s native, {ta:.2f} s under qemu ({ta / tn:.1f}x)")
if worst > 0.1:
    sys.exit("FAIL the arm64 fit differs from the amd64 one")
PY
[ "$fails" = 0 ]
