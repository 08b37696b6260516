# Ambient-occlusion reference of a glTF/GLB scene with Blender Cycles (headless). Run by make-references.sh:
#   blender -b --factory-startup -noaudio --python-exit-code 3 -P blender_ao.py -- \
#       --scene FILE.glb --camera CAM.json --radius R --out PREFIX [--samples 1024] [--seed 0] [--threads 0]
# Writes PREFIX.exr (RGB float32, R = G = B = AO, row 0 at the top, ZIP) and PREFIX.json (the render facts).
#
# The AO follows hrtao's definition (the renderer's --ao-out):
# - pinhole camera from CAM.json ({"eye","target","up","fov_y_deg","width","height"}, scene-file coordinates);
#   the vertical field of view spans the image height; every sample goes through the pixel centre;
# - at the first hit, the fraction of cosine-weighted hemisphere directions around the geometric (face) normal,
#   turned toward the camera, whose ray hits nothing within R; 1 = open, 0 = closed; background pixels are 1.
# How: every material becomes a white diffuse BSDF whose normal is the true normal, the world AO distance is R,
# and the image is Cycles' AO render pass (one cosine-weighted ray per sample, with Cycles' ray-origin offset),
# no bounces, no denoising, no adaptive sampling, colour management off.

import argparse
import json
import math
import os
import sys
import tempfile
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector

# Blender 3.4's glTF importer uses NumPy aliases that NumPy 1.24 removed.
for _name, _type in (("bool", bool), ("int", int), ("float", float), ("object", object), ("str", str)):
    if _name not in np.__dict__:
        setattr(np, _name, _type)

# Blender's glTF importer turns the file's Y-up into Blender's Z-up: (x, y, z) -> (x, -z, y).
GLTF_TO_BLENDER = Matrix(((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)))


def argument_parser(prog, description):
    """The reference scripts' parser: --scene and --camera; the script's own options follow (then
    `add_render_args`)."""
    p = argparse.ArgumentParser(prog=prog, description=description)
    p.add_argument("--scene", required=True, help=".glb or .gltf")
    p.add_argument("--camera", required=True, help="camera JSON in the scene file's coordinates")
    return p


def add_render_args(p, samples_help):
    """--out, --samples, --seed and --threads; returns the arguments after Blender's `--`."""
    p.add_argument("--out", required=True, help="output prefix: writes PREFIX.exr and PREFIX.json")
    p.add_argument("--samples", type=int, default=1024, help=samples_help)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=0, help="CPU threads (0 = all)")
    return p.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def parse_args():
    p = argument_parser("blender_ao.py", "Cycles AO reference of a glTF scene")
    p.add_argument("--radius", type=float, required=True, help="AO radius R in scene units")
    a = add_render_args(p, "AO rays per pixel (render samples)")
    if not a.radius > 0 or a.samples < 1:
        p.error("--radius must be > 0 and --samples >= 1")
    return a


def node_tree(owner, output_type):
    """The cleared node tree of a material or world (`use_nodes`): its nodes, links and a new output node."""
    owner.use_nodes = True
    nodes, links = owner.node_tree.nodes, owner.node_tree.links
    nodes.clear()
    return nodes, links, nodes.new(output_type)


def white_diffuse_material(name):
    """A two-sided white diffuse material: it and its BSDF node (its Normal input unconnected: the mesh's own
    normals)."""
    mat = bpy.data.materials.new(name)
    nodes, links, out = node_tree(mat, "ShaderNodeOutputMaterial")
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.use_backface_culling = False
    return mat, bsdf


def white_true_normal_material():
    mat, bsdf = white_diffuse_material("hrtao_ao_white")
    geometry = mat.node_tree.nodes.new("ShaderNodeNewGeometry")
    mat.node_tree.links.new(geometry.outputs["True Normal"], bsdf.inputs["Normal"])
    return mat


def import_gltf(path):
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".glb", ".gltf"):
        raise ValueError("only .glb/.gltf scenes: %s" % path)
    bpy.ops.import_scene.gltf(filepath=path)
    scene = bpy.context.scene
    mat = white_true_normal_material()
    meshes = 0
    for obj in list(scene.objects):
        if obj.type in ("CAMERA", "LIGHT"):
            bpy.data.objects.remove(obj, do_unlink=True)
            continue
        if obj.type != "MESH":
            continue
        obj.data.materials.clear()
        obj.data.materials.append(mat)
        for slot in obj.material_slots:
            slot.material = mat
        meshes += 1
    if meshes == 0:
        raise RuntimeError("no meshes in %s" % path)
    return scene, meshes


