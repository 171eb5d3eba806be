#!/usr/bin/env bash
# glint hdr on raw files glint did not write: one bracket of the simulated
# camera, its values carried into other writers' files, each merged and
# compared with glint's own merge of the same values (check_raw_input.py):
#  - glint's DNGs with glint's metadata stripped (exiftool): LibRaw reads
#    them; the same radiance;
#  - 16-bit linear TIFFs by dcraw -4 -T: dcraw's scale (65535 / (4095 -
#    64)) and its own demosaic; the same samples as linear DNGs by
#    tifffile, read by LibRaw: the TIFFs' merge;
#  - DNGs by tifffile (a 14-bit range, black 256, white 12000, a GRBG
#    mosaic, a Canon's colour matrix): the values through the file's
#    matrix, and D65 white through it grey;
#  - Minolta MRW (raw_writers.py): a camera raw LibRaw identifies by its
#    table (its white level, colour matrix), frames at ISO 200 with half
#    the exposure among them: the same merge;
# and the conversion gain each bracket implies (photon transfer) against
# the simulated sensor's, bad files named.
# usage: test_raw_input.sh GLINT
set -u
glint=$1
here=$(cd "$(dirname "$0")" && pwd)
for tool in dcraw exiftool; do
	command -v $tool >/dev/null || { echo "skip: $tool is not installed (scripts/setup installs it)"; exit 77; }
done
# tifffile is Debian's python3-tifffile: the system's Python.
py=
for p in python3 /usr/bin/python3; do
	"$p" -c "import tifffile" 2>/dev/null && { py=$p; break; }
