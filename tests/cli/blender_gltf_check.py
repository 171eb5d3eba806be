"""Blender's own glTF importer on a glint export: what it brings in, as
JSON (run by tests/cli/test_gltf.sh).

usage: blender --background --factory-startup --python blender_gltf_check.py
       -- FILE.gltf OUT.json
"""
import json
import sys

import bpy
import numpy

# Debian 12's Blender 3.4 importer calls numpy.bool, which Debian 12's
# numpy 1.24 no longer has (the builtin it aliased).
if not hasattr(numpy, "bool"):
    numpy.bool = bool

src, out = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=src)
res = {"blender": bpy.app.version_string, "objects": [], "materials": []}
for o in bpy.data.objects:
    d = {"name": o.name, "type": o.type}
    if o.type == "MESH":
        d["vertices"] = len(o.data.vertices)
        d["faces"] = len(o.data.polygons)
        d["radius"] = [min(v.co.length for v in o.data.vertices),
                       max(v.co.length for v in o.data.vertices)]
        d["materials"] = [m.name for m in o.data.materials if m]
    res["objects"].append(d)
for m in bpy.data.materials:
    d = {"name": m.name, "nodes": []}
    for n in m.node_tree.nodes if m.node_tree else []:
        d["nodes"].append(n.type)
        if n.type != "BSDF_PRINCIPLED":
            continue
        for k in ("Base Color", "Roughness", "IOR", "Metallic",
                  "Transmission"):
            v = n.inputs[k].default_value
            d[k] = list(v) if hasattr(v, "__len__") else v
        d["linked"] = [i.name for i in n.inputs if i.is_linked]
    res["materials"].append(d)
json.dump(res, open(out, "w"), indent=1)
