#!/usr/bin/env python3
"""Check a capture session on disk: session.json's status, every listed
frame present and whole (PNG through IEND, CRCs right, metadata chunk),
sidecar JSON matching, no temporary files left.
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


def main():
    d, status = sys.argv[1], sys.argv[2]
    want_min = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    s = json.load(open(os.path.join(d, "session.json")))
    assert s["status"] == status, f"status {s['status']}, expected {status}"
    if status == "incomplete":
        assert s.get("error"), "an incomplete session must say why"
    frames = s["frames"]
    assert len(frames) >= want_min, f"{len(frames)} frames < {want_min}"
    on_disk = sorted(f for f in os.listdir(d) if f.startswith("frame-") and f.endswith(".png"))
    assert on_disk == sorted(f["file"] for f in frames), f"listed {frames} vs on disk {on_disk}"
    for f in frames:
        p = os.path.join(d, f["file"])
        chunks = png_chunks(p)
        ihdr = chunks[0][1]
        w, h, depth = struct.unpack(">IIB", ihdr[:9])
        assert depth == 16, f"{p}: {depth}-bit"
        meta = [b for k, b in chunks if k == b"iTXt" and b.startswith(b"glint:frame\0")]
        assert meta, f"{p}: no glint:frame chunk"
        side = json.load(open(p[:-4] + ".json"))
        assert side["width"] == w and side["height"] == h, f"{p}: size vs sidecar"
        assert abs(side["exposure_s"] - f["exposure_s"]) < 1e-12
    junk = [f for f in os.listdir(d) if ".tmp." in f]
    assert not junk, f"temporary files left: {junk}"
    json.load(open(os.path.join(d, "rig.json")))
    assert os.path.getsize(os.path.join(d, "log.txt")) > 0
    print(f"{d}: {status}, {len(frames)} frames whole")


if __name__ == "__main__":
    try:
        main()
    except (AssertionError, ValueError, OSError, KeyError) as e:
        print(f"check_session: {e}", file=sys.stderr)
        sys.exit(1)
