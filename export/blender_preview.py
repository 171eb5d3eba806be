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


def preview_scene(mat, env=None, samples=64, size=512,
                  env_rotation=(0.0, 0.0, 0.0)):
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
        glint_environment(world.node_tree, bg, env, env_rotation)
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


def glint_environment(tree, bg, env, rotation):
    """Light the world with a lat-long map as glint does
    (docs/conventions.md): glint's world is Blender's turned to +Y up
    (g = (x, z, -y), the preview camera looking along glint's -Z), the map
    turned by rotation = (a, b, c) degrees, R = Rz(c) Ry(b) Rx(a), the
    radiance along d that of the map at m = R^T d, stored at
    u = 0.5 + atan2(m.x, -m.z) / 2 pi, v = acos(m.y) / pi from the top.
    Built from nodes, so the map is glint's by construction rather than by
    Blender's own equirectangular convention."""
    nodes, links = tree.nodes, tree.links

    def op(name, a, b=None):
        n = nodes.new("ShaderNodeMath")
        n.operation = name
        for k, v in enumerate((a, b)):
            if v is None:
                continue
            if isinstance(v, (int, float)):
                n.inputs[k].default_value = v
            else:
                links.new(v, n.inputs[k])
        return n.outputs[0]

    coord = nodes.new("ShaderNodeTexCoord")
    b = nodes.new("ShaderNodeSeparateXYZ")
    links.new(coord.outputs["Generated"], b.inputs[0])
    g = nodes.new("ShaderNodeCombineXYZ")
    links.new(b.outputs["X"], g.inputs["X"])
    links.new(b.outputs["Z"], g.inputs["Y"])
    links.new(op("MULTIPLY", b.outputs["Y"], -1.0), g.inputs["Z"])
    rot = nodes.new("ShaderNodeVectorRotate")
    rot.rotation_type = "EULER_XYZ"
    rot.invert = True  # R^T: the map's direction seen along d
    rot.inputs["Rotation"].default_value = [math.radians(x)
                                            for x in rotation]
    rot.inputs["Center"].default_value = (0.0, 0.0, 0.0)
    links.new(g.outputs[0], rot.inputs["Vector"])
    m = nodes.new("ShaderNodeSeparateXYZ")
    links.new(rot.outputs[0], m.inputs[0])
    # Blender's atan2 is ARCTAN2(A, B) = atan2(A, B).
    phi = op("ARCTAN2", m.outputs["X"], op("MULTIPLY", m.outputs["Z"],
                                                -1.0))
    u = op("ADD", op("DIVIDE", phi, 2 * math.pi), 0.5)
    theta = op("ARCCOSINE", op("MINIMUM", op("MAXIMUM", m.outputs["Y"],
                                                   -1.0), 1.0))
    v = op("SUBTRACT", 1.0, op("DIVIDE", theta, math.pi))
    uv = nodes.new("ShaderNodeCombineXYZ")
    links.new(u, uv.inputs["X"])
    links.new(v, uv.inputs["Y"])
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(env)
    tex.interpolation = "Linear"
    tex.extension = "REPEAT"  # wraps across the seam in u
    links.new(uv.outputs[0], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], bg.inputs["Color"])


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
                    help="light the preview with this lat-long map, "
                    "oriented as glint orients it (docs/conventions.md)")
    ap.add_argument("--env-rotation", metavar="X,Y,Z", default="0,0,0",
                    help="the map's rotation in degrees about glint's X, Y, "
                    "Z, as a scene's environment.rotation_deg (default "
                    "0,0,0)")
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
        try:
            rot = [float(x) for x in args.env_rotation.split(",")]
        except ValueError:
            rot = []
        if len(rot) != 3:
            sys.exit("glint: --env-rotation '%s': expected X,Y,Z in "
                     "degrees" % args.env_rotation)
        scene = preview_scene(mat, args.env, args.samples, args.size, rot)
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
