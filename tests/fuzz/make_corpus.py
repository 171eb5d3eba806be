#!/usr/bin/env python3
# The hand-made seeds of corpus/tiff and corpus/exif: minimal little-endian
# TIFFs (uncompressed, one strip; 16-bit RGB, grey, RGBA, float, and 8-bit
# with an EXIF directory) and stb/python.jpg with an EXIF APP1 segment.
#   make_corpus.py [tests/fuzz]
import struct, sys
def tiff(w, h, bps, spp, fmt, pixels, exposure=None):
    # fmt: 1 uint, 3 float
    entries = []
    def e(tag, typ, count, value): entries.append((tag, typ, count, value))
    entries_n = 10 + (1 if exposure else 0)
    # layout: header | pixels | ifd | extra (bps array, exif ifd)
    pix = pixels
    ifd_off = 8 + len(pix)
    ifd_off += ifd_off & 1
    ifd_size = 2 + 12 * entries_n + 4
    extra_off = ifd_off + ifd_size
    extra = b''
    bps_val = None
    if spp > 2:
        bps_off = extra_off + len(extra); extra += struct.pack('<%dH' % spp, *([bps]*spp))
        bps_val = bps_off
    exif_off = None
    if exposure:
        exif_off = extra_off + len(extra)
        rat_off = exif_off + 2 + 12 + 4
        extra += struct.pack('<HHHII', 1, 33434, 5, 1, rat_off) + struct.pack('<I', 0)
        extra += struct.pack('<II', *exposure)
    e(256, 4, 1, w); e(257, 4, 1, h)
    e(258, 3, spp, bps_val if spp > 2 else bps)
    e(259, 3, 1, 1); e(262, 3, 1, 2 if spp >= 3 else 1)
    e(273, 4, 1, 8); e(277, 3, 1, spp); e(278, 4, 1, h)
    e(279, 4, 1, len(pix)); e(339, 3, 1, fmt)
    if exposure: e(34665, 4, 1, exif_off)
    entries.sort()
    ifd = struct.pack('<H', len(entries))
    for tag, typ, count, value in entries:
        if typ == 3 and count == 1: ifd += struct.pack('<HHIHH', tag, typ, count, value, 0)
        else: ifd += struct.pack('<HHII', tag, typ, count, value)
    ifd += struct.pack('<I', 0)
    out = b'II*\0' + struct.pack('<I', ifd_off) + pix
    out += b'\0' * (ifd_off - len(out))
    return out + ifd + extra

def exif_jpeg(jpeg, exposure):
    """jpeg with an APP1 EXIF segment holding ExposureTime only."""
    t = b'II*\0' + struct.pack('<I', 8)
    t += struct.pack('<H', 1) + struct.pack('<HHII', 34665, 4, 1, 26) + struct.pack('<I', 0)
    t += struct.pack('<H', 1) + struct.pack('<HHII', 33434, 5, 1, 44) + struct.pack('<I', 0)
    t += struct.pack('<II', *exposure)
    app = b'Exif\0\0' + t
    return jpeg[:2] + b'\xff\xe1' + struct.pack('>H', len(app) + 2) + app + jpeg[2:]

here = sys.argv[1] if len(sys.argv) > 1 else '.'
w, h = 3, 2
for name, data in [
        ('rgb16.tif', tiff(w, h, 16, 3, 1, struct.pack('<18H', *range(0, 65535, 3641)))),
        ('grey16.tif', tiff(w, h, 16, 1, 1, struct.pack('<6H', *range(0, 60000, 10000)))),
        ('rgb8.tif', tiff(w, h, 8, 3, 1, bytes(range(0, 180, 10)), exposure=(1, 250))),
        ('rgbf.tif', tiff(w, h, 32, 3, 3, struct.pack('<18f', *[0.1 * i for i in range(18)]))),
        ('rgba16.tif', tiff(w, h, 16, 4, 1, struct.pack('<24H', *range(0, 24000, 1000))))]:
    open(here + '/corpus/tiff/' + name, 'wb').write(data)
jpeg = open(here + '/corpus/stb/python.jpg', 'rb').read()
open(here + '/corpus/exif/exif.jpg', 'wb').write(exif_jpeg(jpeg, (1, 125)))
