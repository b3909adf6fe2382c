#!/usr/bin/env python3
"""dormant against Blender Cycles, side by side (`make compare-cycles`; not in CI).

Runs under the Python of a venv holding `bpy` (Blender 5.0 as a module; the Makefile target
creates .deps/bpy-venv). From a trajectory exported by `dormant export` it builds the same
scene in Cycles: the environment and prototype glTFs imported by Blender's glTF importer, one
collection instance per body at its pose, the same camera, sun, sky and punctual lights, then
renders with Cycles on the CPU to linear EXR. dormant renders the same frames with the same
samples per pixel, bounces and threads. Two measurements:

  correctness  one frame at 1,024 spp as two independent 512-spp halves per renderer; the
               per-pixel difference between the renderers is compared with the noise both
               halves show (see `compare_images` for the metric);
  speed        a 120-frame monastery-rain sequence at 16 spp, frames in interleaved chunks
               (dormant, Cycles, dormant, ...) because the machine is shared; wall time per
               frame including scene updates, Cycles' sync (BVH build) and path tracing apart.

What the comparison fixes so that both renderers compute the same image (see
docs/performance.md#against-blender-cycles for what still differs):
  - Y up (glTF, dormant) against Blender's Z up: C = rotation of +90 degrees about X,
    (x, y, z) -> (x, -z, y); the importer applies C to every file, so a body's Blender
    transform is C * pose * scale * C^-1;
  - camera: dormant's field of view is vertical, so the Blender camera's sensor fit is
    VERTICAL with the same angle;
  - Principled BSDF with single-scattering GGX (dormant has no multiple-scattering term), no
    normal maps and opaque (dormant reads neither normal textures nor alpha);
  - no tone mapping (Standard view transform, linear EXR), no denoising, no adaptive sampling,
    no light threshold, no glossy filter, no clamping on either side (dormant's
    --clamp-indirect 0);
  - pixel filter: Cycles' own, Blackman-Harris of width 1.5, on both sides (dormant's
    --filter blackman-harris);
  - bounces: dormant's --max-depth N traces N segments, Cycles' max_bounces N-1.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

try:
    import bpy
    from mathutils import Matrix, Quaternion, Vector
except ImportError:  # pragma: no cover - the Makefile runs this under the bpy venv
    sys.exit("compare-cycles: needs the `bpy` module (make compare-cycles installs it into .deps/bpy-venv)")

ROOT = Path(__file__).resolve().parent.parent
# glTF / dormant (Y up) to Blender (Z up): (x, y, z) -> (x, -z, y).
C = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))


def to_blender(v):
    return Vector((v[0], -v[2], v[1]))


def log(msg):
    print(f"compare-cycles: {msg}", flush=True)


# --- dormant ----------------------------------------------------------------------------------


def run_dormant(args, *cmd):
    """Runs dormant with the fixed thread count; returns wall seconds."""
    full = [str(args.dormant), "--threads", str(args.threads), "--quiet", *map(str, cmd)]
    t = time.perf_counter()
    subprocess.run(full, check=True)
    return time.perf_counter() - t


# What dormant renders with so that it computes Cycles' image (`configure_render`): Cycles'
# pixel filter, no clamping.
MATCHING_FLAGS = ["--filter", "blackman-harris", "--filter-width", "1.5", "--clamp-indirect", "0"]


def dormant_render(args, traj, frames, out, spp, size, seed="fixed", reuse="on", seed_offset=0):
    """Renders frames A..B of `traj` into `out` with EXRs; returns (wall s, the frames' records
    from out/stats.json: stage times in ms, `trace_ms` and `frame_ms` among them)."""
    wall = run_dormant(
        args, "render", "--trajectory", traj, "--frames", frames, "--spp", spp, "--size", size,
        "--max-depth", args.max_depth, "--seed", seed, "--seed-offset", seed_offset, "--reuse", reuse, "--exr",
        "--out", out, *MATCHING_FLAGS,
    )
    a, b = map(int, frames.split(".."))
    records = json.loads((out / "stats.json").read_text())["frames"]
    return wall, [{k: v for k, v in r.items() if k != "decisions"} for r in records if a <= r["frame"] < b]


# --- Blender scene ----------------------------------------------------------------------------


def reset_blender():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def import_gltf(path, name):
    """Imports a glTF into a new collection that is not linked to the scene (it renders only
    through instances). Lights and cameras in the file are dropped (the export has them)."""
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=str(path), import_shading="NORMALS")
    new = [o for o in bpy.data.objects if o not in before]
    coll = bpy.data.collections.new(name)
    for o in new:
        if o.type in {"LIGHT", "CAMERA"}:
            bpy.data.objects.remove(o, do_unlink=True)
            continue
        for c in list(o.users_collection):
            c.objects.unlink(o)
        coll.objects.link(o)
    return coll


def match_materials():
    """Makes every Principled BSDF the model dormant evaluates (src/render/bsdf.rs)."""
    for mat in bpy.data.materials:
        if not mat.use_nodes:
            continue
        tree = mat.node_tree
        for node in tree.nodes:
            if node.type != "BSDF_PRINCIPLED":
                continue
            node.distribution = "GGX"  # single scattering, as dormant
            for name in ("Normal", "Alpha", "Coat Weight", "Sheen Weight", "Subsurface Weight",
                         "Transmission Weight"):
                sock = node.inputs.get(name)
                if sock is None:
                    continue
                for link in list(sock.links):
                    tree.links.remove(link)
                if name == "Alpha":
                    sock.default_value = 1.0
                elif name != "Normal":
                    sock.default_value = 0.0


def give_material(coll, m, name):
    """Gives every mesh of `coll` dormant's fallback material `m` (its file has none)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (*m["base_color"], 1.0)
    bsdf.inputs["Roughness"].default_value = m["roughness"]
    bsdf.inputs["Metallic"].default_value = m["metallic"]
    # Specular IOR Level 0.5 is F0 = 0.04 at IOR 1.5 (dormant's specular 1); 0 removes it.
    bsdf.inputs["Specular IOR Level"].default_value = 0.5 * m["specular"]
    bsdf.inputs["IOR"].default_value = 1.5
    bsdf.inputs["Emission Color"].default_value = (*m["emissive"], 1.0)
    bsdf.inputs["Emission Strength"].default_value = 1.0
    for o in coll.all_objects:
        if o.type == "MESH":
            o.data.materials.clear()
            o.data.materials.append(mat)


