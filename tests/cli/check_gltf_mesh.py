#!/usr/bin/env python3
"""The sphere a glint glTF export carries: its buffer decoded from the data
URI, every vertex on the sphere of the stated diameter with its outward unit
normal, every triangle counter-clockwise seen from outside (glTF's front
face), the accessors' counts, bounds and views consistent, the one node
naming the mesh, the mesh the material, the material the expected name.

usage: check_gltf_mesh.py FILE.gltf NAME DIAMETER_M
"""
import base64
import json
import math
import struct
import sys

path, name, diameter = sys.argv[1], sys.argv[2], float(sys.argv[3])
doc = json.load(open(path))
assert doc["asset"]["version"] == "2.0", doc["asset"]
(buf,) = doc["buffers"]
head = "data:application/octet-stream;base64,"
assert buf["uri"].startswith(head), buf["uri"][:40]
data = base64.b64decode(buf["uri"][len(head):], validate=True)
assert len(data) == buf["byteLength"], (len(data), buf["byteLength"])

scene = doc["scenes"][doc["scene"]]
(node,) = [doc["nodes"][k] for k in scene["nodes"]]
mesh = doc["meshes"][node["mesh"]]
(prim,) = mesh["primitives"]
mat = doc["materials"][prim["material"]]
assert mat["name"] == name == node["name"], (mat["name"], node["name"], name)
assert prim.get("mode", 4) == 4, prim


def read(acc_index, fmt, width):
    acc = doc["accessors"][acc_index]
    view = doc["bufferViews"][acc["bufferView"]]
    off = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    n = acc["count"] * width
    size = struct.calcsize("<" + fmt)
    assert n * size <= view["byteLength"], (acc, view)
    vals = struct.unpack_from("<%d%s" % (n, fmt), data, off)
    return acc, [vals[k:k + width] for k in range(0, n, width)]


pacc, pos = read(prim["attributes"]["POSITION"], "f", 3)
_, nrm = read(prim["attributes"]["NORMAL"], "f", 3)
iacc, idx = read(prim["indices"], "H" if
                 doc["accessors"][prim["indices"]]["componentType"] == 5123
                 else "I", 1)
idx = [i[0] for i in idx]
r = diameter / 2
for c in range(3):
    assert pacc["min"][c] == min(p[c] for p in pos), ("min", c)
    assert pacc["max"][c] == max(p[c] for p in pos), ("max", c)
for p, n in zip(pos, nrm):
    assert abs(math.hypot(*p) - r) < 1e-6 * r + 1e-7, (p, r)
    assert abs(math.hypot(*n) - 1) < 1e-6, n
    assert all(abs(p[c] / r - n[c]) < 1e-5 for c in range(3)), (p, n)
assert len(idx) % 3 == 0 and max(idx) < len(pos), (len(idx), max(idx))
area = 0
for k in range(0, len(idx), 3):
    a, b, c = (pos[i] for i in idx[k:k + 3])
    u = [b[j] - a[j] for j in range(3)]
    v = [c[j] - a[j] for j in range(3)]
    x = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
         u[0] * v[1] - u[1] * v[0])
    m = [(a[j] + b[j] + c[j]) / 3 for j in range(3)]
    out = sum(x[j] * m[j] for j in range(3))
    assert out > 0, ("a triangle faces inward or is degenerate", k // 3)
    area += math.hypot(*x) / 2
# The triangles close the sphere: their area within 1 % of 4 pi r^2.
assert abs(area / (4 * math.pi * r * r) - 1) < 0.01, area
print(f"{path}: {len(pos)} vertices, {len(idx) // 3} triangles, radius "
      f"{r} m, outward, closed (area {area / (4 * math.pi * r * r):.4f} "
      f"of the sphere's), material '{name}'")
