# SPDX-License-Identifier: MIT
"""Render a glint Blender export with Blender itself and compare.

  blender --background --factory-startup --python blender_check.py -- \\
      EXPORT.py MATERIAL.json OUT.json

Runs inside Blender (Cycles).  The export's build_material() makes the
material; a unit sphere of it is rendered by an orthographic camera under
a sun (a delta light of irradiance 1) and a black world, direct light
only, so a pixel on the sphere with normal n shows f(o, l) (n.l) with o
the view and l the sun's direction: every pixel is one evaluation of the
BRDF Blender renders.  Three sun directions.  Each pixel is compared with

- the export's node model written from its equations (Cycles's Beckmann
  or GGX glossy, D G1 G1 / (4 cos cos), weighed by the Fresnel node's dielectric
  F at the view direction, plus the Lambertian diffuse): this checks that
  the model the export was fitted with is what Blender renders;
- glint's Torrance-Sparrow (Beckmann, V-cavity, exact Fresnel at o.h),
  when the material is of that model.

OUT.json: the relative RMS differences over the lit pixels.
"""
import importlib.util
import json
import math
import os
import sys
import tempfile

import bpy
from mathutils import Vector

# The equations as check_export.py writes them (its dielectric Fresnel
# term and Cycles's Beckmann G1).
sys.dont_write_bytecode = True  # nothing left in the checkout
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_export import cycles_g1 as beckmann_g1, fresnel  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
export_path, material_path, out_path = args

spec = importlib.util.spec_from_file_location("glint_export", export_path)
exp = importlib.util.module_from_spec(spec)
spec.loader.exec_module(exp)
mat = exp.build_material()

ts = json.load(open(material_path))
ts = ts.get("material", ts)


def beckmann_d(nh, alpha):
    c2 = nh * nh
    return math.exp(-(1 - c2) / c2 / (alpha * alpha)) / \
        (math.pi * alpha * alpha * c2 * c2)


def ggx_d(nh, alpha):
    c2 = nh * nh
    return 1 / (math.pi * alpha * alpha *
                ((1 - c2) / (alpha * alpha) + c2) ** 2)


def cycles_g1(alpha, c):
    if exp.DISTRIBUTION == "GGX":
        return 2 / (1 + math.sqrt(1 + alpha * alpha * (1 / (c * c) - 1)))
    return beckmann_g1(alpha, c)


def nodes_f(no, ni, nh, oh):
    alpha = exp.ROUGHNESS ** 2
    d = ggx_d if exp.DISTRIBUTION == "GGX" else beckmann_d
    s = d(nh, alpha) * cycles_g1(alpha, no) * \
        cycles_g1(alpha, ni) / (4 * no * ni) * fresnel(no, exp.IOR)
    return [exp.DIFFUSE[c] / math.pi + exp.SPECULAR[c] * s for c in range(3)]


def glint_f(no, ni, nh, oh):
    m = ts["roughness"]
    g = min(1.0, 2 * nh * no / oh, 2 * nh * ni / oh)
    s = beckmann_d(nh, m) * g * fresnel(oh, ts["ior"]) / (4 * ni * no)
    return [ts["diffuse"][c] / math.pi + ts["specular"][c] * s
            for c in range(3)]


scene = bpy.context.scene
for obj in list(scene.objects):
    bpy.data.objects.remove(obj, do_unlink=True)
bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0)
sphere = bpy.context.active_object
bpy.ops.object.shade_smooth()
sphere.data.materials.append(mat)
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
cam.data.type = "ORTHO"
cam.data.ortho_scale = 2.2
cam.location = (0.0, 0.0, 10.0)
scene.collection.objects.link(cam)
scene.camera = cam
world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 1.0
sun.data.angle = 0.0
scene.collection.objects.link(sun)

W = 128
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
for layer in scene.view_layers:
    layer.cycles.use_denoising = False
scene.cycles.max_bounces = 0
scene.cycles.filter_width = 0.01
scene.cycles.seed = 1
scene.render.resolution_x = scene.render.resolution_y = W
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0

sums = {"nodes": [0.0, 0.0], "glint": [0.0, 0.0]}
# glint's BRDF is written here for Torrance-Sparrow only.
keys = [("nodes", nodes_f)]
if ts["model"] == "torrance-sparrow":
    keys.append(("glint", glint_f))
renders = []
tmp = tempfile.mkdtemp()
for k, (theta, phi) in enumerate([(25, 0), (50, 120), (70, 240)]):
    t, p = math.radians(theta), math.radians(phi)
    L = Vector((math.sin(t) * math.cos(p), math.sin(t) * math.sin(p),
                math.cos(t)))
    sun.rotation_euler = L.to_track_quat("Z", "Y").to_euler()
    path = os.path.join(tmp, "sun%d.exr" % k)
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    px = list(img.pixels)
    one = {"nodes": [0.0, 0.0], "glint": [0.0, 0.0], "pixels": 0}
    for j in range(W):
        y = ((j + 0.5) / W * 2 - 1) * 1.1  # rows bottom-up
        for i in range(W):
            x = ((i + 0.5) / W * 2 - 1) * 1.1
            r2 = x * x + y * y
            if r2 > 0.9 ** 2:
                continue
            n = Vector((x, y, math.sqrt(1 - r2)))
            o = Vector((0.0, 0.0, 1.0))
            no, ni = n.dot(o), n.dot(L)
            if no < 0.2 or ni < 0.2:
                continue  # the tessellated terminator, the silhouette
            h = (o + L).normalized()
            args_ = (no, ni, n.dot(h), o.dot(h))
            got = px[4 * (j * W + i):4 * (j * W + i) + 3]
            for key, f in keys:
                e = [v * ni for v in f(*args_)]
                for c in range(3):
                    d = (got[c] - e[c]) ** 2
                    one[key][0] += d
                    one[key][1] += e[c] ** 2
                    sums[key][0] += d
                    sums[key][1] += e[c] ** 2
            one["pixels"] += 1
    renders.append({"sun_theta_deg": theta, "sun_phi_deg": phi,
                    "pixels": one["pixels"],
                    "render_vs_nodes": math.sqrt(one["nodes"][0] /
                                                 one["nodes"][1]),
                    "render_vs_glint": math.sqrt(one["glint"][0] /
                                                 one["glint"][1])
                    if one["glint"][1] else None})
    bpy.data.images.remove(img)
    os.remove(path)
os.rmdir(tmp)
res = {"blender": bpy.app.version_string, "renders": renders,
       "render_vs_nodes": math.sqrt(sums["nodes"][0] / sums["nodes"][1]),
       "render_vs_glint": math.sqrt(sums["glint"][0] / sums["glint"][1])
       if sums["glint"][1] else None}
json.dump(res, open(out_path, "w"), indent=1)
print("glint-check:", json.dumps(res))