done
[ -n "$py" ] || { echo "skip: python3-tifffile is not installed (scripts/setup installs it)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../checks.sh"
json_is() { # FILE PYTHON_EXPR: the expression holds for d = FILE's JSON
	python3 -c "import json, sys; d = json.load(open('$1')); sys.exit(0 if ($2) else 1)" ||
		{ echo "  $1: not ($2):" >&2; python3 -c "import json; print(json.load(open('$1')).get('input'))" >&2; return 1; }
}

cat >"$tmp/rig.json" <<JSON
{"camera": {"backend": "sim", "device": "sim:width=192,height=128,timescale=0.01,decades=4"},
 "bracket": {"step_ev": 1, "max_frames": 24},
 "roi": {"sample": [0, 0, 192, 128]},
 "output": "$tmp/caps"}
JSON
check "a bracket of the simulated camera" run 0 "" capture sample --config "$tmp/rig.json" -q
sess=$(ls -d "$tmp"/caps/*/ | head -1)
frames=("$sess"/frame-00[3-9].dng)
check "glint's own merge of frames 3-9" run 0 "" hdr "${frames[@]}" -o "$tmp/ref" -q
mkdir "$tmp/strip" "$tmp/tif" "$tmp/dng" "$tmp/mrw" "$tmp/lin"
i=0
for f in "${frames[@]}"; do
	b=$(basename "$f" .dng)
	t=$(python3 -c "import json; print(json.load(open('${f%.dng}.json'))['exposure_s'])")
	cp "$f" "$tmp/strip/"
	dcraw -4 -T -c "$f" >"$tmp/tif/$b.tiff"
	dcraw -D -4 -c "$f" >"$tmp/$b.pgm"
	"$py" "$here/raw_writers.py" dng "$tmp/$b.pgm" "$tmp/dng/$b.dng" "$t" 100
	"$py" "$here/raw_writers.py" linear-dng "$tmp/tif/$b.tiff" "$tmp/lin/$b.dng" "$t" 0
	# Every other MRW frame at ISO 200 for half the time: the same light.
	if ((i++ % 2)); then
		python3 "$here/raw_writers.py" mrw "$tmp/$b.pgm" "$tmp/mrw/$b.mrw" "$(python3 -c "print($t / 2)")" 200
	else
		python3 "$here/raw_writers.py" mrw "$tmp/$b.pgm" "$tmp/mrw/$b.mrw" "$t" 100
	fi
done
exiftool -q -overwrite_original -ImageDescription= "$tmp"/strip/*.dng
pfm() { "$glint" convert "$1/hdr.exr" "$1/hdr.pfm" -q; }
pfm "$tmp/ref"

check "stripped DNGs: no glint metadata left in them" bash -c "! grep -l pixels_crc32 '$tmp'/strip/*.dng"
check "stripped DNGs merge through LibRaw" run 0 "" hdr "$tmp"/strip/*.dng -o "$tmp/s" -q
check "... read by LibRaw as the sim camera, RGGB, black 64, white 4095" json_is "$tmp/s/hdr.json" \
	"d['input']['reader'].startswith('LibRaw') and d['input']['camera'] == 'glint sim' and d['input']['format'] == 'RGGB16' and d['input']['black_level'] == 64 and d['input']['white_level'] == 4095 and d['input']['exposure_times_from'] == \"the files' metadata\""
check "... the conversion gain from the bracket within 5 % of the sensor's 0.4095" json_is "$tmp/s/hdr.json" \
	"d['input']['noise_model_from'].startswith('the bracket') and abs(d['noise_model']['dn_per_electron'] / 0.4095 - 1) < 0.05"
pfm "$tmp/s"
check "... the same radiance as glint's merge (within 0.1 %)" python3 "$here/check_raw_input.py" "$tmp/ref/hdr.pfm" "$tmp/s/hdr.pfm" "$tmp/s/hdr.json" 1 0 0.001

check "dcraw's 16-bit TIFFs merge (EXIF times)" run 0 "" hdr "$tmp"/tif/*.tiff -o "$tmp/t" -q
check "... read by libtiff, RGB16, white 65535" json_is "$tmp/t/hdr.json" \
	"d['input']['reader'] == 'libtiff' and d['input']['format'] == 'RGB16' and d['input']['white_level'] == 65535 and d['valid_pixels'] > 0.9 * 192 * 128"
pfm "$tmp/t"
check "... glint's radiance x 65535 / 4031 (dcraw's scale; its demosaic within 1 %)" python3 "$here/check_raw_input.py" "$tmp/ref/hdr.pfm" "$tmp/t/hdr.pfm" "$tmp/t/hdr.json" "$(python3 -c 'print(65535 / 4031)')" 0 0.005

check "tifffile's linear DNGs of those TIFFs' samples merge (LibRaw)" run 0 "" hdr "$tmp"/lin/*.dng -o "$tmp/l" -q
check "... RGB16, no colour matrix" json_is "$tmp/l/hdr.json" \
	"d['input']['reader'].startswith('LibRaw') and d['input']['format'] == 'RGB16' and d['input']['matrix'] is None"
pfm "$tmp/l"
check "... the same radiance as the TIFFs' merge" python3 "$here/check_raw_input.py" "$tmp/t/hdr.pfm" "$tmp/l/hdr.pfm" "$tmp/l/hdr.json" 1 0 0.0002

check "tifffile's DNGs merge" run 0 "" hdr "$tmp"/dng/*.dng -o "$tmp/d" -q
check "... GRBG, black 256, white 12000, the Canon's matrix" json_is "$tmp/d/hdr.json" \
	"d['input']['camera'] == 'Canon EOS 5D Mark II' and d['input']['format'] == 'GRBG16' and d['input']['black_level'] == 256 and d['input']['white_level'] == 12000 and d['input']['matrix'] is not None"
check "... the conversion gain 3 x the sensor's (values x 3) within 5 %" json_is "$tmp/d/hdr.json" \
	"abs(d['noise_model']['dn_per_electron'] / (3 * 0.4095) - 1) < 0.05"
pfm "$tmp/d"
check "... 3 x the file's matrix x glint's radiance; D65 white grey" python3 "$here/check_raw_input.py" "$tmp/ref/hdr.pfm" "$tmp/d/hdr.pfm" "$tmp/d/hdr.json" 3 1 0.002 \
	0.4716,0.0603,-0.0830,-0.7798,1.5474,0.2480,-0.1496,0.1937,0.6651

check "Minolta MRW files merge" run 0 "" hdr "$tmp"/mrw/*.mrw -o "$tmp/m" -q --json
check "... LibRaw's DiMAGE 7Hi: white 3965, black 0, a matrix, ISO read" json_is "$tmp/m/hdr.json" \
	"d['input']['camera'] == 'Minolta DiMAGE 7Hi' and d['input']['white_level'] == 3965 and d['input']['black_level'] == 0 and d['input']['matrix'] is not None and d['input']['iso'] == 100"
pfm "$tmp/m"
# The ISO 200 frames count as gain 2 (read from the files: otherwise they
# would read as twice the light), so the noise model weighs them
# differently from glint's merge: the same median, a spread of the noise.
check "... the file's matrix x glint's radiance (ISO 200 frames at half the time agree)" python3 "$here/check_raw_input.py" "$tmp/ref/hdr.pfm" "$tmp/m/hdr.pfm" "$tmp/m/hdr.json" 1 0 0.005

# The conversion gains found, for the docs' table (docs/hdr.md).
for d in s d m; do
	python3 -c "import json; j = json.load(open('$tmp/$d/hdr.json')); print('  conversion gain from the bracket of', j['input']['camera'], '(%s):' % j['input']['reader'], round(j['noise_model']['dn_per_electron'], 4), 'DN/e-')"
done

# Times: a file without one needs --times; --times replaces the files'.
"$py" "$here/raw_writers.py" dng "$tmp/frame-005.pgm" "$tmp/noexp.dng" 1 100 --no-exposure
check "a raw file without an exposure time: exit 1, named, says --times" run 1 "noexp.dng: no exposure time in its metadata: give the bracket's times (--times" hdr "$tmp/noexp.dng" "$tmp/dng/frame-006.dng" -o "$tmp/x"
t5=$(python3 -c "import json; print(json.load(open('$sess/frame-005.json'))['exposure_s'])")
t6=$(python3 -c "import json; print(json.load(open('$sess/frame-006.json'))['exposure_s'])")
check "... merges with --times" run 0 "" hdr "$tmp/noexp.dng" "$tmp/dng/frame-006.dng" -o "$tmp/x" --times "$t5,$t6" -q
check "... which hdr.json names" json_is "$tmp/x/hdr.json" "d['input']['exposure_times_from'] == '--times'"
check "--times with a session: exit 2 (its frames carry their own)" run 2 "a session's frames carry their own exposure times" hdr "$sess" --times 1,2

# Bad files: named, nothing written.
echo "not a raw file" >"$tmp/bad.nef"
check "a file LibRaw cannot read: exit 1, named" run 1 "bad.nef: not a raw file LibRaw reads" hdr "$tmp/bad.nef" "$tmp/mrw/frame-004.mrw" -o "$tmp/y"
head -c 9000 "$tmp/mrw/frame-004.mrw" >"$tmp/cut.mrw"
check "a truncated raw file: exit 1, named" run 1 "cut.mrw: its raw data is truncated or corrupt (LibRaw: unexpected end of file)" hdr "$tmp/cut.mrw" "$tmp/mrw/frame-005.mrw" -o "$tmp/y"
# A file on which Debian's LibRaw 0.20 itself aborts (a fortified strcat
# in its Hasselblad model parser, found by the fuzz suite): LibRaw runs in a
# child process, so the crash is one named refusal and glint goes on.
cp "$here/../fuzz/regressions/raw/hasselblad-model-strcat" "$tmp/crash.mrw"
check "a file LibRaw crashes on: exit 1, named, nothing written" run 1 "crash.mrw: LibRaw crashed reading it (Aborted)" hdr "$tmp/crash.mrw" "$tmp/mrw/frame-005.mrw" -o "$tmp/y"
check "frames of two cameras: exit 1, both named" run 1 "frame-005.mrw: Minolta DiMAGE 7Hi (read by LibRaw" hdr "$tmp/dng/frame-004.dng" "$tmp/mrw/frame-005.mrw" -o "$tmp/y"
check "... nothing written" test ! -e "$tmp/y/hdr.exr"
# A FIFO given as a photo (LibRaw, libtiff and libexif open by path) is
# refused at once, not read until the test's timeout.
mkfifo "$tmp/fifo.mrw" "$tmp/fifo.tif" "$tmp/fifo.jpg"
for f in fifo.mrw fifo.tif fifo.jpg; do
	check "a FIFO as a photo ($f): exit 1 at once, named" timeout 30 bash -c "'$glint' hdr '$tmp/$f' -o '$tmp/z' --times 1 2>'$tmp/err'; [ \$? = 1 ] && grep -q '$f: a FIFO, not a regular file' '$tmp/err' && test ! -e '$tmp/z'"
done

checks_done
