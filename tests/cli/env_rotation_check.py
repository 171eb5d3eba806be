#!/usr/bin/env python3
"""glint and Blender light a sphere from the same direction of a rotated
environment map (the renderers suite, tests/cli/test_blender.sh).

  env_rotation_check.py make MAP.pfm
      a 256 x 128 lat-long map, black but for a small bright spot at map
      direction SPOT (glint's convention, docs/conventions.md)
  env_rotation_check.py compare GLINT.pfm R_GLINT BLENDER.pfm R_BLENDER
      each render's sphere (centred, R_* its radius in pixels): the
      brightness-weighted mean normal, in the camera's frame (x right, y
      up, z toward the camera); prints both and the angle between them
"""
import math
import struct
import sys

SPOT = (0.45, 0.5, 0.74)  # a map direction (x, y, z), normalised below


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def write_pfm(path, w, h, px):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        for y in range(h - 1, -1, -1):  # PFM rows run bottom-up
            f.write(struct.pack("<%df" % (3 * w), *px[y]))


def read_pfm(path):
    d = open(path, "rb").read()
    parts = d.split(b"\n", 3)
    assert parts[0] == b"PF", parts[0]
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    fmt = "<" if scale < 0 else ">"
    vals = struct.unpack(fmt + "%df" % (3 * w * h), parts[3][:12 * w * h])
    rows = [vals[3 * w * k:3 * w * (k + 1)] for k in range(h)]
    return w, h, rows[::-1]


def make(path):
    w, h = 256, 128
    s = unit(SPOT)
    px = []
    for y in range(h):
        row = []
        th = math.pi * (y + 0.5) / h
        for x in range(w):
            ph = 2 * math.pi * ((x + 0.5) / w - 0.5)
            # glint: phi = atan2(x, -z), theta = acos(y)
            d = (math.sin(th) * math.sin(ph), math.cos(th),
                 -math.sin(th) * math.cos(ph))
            c = sum(a * b for a, b in zip(d, s))
            v = 200.0 * math.exp((c - 1) / 0.002) if c > 0.9 else 0.0
            row += [v, v, v]
        px.append(row)
    write_pfm(path, w, h, px)


def lit_normal(path, r):
    w, h, rows = read_pfm(path)
    cx, cy = w / 2, h / 2
    acc = [0.0, 0.0, 0.0]
    for y in range(h):
        for x in range(w):
            nx, ny = (x + 0.5 - cx) / r, -(y + 0.5 - cy) / r
            q = nx * nx + ny * ny
            if q >= 0.9:  # off the sphere or at its blurred rim
                continue
            i = sum(rows[y][3 * x:3 * x + 3]) / 3
            n = (nx, ny, math.sqrt(1 - q))
            for k in range(3):
                acc[k] += i * n[k]
    return unit(acc)


if sys.argv[1] == "make":
    make(sys.argv[2])
else:
    g = lit_normal(sys.argv[2], float(sys.argv[3]))
    b = lit_normal(sys.argv[4], float(sys.argv[5]))
    ang = math.degrees(math.acos(max(-1, min(1, sum(
        x * y for x, y in zip(g, b))))))
    print("lit from (camera frame) glint %s, Blender %s: %.2f deg apart"
          % (", ".join("%.3f" % c for c in g),
             ", ".join("%.3f" % c for c in b), ang))
    sys.exit(0 if ang < 3 else 1)
