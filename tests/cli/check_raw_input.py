#!/usr/bin/env python3
"""glint hdr of another writer's raw files against glint's merge of the
same camera values (both converted to PFM by glint convert):

  check_raw_input.py REF.pfm OTHER.pfm OTHER_HDR.json SCALE XSHIFT TOL \
      [NEUTRAL_CM]

OTHER's pixel (x, y) holds the values of REF's (x + XSHIFT, y) multiplied
by SCALE and, when hdr.json reports a colour matrix M, turned by it:
OTHER = SCALE * M * REF.  Over the pixels valid in both, the median of
each channel's ratio OTHER / prediction must be within TOL of 1 and its
interquartile range within 2 TOL (the merges' noise and clipping differ a
little: their white levels differ).  With NEUTRAL_CM (a DNG ColorMatrix1,
nine comma-separated XYZ -> camera values), the camera's response to D65
white, CM x XYZ(D65), must come out of M grey: equal channels within
TOL, the D65 white balance the file's matrix implies."""
import array
import json
import sys


def pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        a = array.array("f")
        a.frombytes(f.read())
    if scale > 0:
        a.byteswap()
    assert kind == b"PF" and len(a) == 3 * w * h, (kind, len(a), w, h)
    return w, h, a


def main():
    ref_path, other_path, json_path = sys.argv[1:4]
    scale, xshift, tol = float(sys.argv[4]), int(sys.argv[5]), float(sys.argv[6])
    info = json.load(open(json_path))["input"]
    m = info["matrix"] or [1, 0, 0, 0, 1, 0, 0, 0, 1]
    rw, rh, ref = pfm(ref_path)
    ow, oh, other = pfm(other_path)
    assert oh == rh and ow == rw - xshift, (ow, oh, rw, rh)
    ratios = [[], [], []]
    for y in range(oh):
        for x in range(ow):
            r = ref[3 * (y * rw + x + xshift):][:3]
            o = other[3 * (y * ow + x):][:3]
            if min(r) <= 0 or min(o) <= 0:
                continue
            for c in range(3):
                p = scale * sum(m[3 * c + j] * r[j] for j in range(3))
                if p > 0:
                    ratios[c].append(o[c] / p)
    bad = 0
    for c in range(3):
        q = sorted(ratios[c])
        med = q[len(q) // 2]
        iqr = q[3 * len(q) // 4] - q[len(q) // 4]
        ok = abs(med - 1) <= tol and iqr <= 2 * tol
        bad += not ok
        print(f"{'RGB'[c]}: {len(q)} pixels, ratio to the prediction: "
              f"median {med:.5f}, interquartile range {iqr:.5f} "
              f"({'ok' if ok else 'FAIL'})")
    if len(sys.argv) > 7:
        cm = [float(v) for v in sys.argv[7].split(",")]
        d65 = [0.95047, 1.0, 1.08883]
        cam = [sum(cm[3 * i + j] * d65[j] for j in range(3)) for i in range(3)]
        rgb = [sum(m[3 * i + j] * cam[j] for j in range(3)) for i in range(3)]
        spread = (max(rgb) - min(rgb)) / (sum(rgb) / 3)
        ok = spread <= tol
        bad += not ok
        print(f"D65 white through the file's matrix: RGB "
              f"{rgb[0]:.4f} {rgb[1]:.4f} {rgb[2]:.4f}, spread {spread:.5f} "
              f"({'ok' if ok else 'FAIL'})")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
