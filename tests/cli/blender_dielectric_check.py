# SPDX-License-Identifier: MIT
"""Render a glint dielectric (quartz) Blender export and compare.

  blender --background --factory-startup --python blender_dielectric_check.py \\
      -- EXPORT.py MATERIAL.json OUT.json

Runs inside Blender (Cycles).  The export's build_material() makes the
material (a sharp Glass BSDF and a Volume Absorption); a sphere of the
export's DIAMETER is seen by an orthographic camera in a uniform white
world.  A ray through the sphere's centre meets both interfaces at normal
incidence and crosses one diameter inside, so the centre's radiance is,
with R = ((n - 1)/(n + 1))^2 and T the material's transmission per
diameter (Beer-Lambert),

    R + (1 - R)^2 (T + R T^2) / (1 - R^2 T^2)

(the front reflection, light from behind, light entering at the front and
reflected at the back; with every internal bounce).  The mean over a
small patch at the centre, per channel, against that: OUT.json.
"""
import importlib.util
import json
import math
import os
import sys
import tempfile

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
export_path, material_path, out_path = args

spec = importlib.util.spec_from_file_location("glint_export", export_path)
exp = importlib.util.module_from_spec(spec)
spec.loader.exec_module(exp)
mat = exp.build_material()
truth = json.load(open(material_path))
truth = truth.get("material", truth)

scene = bpy.data.scenes.new("glint-dielectric-check")
bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128,
                                     radius=exp.DIAMETER / 2)
sphere = bpy.context.active_object
bpy.ops.object.shade_smooth()
sphere.data.materials.append(mat)
for c in list(sphere.users_collection):
    c.objects.unlink(sphere)
scene.collection.objects.link(sphere)
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
cam.data.type = "ORTHO"
cam.data.ortho_scale = 1.2 * exp.DIAMETER
cam.location = (0.0, -10 * exp.DIAMETER, 0.0)
cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
scene.collection.objects.link(cam)
scene.camera = cam
world = bpy.data.worlds.new("white")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (
    1.0, 1.0, 1.0, 1.0)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 256
scene.cycles.use_denoising = False
for layer in scene.view_layers:
    layer.cycles.use_denoising = False
scene.cycles.max_bounces = scene.cycles.transmission_bounces = 32
scene.cycles.glossy_bounces = 32
scene.cycles.transparent_max_bounces = 32
scene.cycles.caustics_reflective = scene.cycles.caustics_refractive = True
scene.cycles.sample_clamp_direct = scene.cycles.sample_clamp_indirect = 0
W = 41
scene.render.resolution_x = scene.render.resolution_y = W
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"

tmp = tempfile.mkdtemp()
path = os.path.join(tmp, "centre.exr")
scene.render.filepath = path
bpy.ops.render.render(write_still=True, scene=scene.name)
img = bpy.data.images.load(path)
px = list(img.pixels)
half = 2  # a 5 x 5 patch: within 0.06 radii of the centre
mean = [0.0, 0.0, 0.0]
n = 0
for y in range(W // 2 - half, W // 2 + half + 1):
    for x in range(W // 2 - half, W // 2 + half + 1):
        for c in range(3):
            mean[c] += px[4 * (y * W + x) + c]
        n += 1
mean = [m / n for m in mean]

ior = truth["ior"]
R = ((ior - 1) / (ior + 1)) ** 2
want = [R + (1 - R) ** 2 * (t + R * t * t) / (1 - R * R * t * t)
        for t in truth["transmission"]]
json.dump({"blender": bpy.app.version_string, "centre": mean,
           "expected": want,
           "relative_error": [abs(mean[c] - want[c]) / want[c]
                              for c in range(3)]},
          open(out_path, "w"), indent=1)
