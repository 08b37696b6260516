# Sky-light reference of a glTF/GLB scene with Blender Cycles (headless). Run by make-sky-references.sh:
#   blender -b --factory-startup -noaudio --python-exit-code 3 -P blender_sky.py -- \
#       --scene FILE.glb --camera CAM.json --environment uniform|gradient|FILE.hdr [--rotation DEG] \
#       [--intensity K] [--up y|z] --out PREFIX [--samples 1024] [--seed 0] [--threads 0]
# Writes PREFIX.exr (RGB float32, linear, row 0 at the top, ZIP) and PREFIX.json (the render facts).
#
# The value follows hrtao's `--light-out` contract (the sky light):
# - the camera as blender_ao.py places it (pinhole from CAM.json in the scene file's coordinates, every sample
#   through the pixel centre);
# - at the first hit, L = (1/pi) * integral of K E(w) V(w) max(0, n.w) dw: a white Lambertian (albedo 1) with the
#   file's normals (Cycles turns them toward the camera on a back face), V = 0 where any surface at any distance
#   blocks w (no AO radius), direct light only (no bounces); background pixels 0 (film transparent).
# - Directions: Blender's glTF import turns the file's (x, y, z) into (x, -z, y), which is the sky frame b of a Y-up
#   file; a Z-up file's b is its own (x, y, z): the world's Mapping turns Blender's direction back by -90 degrees
#   about X. Then b' = R_z(-theta) b (Mapping rotation Z = -theta; X applies first).
# - uniform: E = (1, 1, 1). gradient: E = G + (S - G)(1 + b'_z)/2 (Separate XYZ z, Map Range -1..1 -> 0..1, Mix RGB
#   G -> S), S = (0.6, 0.8, 1.0), G = (0.4, 0.3, 0.2). FILE.hdr: Environment Texture (equirectangular, Linear
#   interpolation), which reads u = 0.5 - atan2(b'_y, b'_x)/2pi and t = 0.5 - asin(b'_z)/pi from the top row.
# - Standard view transform, no look, no denoising, no adaptive sampling; the world is importance sampled.

import math
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_ao  # noqa: E402  (the shared camera, import and clip conventions)

SKY = (0.6, 0.8, 1.0)
GROUND = (0.4, 0.3, 0.2)


def parse_args():
    p = blender_ao.argument_parser("blender_sky.py", "Cycles sky-light reference of a glTF scene")
    p.add_argument("--environment", required=True, help="uniform, gradient or an equirectangular .hdr")
    p.add_argument("--rotation", type=float, default=0.0, help="degrees, counter-clockwise seen from above")
    p.add_argument("--intensity", type=float, default=1.0, help="K, the environment's scale")
    p.add_argument("--up", choices=("y", "z"), default="y", help="the scene file's up axis (the zenith)")
    a = blender_ao.add_render_args(p, "samples per pixel")
    if a.samples < 1 or not a.intensity >= 0.0:
        p.error("--samples must be >= 1 and --intensity >= 0")
    if a.environment not in ("uniform", "gradient") and not os.path.isfile(a.environment):
        p.error("--environment: no such file: %s" % a.environment)
    return a


def white_material():
    """Diffuse white with the mesh's own (smooth or custom) normals: the Normal input left unconnected."""
    mat, bsdf = blender_ao.white_diffuse_material("hrtao_sky_white")
    bsdf.inputs["Roughness"].default_value = 0.0
    return mat


