#: The Blender export's script after its constants (NAME, KIND, IOR, ...),
#: which glint writes above it (export/blender.c). Embedded at build time
#: by scripts/embed-text, which drops these '#:' lines.
import math
import os
import sys

import bpy


def build_material(name=NAME):
    """Create (or rebuild) the material NAME in the open file; return it."""
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    if KIND == "dielectric":
        # Cycles: absorption = (1 - Color) * Density per metre.
        glass = nodes.new("ShaderNodeBsdfGlass")
        glass.distribution = "SHARP"
        glass.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        glass.inputs["IOR"].default_value = IOR
        absorb = nodes.new("ShaderNodeVolumeAbsorption")
        absorb.inputs["Color"].default_value = (*ABSORPTION_COLOR, 1.0)
        absorb.inputs["Density"].default_value = DENSITY
        links.new(glass.outputs["BSDF"], out.inputs["Surface"])
        links.new(absorb.outputs["Volume"], out.inputs["Volume"])
        glass.location, absorb.location = (-300, 100), (-300, -100)
        return mat
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*DIFFUSE, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    glossy = nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = DISTRIBUTION
    glossy.inputs["Color"].default_value = (*SPECULAR, 1.0)
    glossy.inputs["Roughness"].default_value = ROUGHNESS
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    fresnel = nodes.new("ShaderNodeFresnel")
    fresnel.inputs["IOR"].default_value = IOR
    mix = nodes.new("ShaderNodeMixShader")
    add = nodes.new("ShaderNodeAddShader")
    links.new(fresnel.outputs["Fac"], mix.inputs["Fac"])
    links.new(black.outputs["BSDF"], mix.inputs[1])
    links.new(glossy.outputs["BSDF"], mix.inputs[2])
    links.new(diffuse.outputs["BSDF"], add.inputs[0])
    links.new(mix.outputs["Shader"], add.inputs[1])
    links.new(add.outputs["Shader"], out.inputs["Surface"])
    for i, n in enumerate((fresnel, black, glossy, diffuse, mix, add, out)):
        n.location = (200 * i - 600, 0)
    return mat


def preview_scene(mat, env=None, samples=64, size=512):
    """A new scene (the open file's scenes are left as they are) with a
    sphere of the material, a camera and light: the environment map env
    (equirectangular) or a sun and a grey sky.  Returns it."""
    import bmesh
    scene = bpy.data.scenes.new("glint-preview")
    mesh = bpy.data.meshes.new("glint-sphere")
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=128, v_segments=64, radius=RADIUS)
    bm.to_mesh(mesh)
    bm.free()
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    mesh.materials.append(mat)
    scene.collection.objects.link(bpy.data.objects.new("sphere", mesh))
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.location = (0.0, -6.0 * RADIUS, 0.0)
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    cam.data.lens = 100
    scene.collection.objects.link(cam)
    scene.camera = cam
    world = bpy.data.worlds.new("glint-preview")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    if env:
        tex = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
        tex.image = bpy.data.images.load(env)
        world.node_tree.links.new(tex.outputs["Color"], bg.inputs["Color"])
    else:
        bg.inputs["Color"].default_value = (0.05, 0.05, 0.05, 1.0)
        sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
        sun.data.energy = 3.0
        sun.rotation_euler = (math.radians(40), 0.0, math.radians(30))
        scene.collection.objects.link(sun)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    # Debian's Blender is built without OpenImageDenoise.
    scene.cycles.use_denoising = False
    for layer in scene.view_layers:
        layer.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    # Plain sRGB, as glint's own previews: no Filmic tone curve.
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    return scene


# Output formats by the file's extension: (Blender's format, its depth).
FORMATS = {".png": ("PNG", "8"), ".exr": ("OPEN_EXR", "32"),
           ".hdr": ("HDR", None), ".tif": ("TIFF", "16"),
           ".tiff": ("TIFF", "16"), ".jpg": ("JPEG", None),
           ".jpeg": ("JPEG", None)}


def set_output(scene, path):
    """Write the render to exactly path, in the format its extension
    names (EXR: 32-bit float, scene-linear)."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        sys.exit("glint: %s: unknown image extension '%s': expected one of "
                 "%s" % (path, ext, ", ".join(sorted(FORMATS))))
    fmt, depth = FORMATS[ext]
    settings = scene.render.image_settings
    settings.file_format = fmt
    settings.color_mode = "RGB"
    if depth:
        settings.color_depth = depth
    scene.render.use_file_extension = False
    scene.render.filepath = path


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(
        prog="blender --background --python " + __file__ + " --",
        description="Build the material " + NAME + "; optionally render a "
        "preview sphere or save the .blend file.")
    ap.add_argument("--render", metavar="OUT",
                    help="render a sphere of the material (Cycles) to OUT "
                    "(.png, .exr, .hdr, .tif or .jpg, from its extension)")
    ap.add_argument("--env", metavar="MAP",
                    help="light the preview with this environment map")
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--save", metavar="OUT.blend",
                    help="save the file with the material (and preview)")
    args = ap.parse_args(argv)
    # Blender resolves relative paths against the .blend file, not the
    # folder the command was given in.
    for k in ("render", "env", "save"):
        if getattr(args, k):
            setattr(args, k, os.path.abspath(getattr(args, k)))
    mat = build_material()
    print("glint: material '%s' built" % mat.name)
    if args.save and os.path.lexists(args.save):
        sys.exit("glint: %s exists: refusing to replace it" % args.save)
    if args.render:
        scene = preview_scene(mat, args.env, args.samples, args.size)
        set_output(scene, args.render)
        bpy.ops.render.render(write_still=True, scene=scene.name)
        print("glint: rendered", args.render)
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=args.save, copy=True)
        print("glint: saved", args.save)


if __name__ == "__main__":
    try:
        main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    except Exception as e:  # Blender itself would exit 0 after a traceback
        sys.exit("glint: %s" % e)