def instance(coll, name, matrix):
    o = bpy.data.objects.new(name, None)
    o.instance_type = "COLLECTION"
    o.instance_collection = coll
    o.matrix_world = matrix
    bpy.context.scene.collection.objects.link(o)
    return o


def placement(scale, offset=(0.0, 0.0, 0.0), pose=None):
    """Blender matrix of a mesh placed by dormant as pose * (scale, offset), in file coords."""
    m = Matrix.Translation(Vector(offset)) @ Matrix.Diagonal((scale, scale, scale, 1.0))
    if pose is not None:
        t, q = pose[:3], pose[3:]
        rot = Quaternion((q[3], q[0], q[1], q[2])).to_matrix().to_4x4()
        m = Matrix.Translation(Vector(t)) @ rot @ m
    return C @ m @ C.inverted()


def build_world(sky):
    world = bpy.data.worlds.new("sky")
    bpy.context.scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes["Background"]
    bg.inputs["Strength"].default_value = 1.0
    if sky["zenith"] == sky["horizon"] == sky["ground"]:
        bg.inputs["Color"].default_value = (*sky["horizon"], 1.0)
        return
    # dormant's gradient (scene::Sky::radiance): horizon -> zenith (or ground) with sqrt|elevation|.
    coord = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(coord.outputs["Generated"], sep.inputs[0])
    absz = nt.nodes.new("ShaderNodeMath")
    absz.operation = "ABSOLUTE"
    nt.links.new(sep.outputs["Z"], absz.inputs[0])
    root = nt.nodes.new("ShaderNodeMath")
    root.operation = "SQRT"
    root.use_clamp = True
    nt.links.new(absz.outputs[0], root.inputs[0])
    up = nt.nodes.new("ShaderNodeMix")
    down = nt.nodes.new("ShaderNodeMix")
    for mix, far in ((up, sky["zenith"]), (down, sky["ground"])):
        mix.data_type = "RGBA"
        mix.inputs["A"].default_value = (*sky["horizon"], 1.0)
        mix.inputs["B"].default_value = (*far, 1.0)
        nt.links.new(root.outputs[0], mix.inputs["Factor"])
    above = nt.nodes.new("ShaderNodeMath")
    above.operation = "GREATER_THAN"
    above.inputs[1].default_value = 0.0
    nt.links.new(sep.outputs["Z"], above.inputs[0])
    pick = nt.nodes.new("ShaderNodeMix")
    pick.data_type = "RGBA"
    nt.links.new(above.outputs[0], pick.inputs["Factor"])
    nt.links.new(down.outputs["Result"], pick.inputs["A"])
    nt.links.new(up.outputs["Result"], pick.inputs["B"])
    nt.links.new(pick.outputs["Result"], bg.inputs["Color"])


def add_light(name, kind, rgb, direction=None, position=None):
    """A Blender light of `rgb` (the colour's largest component becomes the strength)."""
    strength = max(max(rgb), 1e-12)
    data = bpy.data.lights.new(name, kind)
    data.color = [c / strength for c in rgb]
    data.energy = strength
    obj = bpy.data.objects.new(name, data)
    if position is not None:
        obj.location = to_blender(position)
    if direction is not None:
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = to_blender(direction).to_track_quat("-Z", "Y")
    bpy.context.scene.collection.objects.link(obj)
    return data