def bounds(scene):
    pts = [obj.matrix_world @ Vector(c) for obj in scene.objects if obj.type == "MESH" for c in obj.bound_box]
    lo = Vector([min(p[k] for p in pts) for k in range(3)])
    hi = Vector([max(p[k] for p in pts) for k in range(3)])
    return lo, hi


def place_camera(scene, cam):
    eye, target, up = (GLTF_TO_BLENDER @ Vector(cam[k]) for k in ("eye", "target", "up"))
    forward = (target - eye).normalized()
    right = forward.cross(up)
    if right.length < 1e-9:
        raise ValueError("camera: up is parallel to the view direction")
    right.normalize()
    true_up = right.cross(forward)
    data = bpy.data.cameras.new("hrtao_ao_camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(float(cam["fov_y_deg"]))
    obj = bpy.data.objects.new("hrtao_ao_camera", data)
    scene.collection.objects.link(obj)
    # A Blender camera looks down its local -Z with +Y up.
    obj.matrix_world = Matrix(((right.x, true_up.x, -forward.x, eye.x),
                               (right.y, true_up.y, -forward.y, eye.y),
                               (right.z, true_up.z, -forward.z, eye.z),
                               (0.0, 0.0, 0.0, 1.0)))
    scene.camera = obj
    # Clip planes around the scene: the near plane must not cut geometry the reference should see.
    lo, hi = bounds(scene)
    corners = [Vector((x, y, z)) for x in (lo.x, hi.x) for y in (lo.y, hi.y) for z in (lo.z, hi.z)]
    far = max((c - eye).length for c in corners) * 1.01
    nearest = Vector([min(max(eye[k], lo[k]), hi[k]) for k in range(3)])
    near = 0.9 * (nearest - eye).length or 1e-3 * far
    data.clip_start, data.clip_end = max(near, 1e-5 * far), far
    return {"eye": list(eye), "target": list(target), "up": list(true_up), "clip_start": data.clip_start,
            "clip_end": far, "angle_y_deg": math.degrees(data.angle_y)}


def cycles_settings(scene, cam, samples, seed, threads):
    """What every reference of this project renders with: Cycles on the CPU at the camera's size, film transparent,
    colour management off, `samples` per pixel through the pixel centre, no adaptive sampling, no denoising, no
    bounces (blender_ao.py and blender_sky.py)."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = int(cam["width"]), int(cam["height"]), 100
    r.film_transparent = True
    r.threads_mode = "FIXED" if threads > 0 else "AUTO"
    if threads > 0:
        r.threads = threads
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = seed
    c.sampling_pattern = "SOBOL"
    # Every sample through the pixel centre: a filter 0.01 px wide (Cycles' box filter spreads over the whole
    # pixel whatever its width: 423 of rod 160x90's pixels changed coverage with it).
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = 0.01
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 0
    c.volume_bounces = c.transparent_max_bounces = 0
    c.use_fast_gi = False
    s = r.image_settings
    s.file_format, s.color_mode, s.color_depth, s.exr_codec = "OPEN_EXR", "RGBA", "32", "ZIP"


def set_up_render(scene, args, cam):
    cycles_settings(scene, cam, args.samples, args.seed, args.threads)  # alpha = coverage: background AO = 1 below
    r = scene.render
    world = bpy.data.worlds.new("hrtao_ao_world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    world.light_settings.distance = args.radius  # the AO pass's ray length
    scene.world = world
    layer = scene.view_layers[0]
    layer.use_pass_ambient_occlusion = True
    # Route the AO pass (and coverage) to the composite output.
    scene.use_nodes = True
    r.use_compositing = True
    tree = scene.node_tree
    tree.nodes.clear()
    layers = tree.nodes.new("CompositorNodeRLayers")
    layers.layer = layer.name
    comp = tree.nodes.new("CompositorNodeComposite")
    comp.use_alpha = True
    tree.links.new(layers.outputs["AO"], comp.inputs["Image"])
    tree.links.new(layers.outputs["Alpha"], comp.inputs["Alpha"])


def render_rgba(scene, w, h):
    """Renders; the result's RGBA (premultiplied), row 0 at the top."""
    bpy.ops.render.render(write_still=False)
    tmp = tempfile.mkdtemp(prefix="hrtao_ref_")
    raw = os.path.join(tmp, "raw.exr")
    bpy.data.images["Render Result"].save_render(raw, scene=scene)
    img = bpy.data.images.load(raw, check_existing=False)
    rgba = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(rgba)
    bpy.data.images.remove(img)
    os.remove(raw)
    os.rmdir(tmp)
    return rgba.reshape(h, w, 4)[::-1]  # Blender's rows are bottom-up


def render_ao(scene, w, h):
    """The AO image, row 0 at the top, and the coverage."""
    rgba = render_rgba(scene, w, h)
    alpha = np.clip(rgba[..., 3], 0.0, 1.0)
    ao = np.clip(rgba[..., :3].mean(axis=2) + (1.0 - alpha), 0.0, 1.0)  # premultiplied AO + open background
    return ao.astype(np.float32), alpha


def save_rgb_exr(scene, path, rgb):
    """Writes an (h, w, 3) image, row 0 at the top, as an RGB float EXR."""
    h, w, _ = rgb.shape
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = rgb
    img = bpy.data.images.new("hrtao_ref_out", w, h, alpha=True, float_buffer=True)
    img.pixels.foreach_set(rgba[::-1].ravel())
    scene.render.image_settings.color_mode = "RGB"
    img.save_render(path, scene=scene)
    bpy.data.images.remove(img)


def write_exr(scene, path, ao):
    save_rgb_exr(scene, path, np.repeat(ao[..., None], 3, axis=2))


def read_camera(path):
    """The camera file (eye, target, up, fov_y_deg, width, height), checked."""
    with open(path) as f:
        cam = json.load(f)
    for k in ("eye", "target", "up", "fov_y_deg", "width", "height"):
        if k not in cam:
            raise ValueError("%s: the camera needs '%s'" % (path, k))
    return cam


def open_scene(args):
    """An empty Blender with the scene imported: (scene, its mesh objects, the camera file)."""
    cam = read_camera(args.camera)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, meshes = import_gltf(os.path.abspath(args.scene))
    return scene, meshes, cam


def render_facts(scene, args, cam, cam_blender, meshes, t0, t_render):
    """The facts every reference's JSON records beside its own (engine, size, sampling, times, scene)."""
    return {
        "engine": "cycles",
        "blender_version": bpy.app.version_string,
        "width": int(cam["width"]),
        "height": int(cam["height"]),
        "samples": args.samples,
        "filter_width_px": 0.01,
        "sampling_pattern": "sobol",
        "seed": args.seed,
        "render_time_s": round(t_render, 4),
        "total_time_s": round(time.perf_counter() - t0, 4),
        "threads": scene.render.threads,
        "scene": os.path.basename(args.scene),
        "mesh_objects": meshes,
        "camera_json": cam,
        "camera_blender_space": cam_blender,
        "outputs": {"exr": os.path.basename(args.out) + ".exr"},
    }


def finish(args, facts, summary):
    """Writes PREFIX.json (the render facts) and prints the script's summary line."""
    with open(args.out + ".json", "w") as f:
        json.dump(facts, f, indent=1)
    print(summary, flush=True)


def main():
    t0 = time.perf_counter()
    args = parse_args()
    scene, meshes, cam = open_scene(args)
    cam_blender = place_camera(scene, cam)
    set_up_render(scene, args, cam)
    t_render = time.perf_counter()
    w, h = int(cam["width"]), int(cam["height"])
    ao, alpha = render_ao(scene, w, h)
    t_render = time.perf_counter() - t_render
    write_exr(scene, args.out + ".exr", ao)
    geometry = alpha > 0.5
    facts = render_facts(scene, args, cam, cam_blender, meshes, t0, t_render)
    facts.update({
        "method": "Cycles AO render pass (world AO distance = R), ray traced, 1 AO ray per sample",
        "ao_rays_per_pixel": args.samples,
        "radius": args.radius,
        "normal": "geometric (Geometry.True Normal)",
        "stats": {
            "geometry_pixel_fraction": float(geometry.mean()),
            "ao_mean_geometry": float(ao[geometry].mean()) if geometry.any() else None,
            "ao_min": float(ao.min()),
            "ao_max": float(ao.max()),
        },
    })
    finish(args, facts, "[blender_ao] %s: %dx%d, %d rays/pixel, %.1f s" % (args.out, w, h, args.samples, t_render))


if __name__ == "__main__":
    main()
