#!/usr/bin/env python3
"""Raw files of other cameras' formats, written from a raw frame's values
(a 16-bit PGM as `dcraw -D -4` decodes them), for glint hdr's raw input:

  raw_writers.py mrw IN.pgm OUT.mrw EXPOSURE_S ISO
      Minolta MRW as the DiMAGE 7Hi writes it (PRD, WBG and TTW blocks,
      big-endian, unpacked 16-bit samples; its TTW TIFF holds Make, Model
      and an EXIF directory with ExposureTime and ISOSpeedRatings): the
      values less 64 (the camera's black level is 0), RGGB.  Written here
      from the format's layout (no packaged tool writes camera raws);
      LibRaw and dcraw read it by the camera's entry in their tables.
  raw_writers.py dng IN.pgm OUT.dng EXPOSURE_S ISO [--no-exposure]
      A DNG written by tifffile (python3-tifffile), not by glint: the
      values scaled to a 14-bit range (x 3) with black level 256 and
      white level 12000, the first column dropped (a GRBG mosaic),
      ColorMatrix1 a real camera's (Adobe's for the Canon EOS 5D Mark
      II), AsShotNeutral of tungsten light, ExposureTime and ISO in IFD 0.
  raw_writers.py linear-dng IN.tiff OUT.dng EXPOSURE_S 0
      A linear (LinearRaw, demosaiced RGB) DNG by tifffile from a 16-bit
      RGB TIFF's samples (dcraw -4 -T's), white level 65535, no colour
      matrix, ExposureTime in IFD 0.
"""
import struct
import sys

CM_5D2 = [4716, 603, -830, -7798, 15474, 2480, -1496, 1937, 6651]


def read_pgm(path):
    data = open(path, "rb").read()
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            while data[pos:pos + 1] not in (b"\n", b""):
                pos += 1
            continue
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(data[start:pos])
    assert fields[0] == b"P5" and int(fields[3]) == 65535, fields
    w, h = int(fields[1]), int(fields[2])
    pix = struct.unpack(">%dH" % (w * h), data[pos + 1:pos + 1 + 2 * w * h])
    return w, h, pix


def rational(x):
    den = 1000000
    return int(round(x * den)), den


def ttw_tiff(exposure, iso):
    """A big-endian TIFF header block: IFD0 (Make, Model, ExifIFD) and an
    EXIF IFD (ExposureTime, ISOSpeedRatings); offsets from its start."""
    make, model = b"Minolta Co., Ltd.\0", b"DiMAGE 7Hi\0"
    ifd0_n, exif_n = 3, 2
    ifd0 = 8
    exif = ifd0 + 2 + 12 * ifd0_n + 4
    extra = exif + 2 + 12 * exif_n + 4
    make_off = extra
    model_off = make_off + len(make)
    rat_off = model_off + len(model)
    out = bytearray(b"MM\0\x2a" + struct.pack(">I", ifd0))
    out += struct.pack(">H", ifd0_n)
    out += struct.pack(">HHII", 271, 2, len(make), make_off)
    out += struct.pack(">HHII", 272, 2, len(model), model_off)
    out += struct.pack(">HHII", 34665, 4, 1, exif)
    out += struct.pack(">I", 0)
    out += struct.pack(">H", exif_n)
    out += struct.pack(">HHII", 33434, 5, 1, rat_off)
    out += struct.pack(">HHIHH", 34855, 3, 1, iso, 0)
    out += struct.pack(">I", 0)
    out += make + model + struct.pack(">II", *rational(exposure))
    return bytes(out)


def block(tag, payload):
    return b"\0" + tag + struct.pack(">I", len(payload)) + payload


def write_mrw(pgm, out, exposure, iso):
    w, h, pix = read_pgm(pgm)
    prd = (b"21810002" + struct.pack(">HHHH", h, w, h, w) +
           bytes([16, 12, 0x59, 0]) + struct.pack(">HH", 0, 1))
    wbg = bytes(4) + struct.pack(">HHHH", 512, 256, 256, 512)
    head = block(b"PRD", prd) + block(b"WBG", wbg) + \
        block(b"TTW", ttw_tiff(exposure, iso))
    with open(out, "wb") as f:
        f.write(b"\0MRM" + struct.pack(">I", len(head)) + head)
        f.write(struct.pack(">%dH" % (w * h), *(max(v - 64, 0) for v in pix)))


def write_dng(pgm, out, exposure, iso, with_exposure):
    import numpy as np
    import tifffile

    w, h, pix = read_pgm(pgm)
    raw = np.array(pix, dtype=np.int64).reshape(h, w)[:, 1:]
    raw = np.clip((raw - 64) * 3 + 256, 0, 16383).astype(np.uint16)
    tags = [
        (50706, "B", 4, (1, 4, 0, 0), True),      # DNGVersion
        (50707, "B", 4, (1, 1, 0, 0), True),      # DNGBackwardVersion
        (50708, "s", 0, "Canon EOS 5D Mark II", True),
        (271, "s", 0, "Canon", True),
        (272, "s", 0, "Canon EOS 5D Mark II", True),
        (33421, "H", 2, (2, 2), True),            # CFARepeatPatternDim
        (33422, "B", 4, (1, 0, 2, 1), True),      # CFAPattern: GRBG
        (50714, "H", 1, (256,), True),            # BlackLevel
        (50717, "H", 1, (12000,), True),          # WhiteLevel
        (50721, "2i", 9, sum(([v, 10000] for v in CM_5D2), []), True),
        (50778, "H", 1, (21,), True),             # CalibrationIlluminant1
        (50728, "2I", 3, (450, 1000, 1000, 1000, 800, 1000), True),
    ]
    if with_exposure:
        tags.append((33434, "2I", 1, rational(exposure), True))
    tifffile.imwrite(out, raw, photometric=32803, extratags=tags,
                     subfiletype=0, software="tifffile")


def write_linear_dng(tiff, out, exposure):
    import tifffile

    rgb = tifffile.imread(tiff)
    tags = [
        (50706, "B", 4, (1, 4, 0, 0), True),      # DNGVersion
        (50708, "s", 0, "tifffile linear", True),
        (50717, "H", 1, (65535,), True),          # WhiteLevel
        (33434, "2I", 1, rational(exposure), True),
    ]
    tifffile.imwrite(out, rgb, photometric=34892, extratags=tags,
                     subfiletype=0, software="tifffile")


def main():
    kind, pgm, out = sys.argv[1:4]
    exposure, iso = float(sys.argv[4]), int(sys.argv[5])
    if kind == "mrw":
        write_mrw(pgm, out, exposure, iso)
    elif kind == "linear-dng":
        write_linear_dng(pgm, out, exposure)
    else:
        write_dng(pgm, out, exposure, iso, "--no-exposure" not in sys.argv)


if __name__ == "__main__":
    main()