def world(args):
    w = bpy.data.worlds.new("hrtao_sky_world")
    nodes, links, out = blender_ao.node_tree(w, "ShaderNodeOutputWorld")
    bg = nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = args.intensity
    links.new(bg.outputs["Background"], out.inputs["Surface"])
    if args.environment == "uniform":
        bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    else:
        coords = nodes.new("ShaderNodeTexCoord")
        mapping = nodes.new("ShaderNodeMapping")
        mapping.vector_type = "POINT"
        x = -90.0 if args.up == "z" else 0.0
        mapping.inputs["Rotation"].default_value = (math.radians(x), 0.0, math.radians(-args.rotation))
        links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        if args.environment == "gradient":
            xyz = nodes.new("ShaderNodeSeparateXYZ")
            ramp = nodes.new("ShaderNodeMapRange")
            ramp.inputs["From Min"].default_value = -1.0
            ramp.inputs["From Max"].default_value = 1.0
            ramp.inputs["To Min"].default_value = 0.0
            ramp.inputs["To Max"].default_value = 1.0
            mix = nodes.new("ShaderNodeMixRGB")
            mix.blend_type = "MIX"
            mix.inputs["Color1"].default_value = GROUND + (1.0,)
            mix.inputs["Color2"].default_value = SKY + (1.0,)
            links.new(mapping.outputs["Vector"], xyz.inputs["Vector"])
            links.new(xyz.outputs["Z"], ramp.inputs["Value"])
            links.new(ramp.outputs["Result"], mix.inputs["Fac"])
            links.new(mix.outputs["Color"], bg.inputs["Color"])
        else:
            tex = nodes.new("ShaderNodeTexEnvironment")
            tex.image = bpy.data.images.load(os.path.abspath(args.environment), check_existing=False)
            tex.image.colorspace_settings.name = "Linear"
            tex.interpolation = "Linear"
            tex.projection = "EQUIRECTANGULAR"
            links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
            links.new(tex.outputs["Color"], bg.inputs["Color"])
    w.cycles.sampling_method = "AUTOMATIC"  # importance-sample the environment
    return w


def set_up_render(scene, args, cam):
    blender_ao.cycles_settings(scene, cam, args.samples, args.seed, args.threads)  # background 0: film transparent
    scene.world = world(args)


def render_light(scene, w, h):
    """The light image (RGB, row 0 at the top) and the coverage."""
    rgba = blender_ao.render_rgba(scene, w, h)
    alpha = np.clip(rgba[..., 3], 0.0, 1.0)
    return np.ascontiguousarray(rgba[..., :3]).astype(np.float32), alpha


def main():
    t0 = time.perf_counter()
    args = parse_args()
    scene, meshes, cam = blender_ao.open_scene(args)
    mat = white_material()
    for obj in scene.objects:
        if obj.type == "MESH":
            obj.data.materials.clear()
            obj.data.materials.append(mat)
            for slot in obj.material_slots:
                slot.material = mat
    cam_blender = blender_ao.place_camera(scene, cam)
    set_up_render(scene, args, cam)
    t_render = time.perf_counter()
    w, h = int(cam["width"]), int(cam["height"])
    rgb, alpha = render_light(scene, w, h)
    t_render = time.perf_counter() - t_render
    blender_ao.save_rgb_exr(scene, args.out + ".exr", rgb)
    geometry = alpha > 0.5
    env = args.environment if args.environment in ("uniform", "gradient") else os.path.basename(args.environment)
    facts = blender_ao.render_facts(scene, args, cam, cam_blender, meshes, t0, t_render)
    facts.update({
        "method": "Cycles combined pass, white diffuse, no bounces, world importance sampled (the sky light)",
        "environment": env,
        "rotation_deg": args.rotation,
        "intensity": args.intensity,
        "up": args.up,
        "normal": "the file's (smooth or custom split normals)",
        "stats": {
            "geometry_pixel_fraction": float(geometry.mean()),
            "light_mean_geometry": [float(v) for v in rgb[geometry].mean(axis=0)] if geometry.any() else None,
            "light_max": float(rgb.max()),
        },
    })
    summary = "[blender_sky] %s: %dx%d, %d samples, %.1f s" % (args.out, w, h, args.samples, t_render)
    blender_ao.finish(args, facts, summary)


if __name__ == "__main__":
    main()
