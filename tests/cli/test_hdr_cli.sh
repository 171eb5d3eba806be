#!/usr/bin/env bash
# glint hdr on 8-bit photos: the real Memorial Church stack (skips without
# ../shared/data) and bad input.
# usage: test_hdr_cli.sh GLINT SHARED_DATA_DIR
set -u
glint=$1
mem=$2/exposures/memorial
[ -d "$mem" ] || { echo "skip: $mem absent"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../checks.sh"
photos=("$mem"/memorial00[67]?.png)
check "memorial stack merges" run 0 "" hdr --times-file "$mem/shutter_times_qhan1028.txt" "${photos[@]}" -o "$tmp/m" --json
check "... radiance, mask, response written" bash -c "test -s '$tmp/m/hdr.exr' && test -s '$tmp/m/mask.png' && test \$(grep -vc '^#' '$tmp/m/response.csv') = 256"
check "... and drawn (response.png, glint's PNG)" bash -c "head -c 8 '$tmp/m/response.png' | od -An -tx1 | tr -d ' \n' | grep -qx 89504e470d0a1a0a && grep -q 'glint' '$tmp/m/response.png'"
check "a merge into a previous one: refused without --force" run 1 "hdr.exr exists: refusing to replace it" hdr --times-file "$mem/shutter_times_qhan1028.txt" "${photos[@]}" -o "$tmp/m"
check "... replaced with it" run 0 "" hdr --times-file "$mem/shutter_times_qhan1028.txt" "${photos[@]}" -o "$tmp/m" --force -q
check "debevec response too" run 0 "" hdr --times 32,16,8,4,2,1,1/2,1/4,1/8,1/16,1/32,1/64,1/128,1/256,1/512,1/1024 "${photos[@]}" -o "$tmp/d" --response debevec -q
check "times count mismatch: exit 1" run 1 "15 exposure times for 16 images" hdr --times 32,16,8,4,2,1,1/2,1/4,1/8,1/16,1/32,1/64,1/128,1/256,1/512 "${photos[@]:0:15}" "${photos[15]}" -o "$tmp/x"
rev=($(printf '%s\n' "${photos[@]}" | sort -r))
check "frames in the wrong order for their times: exit 1, named" run 1 "memorial0076.png (32 s) is darker than" hdr --times-file "$mem/shutter_times_qhan1028.txt" "${rev[@]}" -o "$tmp/rev"
check "... nothing written" test ! -e "$tmp/rev/hdr.exr"
check "a duplicated frame: exit 1, named" run 1 "are the same image" hdr --times 4,2,1 "${photos[5]}" "${photos[5]}" "${photos[7]}" -o "$tmp/dup"
check "equal times: exit 1" run 1 "must differ" hdr --times 1,1 "${photos[0]}" "${photos[1]}" -o "$tmp/x"
check "a bad time: exit 1" run 1 "'-2'" hdr --times 1,-2 "${photos[0]}" "${photos[1]}" -o "$tmp/x"
check "unknown response method: exit 2" run 2 "--response 'fancy': expected one of robertson, debevec" hdr --times 1,2 a.png b.png -o "$tmp/x" --response fancy
# Exposure times from EXIF: 8-bit TIFF photos written byte by byte with
# an EXIF directory (make_exif_tiffs.py), merged without --times.
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$tmp/exif" "$tmp/wrong" "$tmp/none"
python3 "$here/make_exif_tiffs.py" "$tmp/exif" 4 1 1/4 1/16
check "TIFF photos merge with their EXIF exposure times" run 0 "" hdr "$tmp"/exif/p*.tif -o "$tmp/e" --json
check "... the times read are EXIF's" python3 -c "
import json; d = json.load(open('$tmp/out'))
assert d['times_from'] == 'EXIF' and d['exposure_times_s'] == [4, 1, 0.25, 0.0625], d"
python3 "$here/make_exif_tiffs.py" "$tmp/wrong" --exif 1/16 1/4 1 4 --shot 4 1 1/4 1/16
check "EXIF times that contradict the pixels: exit 1, named" run 1 "p1.tif (0.25 s) is darker than" hdr "$tmp"/wrong/p*.tif -o "$tmp/w"
python3 "$here/make_exif_tiffs.py" "$tmp/none" --no-exif 1
check "a photo without EXIF: exit 1, says --times" run 1 "p0.tif: no EXIF directory: give the exposure times with --times" hdr "$tmp/none/p0.tif" "$tmp/exif/p1.tif" -o "$tmp/n"
check "... --times then merges TIFF photos" run 0 "" hdr --times 1,1/4 "$tmp/none/p0.tif" "$tmp/exif/p2.tif" -o "$tmp/n2"
head -c 3000 "${photos[3]}" >"$tmp/cut.png"
check "truncated photo: exit 1, named" run 1 "cut.png" hdr --times 1,2 "${photos[0]}" "$tmp/cut.png" -o "$tmp/x"
check "nothing written on failure" test ! -e "$tmp/x/hdr.exr"
# glint probe
campus=$(dirname "$mem")/../probes/campus_probe.hdr
check "probe convert angular -> latlong" run 0 "" probe convert "$campus" "$tmp/c.exr" --from angular --to latlong
check "... -> cross" run 0 "" probe convert "$tmp/c.exr" "$tmp/c.hdr" --from latlong --to cross --size 300x400
check "unknown format: exit 2" run 2 "latlong, angular, cross or ball" probe convert "$tmp/c.exr" "$tmp/d.exr" --from latlong --to sphere
check "non-square angular: exit 1" run 1 "square" probe convert "$tmp/c.exr" "$tmp/d.exr" --from angular --to latlong
check "unwrap without the focal length: exit 2" run 2 "--focal-px is required" probe unwrap "$tmp/c.exr" -o "$tmp/e.exr" --ball 320,160,100
chrome=$(dirname "$mem")/../spheres/uw_psm/chrome/chrome.3.tga
check "an 8-bit ball photo is refused as radiance" run 1 "not radiance" probe unwrap "$chrome" -o "$tmp/u.exr" --focal-px 1000
check "... nothing written" test ! -e "$tmp/u.exr"
check "--srgb: the ball is found in the photo" run 0 "found the ball at 254." probe unwrap "$chrome" -o "$tmp/u.exr" --focal-px 1000 --srgb
check "... and the 8-bit input is warned about" grep -q "8-bit, taken as sRGB-encoded" "$tmp/err"
check "... a preview of the map beside it (glint's PNG)" bash -c "head -c 8 '$tmp/u-preview.png' | od -An -tx1 | tr -d ' \n' | grep -qx 89504e470d0a1a0a && grep -q glint '$tmp/u-preview.png'"
check "a --ball 19 px off the photo's is warned about" run 0 "disagrees with the ball found in the photo" probe unwrap "$chrome" -o "$tmp/u.exr" --focal-px 1000 --srgb --ball 254.5,147.5,100 --force
python3 - "$tmp/noise.pfm" <<'PY'
import random, struct, sys
random.seed(7)
w, h = 320, 240
with open(sys.argv[1], "wb") as f:
    f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
    f.write(struct.pack("<%df" % (w * h * 3), *[random.random() for _ in range(w * h * 3)]))
PY
check "unwrap of pure noise: no ball, the photo named, exit 1" run 1 "noise.pfm: no ball found" probe unwrap "$tmp/noise.pfm" -o "$tmp/n.exr" --focal-px 640
check "... 'no sphere in the image', nothing written" bash -c "grep -q 'no sphere in the image' '$tmp/err' && test ! -e '$tmp/n.exr'"
python3 - "$tmp/neg.pfm" <<'PY'
import struct, sys
w, h = 128, 128
px = []
for y in range(h):
    for x in range(w):
        v = -40.0 if (x - 64) ** 2 + (y - 64) ** 2 < 100 else 1.0
        px += [v, v, v]
with open(sys.argv[1], "wb") as f:
    f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
    f.write(struct.pack("<%df" % len(px), *px))
PY
check "unwrap of a ball holding negative radiance: refused where it is made" run 1 "unwrap: $tmp/nmap.exr: pixel" probe unwrap "$tmp/neg.pfm" -o "$tmp/nmap.exr" --focal-px 1000 --ball 64,64,50
check "... below zero by more than the noise allows, nothing written" bash -c "grep -q 'below zero by more than the noise allows' '$tmp/err' && test ! -e '$tmp/nmap.exr'"
check "unwrap of a ball off the photo: exit 1" run 1 "not inside" probe unwrap "$tmp/c.exr" -o "$tmp/e.exr" --focal-px 1000 --ball 10,10,50
check "... nothing written" test ! -e "$tmp/e.exr"
check "unwrap writes env, mask, density" run 0 "" probe unwrap "$tmp/c.exr" -o "$tmp/e.exr" --focal-px 1000 --ball 320,160,100
check "... all three" bash -c "test -s '$tmp/e.exr' && test -s '$tmp/e-mask.png' && test -s '$tmp/e-density.exr'"
check "register a map with itself: no turn" run 0 "" probe register "$tmp/c.exr" "$tmp/c.exr" -o "$tmp/b.exr" --yaw 0 --json
check "... angle ~0" python3 -c "import json,sys; d=json.load(open('$tmp/out')); sys.exit(d['angle_deg'] > 0.3)"
printf '10 10 20 20\n' >"$tmp/one.txt"
check "register from one point: exit 1" run 1 "at least 2" probe register "$tmp/c.exr" "$tmp/c.exr" -o "$tmp/b2.exr" --points "$tmp/one.txt"
checks_done
