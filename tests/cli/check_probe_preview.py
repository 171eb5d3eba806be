#!/usr/bin/env python3
"""A probe's ENV-preview.png rings each light source of ENV-sources.json
where the map holds it: the ring's colour on the circle of radius 7 px
about the source's lat-long position, and the title line on top.

usage: check_probe_preview.py ENV-preview.png ENV-sources.json
"""
import json
import math
import struct
import sys
import zlib


def read_png_rgb8(path):
    """An 8-bit RGB, non-interlaced PNG (as glint writes them): rows."""
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(d):
        n, kind = struct.unpack(">I4s", d[pos:pos + 8])
        body = d[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(
                ">IIBBBBB", body)
            assert (depth, colour, interlace) == (8, 2, 0), (depth, colour)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, bpp, stride = zlib.decompress(idat), 3, 3 * w
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(
            raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else b if pb <= pc else c
                line[i] = (line[i] + pr) & 255
        rows.append(line)
        prev = line
    return w, h, rows


png, sources = sys.argv[1], json.load(open(sys.argv[2]))["sources"]
w, h, rows = read_png_rgb8(png)
top, mh = 14, w // 2
assert h == top + mh, (w, h)
ring = (255, 40, 200)
for k, s in enumerate(sources):
    x, y, z = s["direction"]
    u = 0.5 + math.atan2(x, -z) / (2 * math.pi)
    v = math.acos(max(-1, min(1, y))) / math.pi
    cx, cy = u * w, top + v * mh
    hits = 0
    for a in range(36):
        px = int(cx + 7 * math.cos(a * math.pi / 18))
        py = int(cy + 7 * math.sin(a * math.pi / 18))
        if 0 <= px < w and 0 <= py < h:
            hits += tuple(rows[py][3 * px:3 * px + 3]) == ring
    print(f"source {k + 1}: ({cx:.1f}, {cy:.1f}) px, ringed at {hits} of "
          "36 points")
    assert hits >= 24, (k, hits)
# The title: dark text on the white band.
assert any(rows[y][3 * x] < 100 for y in range(3, 10) for x in range(2, 60))
print(f"{png}: {len(sources)} source(s) ringed where the map holds them")
