#!/usr/bin/env python3
"""Check a capture session on disk: session.json's status, every listed
frame present and whole (a DNG: its IFD, every strip inside the file, the
glint metadata, EXIF's exposure time; or an older session's PNG: through
IEND, CRCs right, metadata chunk), sidecar JSON matching, no temporary
files left; a complete session's bracket counts (frames kept as listed,
unclipped frames superseded, metering frames).
A session that is not complete must name the stage that stopped it and
why.
usage: check_session.py DIR STATUS [MIN_FRAMES]"""
import json
import os
import struct
import sys
import zlib


def png_chunks(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, chunks = 8, []
    while pos < len(data):
        if pos + 8 > len(data):
            raise ValueError(f"{path}: truncated chunk header")
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        crc = data[pos + 8 + n:pos + 12 + n]
        if len(body) != n or len(crc) != 4:
            raise ValueError(f"{path}: truncated {kind!r}")
        if struct.unpack(">I", crc)[0] != zlib.crc32(kind + body):
            raise ValueError(f"{path}: bad CRC in {kind!r}")
        chunks.append((kind, body))
        pos += 12 + n
    if not chunks or chunks[-1][0] != b"IEND":
        raise ValueError(f"{path}: no IEND")
    return chunks


TIFF_SIZES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 7: 1, 10: 8, 12: 8, 13: 4, 16: 8}


def tiff_ifd(data, off):
    """A little-endian TIFF IFD at off: {tag: [values]}."""
    n, = struct.unpack("<H", data[off:off + 2])
    tags = {}
    for k in range(n):
        e = data[off + 2 + 12 * k:off + 14 + 12 * k]
        if len(e) < 12:
            raise ValueError("truncated IFD")
        tag, typ, count = struct.unpack("<HHI", e[:8])
        size = TIFF_SIZES.get(typ, 1) * count
        raw = e[8:12] if size <= 4 else \
            data[struct.unpack("<I", e[8:12])[0]:][:size]
        if len(raw) < size:
            raise ValueError(f"tag {tag}: values past the end of the file")
        if typ == 3:
            vals = list(struct.unpack("<%dH" % count, raw[:size]))
        elif typ in (4, 13):
            vals = list(struct.unpack("<%dI" % count, raw[:size]))
        elif typ in (5, 10):
            q = struct.unpack("<%d%s" % (2 * count, "I" if typ == 5 else "i"),
                              raw[:size])
            vals = [q[2 * i] / q[2 * i + 1] for i in range(count)]
        else:
            vals = raw[:size]
        tags[tag] = vals
    return tags


def dng_frame(path):
    """(width, height, metadata bytes, EXIF exposure time) of a whole DNG."""
    data = open(path, "rb").read()
    if data[:4] != b"II*\0":
        raise ValueError(f"{path}: not a little-endian TIFF/DNG")
    t = tiff_ifd(data, struct.unpack("<I", data[4:8])[0])
    w, h = t[256][0], t[257][0]
    spp = t.get(277, [1])[0]
    assert t[258][0] == 16, f"{path}: {t[258]}-bit"
    assert 50706 in t, f"{path}: no DNGVersion"
    offs, counts = t[273], t[279]
    assert sum(counts) == w * h * spp * 2, f"{path}: strips hold {sum(counts)} bytes"
    for o, c in zip(offs, counts):
        if o + c > len(data):
            raise ValueError(f"{path}: a strip runs past the end (truncated)")
    exif = tiff_ifd(data, t[34665][0])
    return w, h, bytes(t[270]).rstrip(b"\0"), exif[33434][0]


def main():
    d, status = sys.argv[1], sys.argv[2]
    want_min = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    s = json.load(open(os.path.join(d, "session.json")))
    assert s["status"] == status, f"status {s['status']}, expected {status}"
    if status in ("incomplete", "failed"):
        assert s.get("error"), f"a session {status} must say why"
        assert s.get("stage"), f"a session {status} must name its stage"
    frames = s["frames"]
    assert len(frames) >= want_min, f"{len(frames)} frames < {want_min}"
    on_disk = sorted(f for f in os.listdir(d) if f.startswith("frame-") and
                     f.endswith((".dng", ".png")))
    assert on_disk == sorted(f["file"] for f in frames), f"listed {frames} vs on disk {on_disk}"
    for f in frames:
        p = os.path.join(d, f["file"])
        if p.endswith(".dng"):
            w, h, meta, t = dng_frame(p)
            assert json.loads(meta)["exposure_s"] == f["exposure_s"], p
            assert abs(t - f["exposure_s"]) <= 1e-6 * f["exposure_s"], \
                f"{p}: EXIF ExposureTime {t} vs {f['exposure_s']}"
        else:
            chunks = png_chunks(p)
            ihdr = chunks[0][1]
            w, h, depth = struct.unpack(">IIB", ihdr[:9])
            assert depth == 16, f"{p}: {depth}-bit"
            meta = [b for k, b in chunks
                    if k == b"iTXt" and b.startswith(b"glint:frame\0")]
            assert meta, f"{p}: no glint:frame chunk"
        side = json.load(open(p[:-4] + ".json"))
        assert side["width"] == w and side["height"] == h, f"{p}: size vs sidecar"
        assert abs(side["exposure_s"] - f["exposure_s"]) < 1e-12
    junk = [f for f in os.listdir(d) if ".tmp." in f]
    assert not junk, f"temporary files left: {junk}"
    json.load(open(os.path.join(d, "rig.json")))
    assert os.path.getsize(os.path.join(d, "log.txt")) > 0
    if status == "complete":
        b = s["bracket"]
        assert b["frames"] == len(frames), f"bracket says {b['frames']} frames, {len(frames)} listed"
        assert b["unclipped_superseded"] >= 0 and b["metering_frames"] >= 0, b
        assert not b["truncated"], "a complete session's bracket was cut short"
        # complete: every output it promises is there, whole
        for name in s.get("files", []):
            p = os.path.join(d, name)
            assert os.path.isfile(p) and os.path.getsize(p) > 0, \
                f"{name}: listed as written, missing or empty"
    print(f"{d}: {status}, {len(frames)} frames whole")


if __name__ == "__main__":
    try:
        main()
    except (AssertionError, ValueError, OSError, KeyError) as e:
        print(f"check_session: {e}", file=sys.stderr)
        sys.exit(1)
