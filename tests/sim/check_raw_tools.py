#!/usr/bin/env python3
"""A glint DNG frame opened by the raw tools users have: dcraw and LibRaw
(the decoder darktable and most raw software build on).

  check_raw_tools.py FRAME.dng WORK_DIR

Both decode the raw values (dcraw -D -4, LibRaw's unprocessed_raw: 16-bit
PGM, big-endian, row by row: exactly what glint's pixels_crc32 covers), so
the CRC-32 of their output must equal the frame's sidecar "pixels_crc32":
bit for bit what glint captured.  Their identification must give glint's
size, CFA pattern, exposure time, ISO (100 x gain) and black level.
Exits 77 when the tools are not installed (scripts/setup installs them)."""
import json
import os
import re
import shutil
import subprocess
import sys
import zlib


def pgm_pixels(data):
    m = re.match(rb"P5\s+(\d+)\s+(\d+)\s+(\d+)\s", data)
    assert m, data[:20]
    w, h, maxval = (int(x) for x in m.groups())
    assert maxval == 65535, maxval
    pix = data[m.end():]
    assert len(pix) == 2 * w * h, (len(pix), w, h)
    return w, h, pix


def main():
    path, work = sys.argv[1], sys.argv[2]
    if not (shutil.which("dcraw") and shutil.which("unprocessed_raw")):
        print("skip: dcraw and libraw-bin are not installed")
        sys.exit(77)
    side = json.load(open(path[:-4] + ".json"))
    want = side["pixels_crc32"]
    pattern = {"RGGB16": "RG/GB", "GRBG16": "GR/BG", "GBRG16": "GB/RG",
               "BGGR16": "BG/GR"}[side["format"]]

    # dcraw: identification, then the raw values.
    info = subprocess.run(["dcraw", "-i", "-v", path], capture_output=True,
                          text=True, check=True).stdout
    print(" ", " | ".join(line.strip() for line in info.splitlines()
                          if re.match(r"(Shutter|ISO|Filter|Image size)",
                                      line)))
    shutter = re.search(r"Shutter: (?:1/)?([\d.]+) sec", info)
    t = float(shutter.group(1))
    t = 1 / t if "Shutter: 1/" in info else t
    assert abs(t - side["exposure_s"]) <= 1e-3 * side["exposure_s"], (t, side)
    iso = int(re.search(r"ISO speed: (\d+)", info).group(1))
    assert iso == round(100 * side["gain"]), (iso, side["gain"])
    assert f"Filter pattern: {pattern}" in info, info
    assert re.search(r"Image size: +%d x %d" % (side["width"], side["height"]),
                     info), info
    raw = subprocess.run(["dcraw", "-D", "-4", "-c", path],
                         capture_output=True, check=True).stdout
    w, h, pix = pgm_pixels(raw)
    assert (w, h) == (side["width"], side["height"]), (w, h)
    got = zlib.crc32(pix)
    assert got == want, f"dcraw decodes CRC-32 {got:08x}, glint wrote {want:08x}"

    # LibRaw: identification and unprocessed_raw's PGM.
    copy = os.path.join(work, "libraw.dng")
    shutil.copyfile(path, copy)
    info = subprocess.run(["raw-identify", "-v", copy], capture_output=True,
                          text=True, check=True).stdout
    assert re.search(r"^black: %d$" % round(side["black_level"]), info, re.M), info
    assert "ISO speed: %d" % round(100 * side["gain"]) in info, info
    subprocess.run(["unprocessed_raw", copy], capture_output=True, check=True)
    w, h, pix = pgm_pixels(open(copy + ".pgm", "rb").read())
    got2 = zlib.crc32(pix)
    assert got2 == want, f"LibRaw decodes CRC-32 {got2:08x}, glint wrote {want:08x}"
    print(f"  dcraw and LibRaw: {w} x {h}, CRC-32 {want:08x} as glint wrote it")


main()
