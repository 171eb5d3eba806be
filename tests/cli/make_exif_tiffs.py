#!/usr/bin/env python3
"""Write a bracket of 8-bit RGB TIFF photos of a synthetic scene, each
with an EXIF directory holding its ExposureTime (written here byte by
byte, not with libtiff).

  make_exif_tiffs.py DIR T1 T2 ...   -> DIR/p0.tif, p1.tif, ... (exposed
                                        for T1, T2, ...)
  make_exif_tiffs.py DIR --exif T1 T2 ... --shot S1 S2 ...
                                     (EXIF says T, the pixels were shot
                                      with S: a wrong time)
  make_exif_tiffs.py DIR --no-exif T  (p0.tif without EXIF)"""
import math
import struct
import sys

W, H = 48, 32


def pixels(t):
    out = bytearray()
    for y in range(H):
        for x in range(W):
            L = 10 ** (3.0 * x / W - 1.5) * (0.5 + 0.5 * y / H)
            for c in (1.0, 0.8, 0.6):
                v = min(1.0, L * c * t) ** (1 / 2.2)
                out.append(int(round(255 * v)))
    return bytes(out)


def rational(t):
    den = 1000000
    return int(round(t * den)), den


def tiff(path, t_pixels, t_exif):
    data = pixels(t_pixels)
    n0 = 12 if t_exif else 11
    ifd0 = 8
    exif = ifd0 + 2 + 12 * n0 + 4
    extra = exif + (2 + 12 + 4 if t_exif else 0)
    bits_off, rat_off = extra, extra + 6
    data_off = rat_off + 8
    e = []  # (tag, type, count, value bytes)
    e.append((256, 3, 1, struct.pack("<HH", W, 0)))
    e.append((257, 3, 1, struct.pack("<HH", H, 0)))
    e.append((258, 3, 3, struct.pack("<I", bits_off)))
    e.append((259, 3, 1, struct.pack("<HH", 1, 0)))
    e.append((262, 3, 1, struct.pack("<HH", 2, 0)))
    e.append((273, 4, 1, struct.pack("<I", data_off)))
    e.append((277, 3, 1, struct.pack("<HH", 3, 0)))
    e.append((278, 3, 1, struct.pack("<HH", H, 0)))
    e.append((279, 4, 1, struct.pack("<I", len(data))))
    e.append((284, 3, 1, struct.pack("<HH", 1, 0)))
    e.append((305, 2, 4, b"py\0\0"))
    if t_exif:
        e.append((34665, 4, 1, struct.pack("<I", exif)))
    assert len(e) == n0
    out = bytearray(b"II*\0" + struct.pack("<I", ifd0))
    out += struct.pack("<H", n0)
    for tag, typ, count, val in e:
        out += struct.pack("<HHI", tag, typ, count) + val
    out += struct.pack("<I", 0)
    if t_exif:
        out += struct.pack("<H", 1)
        out += struct.pack("<HHII", 33434, 5, 1, rat_off)
        out += struct.pack("<I", 0)
    out += struct.pack("<HHH", 8, 8, 8)
    out += struct.pack("<II", *rational(t_exif or 1))
    assert len(out) == data_off, (len(out), data_off)
    out += data
    open(path, "wb").write(out)


def main():
    d, args = sys.argv[1], sys.argv[2:]
    if args[0] == "--no-exif":
        tiff(f"{d}/p0.tif", float(args[1]), None)
    elif args[0] == "--exif":
        k = args.index("--shot")
        ex, shot = args[1:k], args[k + 1:]
        for i, (a, b) in enumerate(zip(ex, shot)):
            tiff(f"{d}/p{i}.tif", eval(b), eval(a))
    else:
        for i, a in enumerate(args):
            tiff(f"{d}/p{i}.tif", eval(a), eval(a))


main()