def build_lights(export):
    sun = export["sun"]
    data = add_light("sun", "SUN", sun["irradiance"], direction=[-d for d in sun["direction"]])
    data.angle = math.radians(2.0 * sun["angular_radius_deg"])  # W/m^2, full angle
    for i, light in enumerate(export["lights"]):
        if light["kind"] == "directional":
            add_light(f"light{i}", "SUN", light["irradiance"], direction=light["direction"]).angle = 0.0
            continue
        # Blender's point and spot power P radiates P / (4 pi) W/sr.
        watts = [4.0 * math.pi * c for c in light["intensity"]]
        kind = "POINT" if light["kind"] == "point" else "SPOT"
        data = add_light(f"light{i}", kind, watts, position=light["position"], direction=light.get("direction"))
        data.shadow_soft_size = 0.0
        if kind == "SPOT":
            outer = math.acos(light["cos_outer"])
            data.spot_size = 2.0 * outer
            # glTF's smooth falloff against Blender's smoothstep blend: an approximation.
            data.spot_blend = 1.0 - math.acos(light["cos_inner"]) / max(outer, 1e-6)


def set_camera(cam_obj, cam):
    eye, target = to_blender(cam["eye"]), to_blender(cam["target"])
    forward = (target - eye).normalized()
    right = forward.cross(to_blender(cam["up"])).normalized()
    up = right.cross(forward)
    m = Matrix((right, up, -forward)).transposed().to_4x4()
    m.translation = eye
    cam_obj.matrix_world = m
    cam_obj.data.sensor_fit = "VERTICAL"
    cam_obj.data.angle_y = math.radians(cam["vfov_deg"])


def configure_render(args, spp, size, seed, persistent):
    scene = bpy.context.scene
    r, c = scene.render, scene.cycles
    r.engine = "CYCLES"
    c.device = "CPU"
    w, h = map(int, size.split("x"))
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.threads_mode, r.threads = "FIXED", args.threads
    r.use_persistent_data = persistent
    r.film_transparent = False
    r.use_compositing = False
    r.use_sequencer = False
    c.samples = spp
    c.seed = seed
    c.use_animated_seed = False
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = args.max_depth - 1
    for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "transparent_max_bounces"):
        setattr(c, k, args.max_depth - 1)
    c.volume_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    # Cycles' default filter, which dormant renders too (MATCHING_FLAGS).
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = 1.5
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"


class CyclesScene:
    """The export's scene in Blender: prototypes as collections, one instance per body."""

    def __init__(self, export):
        reset_blender()
        self.export = export
        env = export["environment"]
        if env["gltf"] is None:
            sys.exit(f"compare-cycles: the environment is built in ({env['builtin']}); only glTF is supported")
        env_coll = import_gltf(env["gltf"], "environment")
        instance(env_coll, "environment", placement(env["scale"], env["offset"]))
        self.collections = []
        for p in export["prototypes"]:
            if p["gltf"] is None:
                sys.exit(f"compare-cycles: prototype {p['name']} is a built-in {p['builtin']}; only glTF is supported")
            self.collections.append(import_gltf(p["gltf"], p["name"]))
        match_materials()
        if export["environment_material"]:
            give_material(env_coll, export["environment_material"], "environment-fallback")
        for coll, p in zip(self.collections, export["prototypes"]):
            if p["material"]:
                give_material(coll, p["material"], f"{p['name']}-fallback")
        build_world(export["sky"])
        build_lights(export)
        cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
        bpy.context.scene.collection.objects.link(cam)
        bpy.context.scene.camera = cam
        self.camera = cam
        self.bodies = {}

    def pose(self, frame):
        """Places every body as in `frame` (absent ones hidden) and the camera."""
        protos = self.export["body_prototypes"]
        for b, pose in enumerate(frame["poses"]):
            obj = self.bodies.get(b)
            if pose is None:
                if obj is not None and not obj.hide_render:
                    obj.hide_render = True
                continue
            p = self.export["prototypes"][protos[b]]
            m = placement(p["scale"], p["offset"], pose)
            if obj is None:
                self.bodies[b] = instance(self.collections[protos[b]], f"body{b}", m)
            else:
                obj.matrix_world = m
                if obj.hide_render:
                    obj.hide_render = False
        set_camera(self.camera, frame["camera"])

    def break_light(self, factor):
        """The negative control's broken light: the sun's strength times `factor`; returns
        what restores it."""
        sun = bpy.data.lights["sun"]
        energy = sun.energy
        sun.energy = energy * factor

        def restore():
            sun.energy = energy
        return restore

    def break_material(self, prototype):
        """The negative control's wrong body material: every material of prototype
        `prototype`'s meshes becomes flat magenta; returns what restores them."""
        saved = []
        mats = {s.material for o in self.collections[prototype].all_objects if o.type == "MESH"
                for s in o.material_slots if s.material is not None}
        for mat in mats:
            copy = mat.copy()
            bsdf = next((n for n in copy.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
            if bsdf is None:
                continue
            sock = bsdf.inputs["Base Color"]
            for link in list(sock.links):
                copy.node_tree.links.remove(link)
            sock.default_value = (1.0, 0.0, 1.0, 1.0)
            for o in self.collections[prototype].all_objects:
                for slot in getattr(o, "material_slots", []):
                    if slot.material == mat:
                        saved.append((slot, mat))
                        slot.material = copy

        def restore():
            for slot, mat in saved:
                slot.material = mat
        return restore

    def render(self, path):
        """Renders to `path`; returns (wall s, sync s, path-tracing s) from Cycles' status."""
        marks = []

        def on_stats(text):
            marks.append((time.perf_counter(), str(text)))

        bpy.app.handlers.render_stats.append(on_stats)
        bpy.context.scene.render.filepath = str(path)
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        t1 = time.perf_counter()
        bpy.app.handlers.render_stats.remove(on_stats)
        first_sample = next((t for t, s in marks if "Sample" in s), None)
        sync = (first_sample - t0) if first_sample else float("nan")
        return t1 - t0, sync, (t1 - first_sample) if first_sample else float("nan")


class CyclesAnimation:
    """Cycles as a user renders a simulation: dormant's animated glTF (`dormant export --gltf`:
    one keyframed object per body, shared meshes) imported by Blender's importer, the
    comparison's own camera, lights and sky, and frames rendered as animation jobs with
    persistent data. The import is timed apart (`import_s`)."""

    def __init__(self, glb, export):
        reset_blender()
        scene = bpy.context.scene
        # The importer turns key times into frames at the scene's rate; frame f is then
        # dormant's frame f (scripts/blender-roundtrip.py checks the import).
        scene.render.fps, scene.render.fps_base = round(1.0 / export["timestep"]), 1.0
        t = time.perf_counter()
        bpy.ops.import_scene.gltf(filepath=str(glb), import_shading="NORMALS")
        self.import_s = time.perf_counter() - t
        for o in [o for o in bpy.data.objects if o.type in ("LIGHT", "CAMERA")]:
            bpy.data.objects.remove(o)
        match_materials()
        build_world(export["sky"])
        build_lights(export)
        cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
        set_camera(cam, export["frames"][0]["camera"])

    def render(self, first, last, out):
        """Frames first..last as one animation job into `out`; per frame (wall s from the
        previous frame's end, sync s to its first sample)."""
        scene = bpy.context.scene
        scene.frame_start, scene.frame_end = first, last - 1
        scene.render.filepath = str(out / "frame_####")
        marks = {"post": [], "sample": []}

        def on_post(*_):
            marks["post"].append(time.perf_counter())

        def on_stats(text):
            if "Sample" in str(text) and len(marks["sample"]) == len(marks["post"]):
                marks["sample"].append(time.perf_counter())

        bpy.app.handlers.render_post.append(on_post)
        bpy.app.handlers.render_stats.append(on_stats)
        t0 = time.perf_counter()
        bpy.ops.render.render(animation=True)
        bpy.app.handlers.render_post.remove(on_post)
        bpy.app.handlers.render_stats.remove(on_stats)
        starts = [t0] + marks["post"][:-1]
        samples = marks["sample"] + [float("nan")] * (len(starts) - len(marks["sample"]))
        return [{"frame": first + k, "wall_s": end - start, "sync_s": sample - start, "update_s": 0.0,
                 "trace_s": end - sample}
                for k, (start, end, sample) in enumerate(zip(starts, marks["post"], samples))]


# --- images -----------------------------------------------------------------------------------


def read_exr(path):
    img = bpy.data.images.load(str(path), check_existing=False)
    img.colorspace_settings.name = "Linear Rec.709"
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)


def compare_images(a1, a2, b1, b2):
    """a1, a2: renderer A's two independent halves; b1, b2: B's. Per pixel and channel, the
    mean of the halves estimates the full-spp image, and (x1 - x2)^2 / 4 its variance.

    - `chi2`: sum of (A - B)^2 over sum of (var A + var B): 1 when the renderers agree within
      their noise; (chi2 - 1) / chi2 is the share of the squared difference that is bias.
    - `within_3se`: fraction of pixels whose luminance difference lies within 3 standard
      errors, the variances pooled over 3x3 pixels (a 1-sample variance alone is too noisy).
    - `mean_ratio`: mean luminance of A over B (light units, exposure).
    - `rel_mse`: mean of (A - B)^2 / (B^2 + 1e-2) against each renderer's own rel. MSE of
      half vs half (what the noise alone gives at half the samples, divided by 4 for the full)."""
    lum = np.array([0.2126, 0.7152, 0.0722])
    a, b = (a1 + a2) / 2, (b1 + b2) / 2
    va, vb = (a1 - a2) ** 2 / 4, (b1 - b2) ** 2 / 4
    chi2 = float(((a - b) ** 2).sum() / (va + vb).sum())
    la, lb = a @ lum, b @ lum
    vla, vlb = ((a1 - a2) @ lum) ** 2 / 4, ((b1 - b2) @ lum) ** 2 / 4

    def box3(x):
        p = np.pad(x, 1, mode="edge")
        return sum(p[i:i + x.shape[0], j:j + x.shape[1]] for i in range(3) for j in range(3)) / 9

    se = np.sqrt(box3(vla) + box3(vlb))
    within = float((np.abs(la - lb) <= 3 * se + 1e-6).mean())
    rel = lambda x, y: float(((x - y) ** 2 / (y ** 2 + 1e-2)).mean())
    return {
        "chi2": chi2,
        "bias_share": max(0.0, (chi2 - 1) / chi2),
        "within_3se": within,
        "mean_ratio": float(la.mean() / lb.mean()),
        "rel_mse_between": rel(a, b),
        "rel_mse_noise_a": rel(a1, a2) / 4,
        "rel_mse_noise_b": rel(b1, b2) / 4,
    }, (la - lb) / np.maximum(se, 1e-6)


# Image checks with teeth (issue 38): thresholds that do not depend on the pixel count.
MAX_MEAN_LUMINANCE_ERROR = 0.01  # |mean luminance dormant / Cycles - 1|
TILE = 16
MAX_TILE_ERROR = 0.03  # a 16x16 tile's mean luminance, relative
MIN_TILES_WITHIN = 0.99  # share of tiles within MAX_TILE_ERROR
# Pixels whose largest channel differs by more than 6 standard errors: the tile means miss a
# wrong material on bodies a few pixels wide (the duck prototype made magenta, 160x90: tiles
# 100% within, 0.22% of pixels beyond 6 s.e. against 0.02% for the renderers as they are).
Z_OUTLIER = 6.0
MAX_Z_OUTLIERS = 0.001


def tile_check(a, b, tile=TILE):
    """Mean luminance ratio of `a` over `b`, and the share of `tile` x `tile` tiles whose mean
    luminances agree within MAX_TILE_ERROR (relative to `b`'s)."""
    lum = np.array([0.2126, 0.7152, 0.0722])
    la, lb = a @ lum, b @ lum
    h, w = (la.shape[0] // tile) * tile, (la.shape[1] // tile) * tile
    ta = la[:h, :w].reshape(h // tile, tile, w // tile, tile).mean(axis=(1, 3))
    tb = lb[:h, :w].reshape(h // tile, tile, w // tile, tile).mean(axis=(1, 3))
    within = np.abs(ta - tb) <= MAX_TILE_ERROR * np.maximum(np.abs(tb), 1e-3)
    return float(la.mean() / lb.mean()), float(within.mean())


def image_checks(a1, a2, b1, b2):
    """The thresholds on the means of the halves, and the per pixel-channel z (difference of
    the means over its standard error, each half's variance pooled over 3x3 pixels): its mean
    square and the share beyond 3."""
    a, b = (a1 + a2) / 2, (b1 + b2) / 2
    ratio, tiles = tile_check(a, b)

    def box3(x):
        p = np.pad(x, ((1, 1), (1, 1), (0, 0)), mode="edge")
        return sum(p[i:i + x.shape[0], j:j + x.shape[1]] for i in range(3) for j in range(3)) / 9

    se = np.sqrt(box3((a1 - a2) ** 2 / 4) + box3((b1 - b2) ** 2 / 4))
    z = (a - b) / np.maximum(se, 1e-6)
    outliers = float((np.abs(z).max(axis=2) > Z_OUTLIER).mean())
    passed = (abs(ratio - 1) <= MAX_MEAN_LUMINANCE_ERROR and tiles >= MIN_TILES_WITHIN
              and outliers <= MAX_Z_OUTLIERS)
    return {"mean_luminance_ratio": ratio, "tiles_within": tiles, "mean_z2": float((z ** 2).mean()),
            "share_z_over_3": float((np.abs(z) > 3).mean()), "pixels_beyond_6se": outliers,
            "passed": bool(passed)}


def write_png(path, rgb):
    img = bpy.data.images.new(path.stem, rgb.shape[1], rgb.shape[0], float_buffer=True)
    rgba = np.concatenate([rgb[::-1], np.ones(rgb.shape[:2] + (1,))], axis=2).astype(np.float32)
    img.pixels.foreach_set(rgba.ravel())
    img.filepath_raw = str(path)
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)


# --- the two measurements ---------------------------------------------------------------------


def variant_scene(args, out):
    """monastery-rain with absolute asset paths and a closer camera on the west pile (bodies a
    few pixels wide at 320x180 rather than one)."""
    text = (ROOT / "scenes/monastery-rain.toml").read_text()
    assets = (ROOT / "scenes" / "../../shared/assets").resolve()
    if args.assets:
        assets = Path(args.assets).resolve()
    text = text.replace('assets = "../../shared/assets"', f'assets = "{assets}"')
    text = text.replace('camera = "overview"', 'camera = "close"')
    text = text.replace("[[lights]]", """[[cameras]]
name = "close"
position = [-10.0, 32.0, 32.0]
look_at = [-22.0, 4.0, -15.0]
fov_degrees = 40.0

[[lights]]""", 1)
    path = out / "correctness.toml"
    path.write_text(text)
    return path


def export(args, traj, frames, path):
    run_dormant(args, "export", "--trajectory", traj, "--frames", frames, "--out", path)
    return json.loads(Path(path).read_text())


def correctness(args, out):
    """One frame at `--spp` per renderer as two independent halves (seeds 1 and 2 of both)."""
    out.mkdir(parents=True, exist_ok=True)
    scene = variant_scene(args, out)
    traj = out / "correctness.traj"
    f = args.settle_frames
    if not (args.reuse_trajectory and traj.exists()):
        run_dormant(args, "simulate", scene, "--count", args.correct_count, "--frame-count", f, "--out", traj)
    exp = export(args, traj, f"{f - 1}..{f}", out / "correctness.json")
    frame = exp["frames"][0]
    i = frame["index"]
    half = args.spp // 2
    cycles = CyclesScene(exp)
    cycles.pose(frame)
    res = {"frame": i, "bodies": len(frame["poses"]), "spp": args.spp, "size": args.correct_size,
           "dormant_s": [], "cycles_s": [], "cycles_sync_s": []}
    for k in range(2):
        if not (args.reuse_dormant and (out / f"dormant-{k}" / f"frame_{i:04}.exr").exists()):
            wall, _ = dormant_render(args, traj, f"{i}..{i + 1}", out / f"dormant-{k}", half, args.correct_size,
                                     reuse="off", seed_offset=k + 1)
            res["dormant_s"].append(wall)
        configure_render(args, half, args.correct_size, seed=k + 1, persistent=False)
        wall, sync, _ = cycles.render(out / "cycles" / f"half{k}.exr")
        res["cycles_s"].append(wall)
        res["cycles_sync_s"].append(sync)
        log(f"correctness half {k}: dormant {sum(res['dormant_s'][k:k + 1]):.1f} s, cycles {wall:.1f} s (sync {sync:.1f} s)")
    d = [read_exr(out / f"dormant-{k}" / f"frame_{i:04}.exr") for k in range(2)]
    c = [read_exr(out / "cycles" / f"half{k}.exr") for k in range(2)]
    metrics, z = compare_images(d[0], d[1], c[0], c[1])
    res.update(metrics)
    res["checks"] = image_checks(d[0], d[1], c[0], c[1])
    res["negative_controls"] = negative_controls(args, out, cycles, d)
    res["passed"] = res["checks"]["passed"] and not any(n["passed"] for n in res["negative_controls"].values())
    write_png(out / "dormant.png", (d[0] + d[1]) / 2)
    write_png(out / "cycles.png", (c[0] + c[1]) / 2)
    zc = np.clip(z / 6 + 0.5, 0, 1)
    write_png(out / "z.png", np.stack([zc, np.full_like(zc, 0.5), 1 - zc], axis=2))
    return res


def speed(args, out):
    """The rain sequence at 16 spp, interleaved in chunks: dormant, then Cycles in each mode."""
    out.mkdir(parents=True, exist_ok=True)
    traj = out / "rain.traj"
    a, b = map(int, args.rain_frames.split(".."))
    if not (args.reuse_trajectory and traj.exists()):
        t = time.perf_counter()
        run_dormant(args, "simulate", ROOT / "scenes/monastery-rain.toml", "--frame-count", b, "--out", traj)
        log(f"speed: simulated {b} frames in {time.perf_counter() - t:.0f} s")
    rows_log = (out / "frames.jsonl").open("a")
    exp = export(args, traj, f"{a}..{b}", out / "rain.json")
    res = {"frames": f"{a}..{b}", "spp": args.rain_spp, "size": args.rain_size, "dormant": [],
           "cycles": {m: [] for m in args.cycles_modes.split(",")}, "dormant_wall_s": 0.0,
           "cycles_setup_s": 0.0}
    modes = set(res["cycles"])
    if "animation" in modes and modes != {"animation"}:
        sys.exit("compare-cycles: --cycles-modes animation runs alone (it is a different Blender scene)")
    t = time.perf_counter()
    if modes == {"animation"}:
        glb = out / "rain.glb"
        run_dormant(args, "export", "--trajectory", traj, "--gltf", glb)
        cs = CyclesAnimation(glb, exp)
        res["cycles_import_s"] = cs.import_s
    else:
        cs = CyclesScene(exp)  # glTF import and materials, once for every mode
    res["cycles_setup_s"] = time.perf_counter() - t
    frames = exp["frames"]
    for c0 in range(0, len(frames), args.chunk):
        chunk = frames[c0:c0 + args.chunk]
        first, last = chunk[0]["index"], chunk[-1]["index"] + 1
        wall, records = dormant_render(args, traj, f"{first}..{last}", out / "dormant", args.rain_spp, args.rain_size)
        res["dormant_wall_s"] += wall
        res["dormant"] += records
        rows_log.write(json.dumps({"dormant_chunk": [first, last], "wall_s": wall,
                                   "frame_ms": [r["frame_ms"] for r in records],
                                   "trace_ms": [r["trace_ms"] for r in records]}) + "\n")
        rows_log.flush()
        log(f"speed {first}..{last}: dormant {wall:.1f} s")
        for m, rows in res["cycles"].items():
            if m == "animation":
                configure_render(args, args.rain_spp, args.rain_size, seed=0, persistent=True)
                rows += cs.render(first, last, out / "cycles-animation")
                for r in rows[-len(chunk):]:
                    rows_log.write(json.dumps({"cycles": m, **r}) + "\n")
                rows_log.flush()
                log(f"speed {first}..{last}: cycles (animation) {sum(r['wall_s'] for r in rows[-len(chunk):]):.1f} s")
                continue
            todo = chunk if m == "persistent" else frames[len(res["cycles"][m]):args.default_frames]
            if not todo:
                continue  # rebuilt every frame: too slow for every frame on a shared machine
            configure_render(args, args.rain_spp, args.rain_size, seed=0, persistent=(m == "persistent"))
            for fr in todo:
                t = time.perf_counter()
                cs.pose(fr)
                bpy.context.view_layer.update()
                update = time.perf_counter() - t
                wall, sync, trace = cs.render(out / f"cycles-{m}" / f"frame_{fr['index']:04}.exr")
                rows.append({"frame": fr["index"], "update_s": update, "wall_s": wall + update,
                             "sync_s": sync, "trace_s": trace})
                rows_log.write(json.dumps({"cycles": m, **rows[-1]}) + "\n")
                rows_log.flush()
            log(f"speed {first}..{last}: cycles ({m}) {sum(r['wall_s'] for r in rows[-len(todo):]):.1f} s")
    mode = next(iter(res["cycles"]))
    res["noise"] = noise_at_equal_spp(args, out, traj, cs, mode, frames[len(frames) // 2])
    return res


def relative_variance(images):
    """The mean over pixels and channels of the variance across `images` (independent seeds)
    over the squared mean (plus 0.01, as relative MSE): the noise of one such image."""
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    return float((stack.var(axis=0, ddof=1) / (mean ** 2 + 1e-2)).mean())


def noise_at_equal_spp(args, out, traj, cs, mode, frame, seeds=4):
    """Each renderer's noise on `frame` at the sequence's spp, from `seeds` independent seeds
    (dormant --seed-offset, Cycles' seed), against its own mean, so that the other's bias
    does not count. Time to equal noise scales as noise x time (variance falls as 1/spp)."""
    i = frame["index"]
    d, c = [], []
    for k in range(seeds):
        folder = out / "noise" / f"dormant-{k}"
        dormant_render(args, traj, f"{i}..{i + 1}", folder, args.rain_spp, args.rain_size, reuse="off",
                       seed_offset=k + 1)
        d.append(read_exr(folder / f"frame_{i:04}.exr"))
        configure_render(args, args.rain_spp, args.rain_size, seed=k + 1, persistent=(mode != "default"))
        if mode == "animation":
            cs.render(i, i + 1, out / "noise" / f"cycles-{k}")
            c.append(read_exr(out / "noise" / f"cycles-{k}" / f"frame_{i:04}.exr"))
        else:
            cs.pose(frame)
            cs.render(out / "noise" / f"cycles-{k}.exr")
            c.append(read_exr(out / "noise" / f"cycles-{k}.exr"))
    res = {"frame": i, "seeds": seeds, "dormant": relative_variance(d), "cycles": relative_variance(c)}
    log(f"noise at {args.rain_spp} spp, frame {i}: dormant {res['dormant']:.3e}, cycles {res['cycles']:.3e}")
    return res


def negative_controls(args, out, cycles, dormant_halves):
    """Cycles' halves again with the sun 5% dimmer, and with prototype 0's material wrong:
    the image checks must fail both, or they would not catch such a bug."""
    half = args.spp // 2
    controls = {}
    for name, breaker in [("sun_5pct_dimmer", lambda: cycles.break_light(0.95)),
                          ("prototype_0_magenta", lambda: cycles.break_material(0))]:
        restore = breaker()
        broken = []
        for k in range(2):
            configure_render(args, half, args.correct_size, seed=k + 1, persistent=False)
            path = out / f"cycles-{name}" / f"half{k}.exr"
            cycles.render(path)
            broken.append(read_exr(path))
        restore()
        controls[name] = image_checks(dormant_halves[0], dormant_halves[1], broken[0], broken[1])
        log(f"negative control {name}: {controls[name]}")
    return controls


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dormant", default=ROOT / "target/release/dormant", type=Path)
    ap.add_argument("--out", default=ROOT / "out/compare-cycles", type=Path)
    ap.add_argument("--assets", help="asset directory (default: ../shared/assets from the repo)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--max-depth", type=int, default=6, help="dormant --max-depth (Cycles bounces: one less)")
    ap.add_argument("--spp", type=int, default=1024, help="correctness: samples per pixel (two halves)")
    ap.add_argument("--correct-size", default="320x180")
    ap.add_argument("--correct-count", type=int, default=300, help="correctness: bodies dropped")
    ap.add_argument("--settle-frames", type=int, default=720, help="correctness: frames simulated before the compared pair")
    ap.add_argument("--rain-frames", default="0..120", help="speed: frames A..B of monastery-rain")
    ap.add_argument("--rain-spp", type=int, default=16)
    ap.add_argument("--rain-size", default="320x180")
    ap.add_argument("--chunk", type=int, default=10, help="speed: frames per interleaved chunk")
    ap.add_argument("--cycles-modes", default="animation",
                    help="speed: `animation` (alone: dormant's animated glTF imported, keyframed, rendered as "
                         "animation jobs with persistent data, as a user would), or `persistent` (each body posed "
                         "from Python every frame, scene kept) and/or `default` (rebuilt every frame)")
    ap.add_argument("--default-frames", type=int, default=10,
                    help="speed: the first N frames also in Cycles' default mode (persistent mode renders all)")
    ap.add_argument("--reuse-dormant", action="store_true", help="correctness: keep dormant's EXRs of an earlier run")
    ap.add_argument("--reuse-trajectory", action="store_true", help="keep trajectories simulated by an earlier run")
    ap.add_argument("--only", choices=["correctness", "speed"])
    ap.add_argument("--quick", action="store_true",
                    help="the image checks alone on a small frame: --only correctness --spp 256 --correct-size 160x90")
    args = ap.parse_args()
    if args.quick:
        args.only, args.spp, args.correct_size = "correctness", 256, "160x90"
    if not args.dormant.exists():
        sys.exit(f"compare-cycles: {args.dormant} not found (cargo build --release)")
    args.out.mkdir(parents=True, exist_ok=True)
    report = {"blender": bpy.app.version_string, "threads": args.threads, "max_depth": args.max_depth}
    if args.only in (None, "correctness"):
        report["correctness"] = correctness(args, args.out / "correctness")
        (args.out / "report.json").write_text(json.dumps(report, indent=2, default=str))
    if args.only in (None, "speed"):
        report["speed"] = speed(args, args.out / "speed")
    (args.out / "report.json").write_text(json.dumps(report, indent=2, default=str))
    summarize(report)
    if not report.get("correctness", {}).get("passed", True):
        sys.exit("compare-cycles: the image checks failed (or a negative control passed): see report.json")


def summarize(report):
    if "correctness" in report:
        c = report["correctness"]
        log(f"correctness ({c['size']}, {c['spp']} spp): chi2 {c['chi2']:.3f} (bias share {c['bias_share']:.1%}), "
            f"{c['within_3se']:.1%} of pixels within 3 s.e., mean dormant/cycles {c['mean_ratio']:.4f}; "
            f"rel. MSE between {c['rel_mse_between']:.2e}, noise dormant {c['rel_mse_noise_a']:.2e}, "
            f"cycles {c['rel_mse_noise_b']:.2e}; time dormant {sum(c['dormant_s']):.1f} s, cycles {sum(c['cycles_s']):.1f} s")
        k = c["checks"]
        log(f"image checks: mean luminance {k['mean_luminance_ratio']:.4f} (limit 1 +- {MAX_MEAN_LUMINANCE_ERROR}), "
            f"{k['tiles_within']:.1%} of {TILE}x{TILE} tiles within {MAX_TILE_ERROR:.0%} (limit {MIN_TILES_WITHIN:.0%}), "
            f"pixels beyond {Z_OUTLIER:.0f} s.e. {k['pixels_beyond_6se']:.3%} (limit {MAX_Z_OUTLIERS:.1%}), "
            f"mean z^2 {k['mean_z2']:.2f}, |z| > 3 {k['share_z_over_3']:.2%}: {'passed' if k['passed'] else 'FAILED'}; "
            f"negative controls failed: {[n for n, v in c['negative_controls'].items() if not v['passed']]}")
    if "speed" in report:
        s = report["speed"]
        n = len(s["dormant"])
        trace = sum(r["trace_ms"] for r in s["dormant"]) / 1e3
        update = sum(r["frame_ms"] for r in s["dormant"]) / 1e3 - trace
        log(f"speed ({s['frames']}, {s['size']}, {s['spp']} spp): dormant {s['dormant_wall_s']:.1f} s for {n} frames "
            f"(per frame: wall {s['dormant_wall_s'] / n:.2f} s, scene update {update / n:.3f} s, trace {trace / n:.2f} s)")
        for m, rows in s["cycles"].items():
            tot = sum(r["wall_s"] for r in rows) + s["cycles_setup_s"]
            sync = sum(r["sync_s"] for r in rows)
            k = max(len(rows), 1)
            pose = sum(r["update_s"] for r in rows)
            trace_c = sum(r["trace_s"] for r in rows)
            log(f"  cycles {m}: {tot:.1f} s for {len(rows)} frames (setup {s['cycles_setup_s']:.1f} s; per frame: wall "
                f"{(tot - s['cycles_setup_s']) / k:.2f} s, pose update {pose / k:.3f} s, sync {sync / k:.3f} s, "
                f"trace {trace_c / k:.2f} s); dormant/cycles per frame {s['dormant_wall_s'] / n / ((tot - s['cycles_setup_s']) / k):.2f}")
            if "noise" in s:
                v = s["noise"]["dormant"] / s["noise"]["cycles"]
                per = s["dormant_wall_s"] / n / ((tot - s["cycles_setup_s"]) / k)
                log(f"  noise dormant/cycles at equal spp {v:.3f}: dormant's time to Cycles' noise over Cycles' time "
                    f"{per * v:.2f} (per frame, setup apart)")


if __name__ == "__main__":
    main()
