#!/usr/bin/env python3
"""Blender's rigid bodies through dormant, and dormant's export into Blender
(`make blender-roundtrip`; not in CI: it needs the PyPI `bpy` that `make compare-cycles`
installs, and a few minutes).

  bake     builds a rigid-body scene from Python: a passive ground, N objects of three shapes
           (boxes, spheres, cylinders) dropped from a grid, and one box lying on the ground
           from the start (it rests for most of the run); bakes the simulation to keyframes
           and exports it with Blender's own glTF exporter (one animation per object);
  images   dormant renders the two last frames of that file (settled) as a user would, the
           file alone given as the scene (`dormant render rigid.glb`: its camera, its sun,
           24 fps, dormant's default sky); Cycles renders the same two frames in the same
           session with Blender's own sun and dormant's sky (read from `dormant export`),
           each at SPP samples with independent seeds; the images are compared as `make
           compare-cycles` does, with thresholds: mean luminance within 1%, the mean of each
           16x16 tile within 3% in at least 99% of tiles. The sun reaches dormant through
           the exporter's photometric units (a strength of 3 W/m^2 written as 2049 lux);
           the check is that it arrives at Blender's strength. The materials are Lambertian by default (Specular IOR Level 0, which the
           exporter writes as KHR_materials_specular); `--specular 0.5` gives them glTF's
           specular layer (F0 0.04), which both renderers layer as Principled v2 does
           (mean luminance 1.0021 on 2026-12-07; 2.5% apart before dormant's base took that
           layering, docs/lab/cycles.md);
  import   `dormant export --gltf` of scenes/tiny.toml is imported by Blender's glTF
           importer (the scene's frame rate set to the file's) and every body's world
           transform at several frames is compared with dormant's own poses: within 1e-4 of
           the scene's size.

Blender's exporter writes no world: Cycles gets the sky dormant uses for a file without one.
The sun (SUN below) and the camera are Blender's, exported in the file (dormant uses a
file's first directional light as its sun, and its first camera).
Writes out/blender-roundtrip/report.json; exits 1 when a check fails.
"""

import argparse
import importlib.util
import json
import math
import random
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np

try:
    import bpy
    from mathutils import Matrix, Quaternion, Vector
except ImportError:  # pragma: no cover - the Makefile runs this under the bpy venv
    sys.exit("blender-roundtrip: needs the `bpy` module (make blender-roundtrip installs it)")

ROOT = Path(__file__).resolve().parent.parent
# The Cycles comparison's scene helpers and image metric, shared rather than copied.
_spec = importlib.util.spec_from_file_location("compare_cycles", ROOT / "scripts" / "compare-cycles.py")
cc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cc)

FPS = 24  # also the rate dormant gives a glTF file that records none
# dormant's Y-up direction the light travels; W/m^2 on a surface facing it (Blender's
# strength); a disc of 2 degrees across, as dormant gives a file's directional light.
SUN = {"direction": (-0.4, -1.0, -0.3), "irradiance": 3.0, "angle_deg": 2.0}
SHAPES = ("box", "sphere", "cylinder")
COLORS = ((0.8, 0.25, 0.18), (0.2, 0.45, 0.8), (0.85, 0.7, 0.25))


def log(msg):
    print(f"blender-roundtrip: {msg}", flush=True)


# --- the rigid-body scene ---------------------------------------------------------------------


SPECULAR = [0.0]  # Principled "Specular IOR Level" of every material (--specular)


def material(name, rgb):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.6
    bsdf.inputs["Metallic"].default_value = 0.0
    # 0.5 is glTF's F0 of 0.04 (dormant's specular 1); 0 leaves both renderers Lambertian
    # (the exporter writes KHR_materials_specular's factor, 2x the level).
    bsdf.inputs["Specular IOR Level"].default_value = SPECULAR[0]
    return mat


def add_shape(kind, location, rotation, mat):
    if kind == "box":
        bpy.ops.mesh.primitive_cube_add(size=0.4, location=location, rotation=rotation)
    elif kind == "sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, segments=16, ring_count=8, location=location)
    else:
        bpy.ops.mesh.primitive_cylinder_add(radius=0.2, depth=0.4, vertices=16, location=location, rotation=rotation)
    obj = bpy.context.active_object
    obj.data.materials.append(mat)
    return obj


def build_scene(count, frames, seed):
    """The scene in the module docs; returns the active bodies."""
    cc.reset_blender()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = FPS, 1, frames
    rng = random.Random(seed)
    mats = [material(f"{s}-material", c) for s, c in zip(SHAPES, COLORS)]
    bpy.ops.mesh.primitive_plane_add(size=24.0, location=(0, 0, 0))
    ground = bpy.context.active_object
    ground.data.materials.append(material("ground", (0.6, 0.6, 0.6)))
    bpy.ops.rigidbody.world_add()
    scene.rigidbody_world.point_cache.frame_start, scene.rigidbody_world.point_cache.frame_end = 1, frames
    bodies = [add_shape("box", (-4.0, -4.0, 0.2), (0, 0, 0.3), mats[0])]
    side = math.ceil(math.sqrt(count / 4))
    for i in range(count - 1):
        x, y, layer = i % side, (i // side) % side, i // (side * side)
        location = ((x - side / 2) * 0.6, (y - side / 2) * 0.6, 2.0 + 0.6 * layer)
        rotation = tuple(rng.uniform(0, math.tau) for _ in range(3))
        kind = SHAPES[i % 3]
        bodies.append(add_shape(kind, location, rotation, mats[i % 3]))
    select(bodies)
    bpy.ops.rigidbody.objects_add(type="ACTIVE")
    for o in bodies:
        o.rigid_body.use_deactivation = True  # Bullet puts settled bodies to sleep, as users set it
    select([ground])
    bpy.ops.rigidbody.objects_add(type="PASSIVE")
    cam_data = bpy.data.cameras.new("camera")
    camera = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(camera)
    camera.location = (0.0, -13.0, 7.0)
    camera.rotation_euler = (math.radians(62), 0.0, 0.0)
    cam_data.sensor_fit, cam_data.angle_y = "VERTICAL", math.radians(40)
    scene.camera = camera
    sun = cc.add_light("sun", "SUN", [SUN["irradiance"]] * 3, direction=SUN["direction"])
    sun.angle = math.radians(SUN["angle_deg"])
    return bodies


def select(objects):
    bpy.ops.object.select_all(action="DESELECT")
    for o in objects:
        o.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]


def bake_and_export(bodies, frames, glb):
    """Bakes the simulation and turns it into keyframes as Object > Rigid Body > Bake To
    Keyframes does (that operator needs Blender's UI context): every body's world transform at
    every frame, the rigid bodies removed, location and rotation keyed."""
    scene = bpy.context.scene
    bpy.ops.ptcache.bake_all(bake=True)
    poses = {}
    for f in range(1, frames + 1):
        scene.frame_set(f)
        poses[f] = [o.matrix_world.copy() for o in bodies]
    select(bodies)
    bpy.ops.rigidbody.objects_remove()
    for o in bodies:
        o.rotation_mode = "QUATERNION"
    for f, matrices in poses.items():
        for o, m in zip(bodies, matrices):
            o.matrix_world = m
            o.keyframe_insert("location", frame=f)
            o.keyframe_insert("rotation_quaternion", frame=f)
    bpy.ops.export_scene.gltf(
        filepath=str(glb), export_format="GLB", export_animations=True, export_cameras=True,
        export_lights=True, export_yup=True,
    )


def first_key_time(glb):
    """The earliest animation key time in a GLB (how the exporter maps Blender frames)."""
    data = Path(glb).read_bytes()
    length = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + length])
    inputs = {s["input"] for a in doc.get("animations", []) for s in a["samplers"]}
    return min(doc["accessors"][i]["min"][0] for i in inputs)


# --- images -----------------------------------------------------------------------------------


def dormant_sky(args, glb, out):
    """The sky dormant renders the file under (`dormant export`'s, the default daylight)."""
    path = out / "rigid-export.json"
    subprocess.run([str(args.dormant), "--quiet", "export", str(glb), "--frames", "0..1", "--out", str(path)],
                   check=True)
    return json.loads(path.read_text())["sky"]


def images(args, out, glb, frames):
    offset = 1 if first_key_time(glb) == 0.0 else 0  # Blender frame of dormant's frame 0
    pair = [frames - 1 - offset - 1, frames - 1 - offset]
    half = args.spp
    for i in pair:
        subprocess.run([str(args.dormant), "--quiet", "--threads", str(args.threads), "render", str(glb),
                        "--frames", f"{i}..{i + 1}", "--spp", str(half), "--size", args.size, "--max-depth",
                        str(args.max_depth), "--seed", "per-frame", "--reuse", "off", "--exr", "--out",
                        str(out / "dormant"), *cc.MATCHING_FLAGS], check=True)
    cc.build_world(dormant_sky(args, glb, out))
    cc.match_materials()
    scene = bpy.context.scene
    for k, i in enumerate(pair):
        scene.frame_set(i + offset)
        cc.configure_render(args, half, args.size, seed=k + 1, persistent=False)
        scene.render.filepath = str(out / "cycles" / f"frame_{i:04}.exr")
        bpy.ops.render.render(write_still=True)
    d = [cc.read_exr(out / "dormant" / f"frame_{i:04}.exr") for i in pair]
    c = [cc.read_exr(out / "cycles" / f"frame_{i:04}.exr") for i in pair]
    metrics, _ = cc.compare_images(d[0], d[1], c[0], c[1])
    ratio, tiles = cc.tile_check((d[0] + d[1]) / 2, (c[0] + c[1]) / 2)
    cc.write_png(out / "dormant.png", (d[0] + d[1]) / 2)
    cc.write_png(out / "cycles.png", (c[0] + c[1]) / 2)
    passed = abs(ratio - 1) <= cc.MAX_MEAN_LUMINANCE_ERROR and tiles >= cc.MIN_TILES_WITHIN
    metrics.update({"frames": pair, "blender_frame_of_frame_0": offset, "luminance_ratio": ratio,
                    "tiles_within_3pct": tiles, "passed": passed})
    return metrics


# --- dormant's export into Blender ------------------------------------------------------------


def import_check(args, out):
    glb, poses = out / "tiny.glb", out / "tiny-poses.json"
    tiny = ROOT / "scenes" / "tiny.toml"
    subprocess.run([str(args.dormant), "--quiet", "export", str(tiny), "--gltf", str(glb)], check=True)
    subprocess.run([str(args.dormant), "--quiet", "export", str(tiny), "--frame-step", "1", "--out", str(poses)],
                   check=True)
    exported = json.loads(poses.read_text())
    cc.reset_blender()
    scene = bpy.context.scene
    # The importer turns key times into frames at the scene's rate: set it to the file's first.
    scene.render.fps, scene.render.fps_base = round(1.0 / exported["timestep"]), 1.0
    bpy.ops.import_scene.gltf(filepath=str(glb))
    bodies = {o.name: o for o in bpy.data.objects if o.name.startswith("body ")}
    frames = exported["frames"]
    picks = [frames[len(frames) * k // 5] for k in range(5)] + [frames[-1]]
    # Where the importer puts key time 0 (frame 0 or the scene's frame 1): the better of both.
    offset = min((0, 1), key=lambda o: largest_difference(scene, bodies, picks[1:2], o))
    worst = largest_difference(scene, bodies, picks, offset)
    size = scene_size(exported)
    return {"bodies": len(bodies), "frames_checked": [f["index"] for f in picks], "scene_size": size,
            "blender_frame_of_frame_0": offset, "largest_difference": worst,
            "passed": len(bodies) > 0 and worst <= 1e-4 * size}


def largest_difference(scene, bodies, picks, offset):
    """The largest difference of a world-matrix entry between Blender's imported bodies at
    frame index + `offset` and dormant's poses, over the frames `picks`."""
    worst = 0.0
    for fr in picks:
        scene.frame_set(fr["index"] + offset)
        for b, pose in enumerate(fr["poses"]):
            obj = bodies.get(f"body {b}")
            if pose is None or obj is None:
                continue
            expected = cc.placement(1.0, pose=pose)
            worst = max(worst, max(abs(obj.matrix_world[r][c] - expected[r][c]) for r in range(3) for c in range(4)))
    return worst


def scene_size(exported):
    """The diagonal of the box around every body position over the run."""
    points = np.array([p[:3] for f in exported["frames"] for p in f["poses"] if p], dtype=float)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 1.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dormant", type=Path, default=ROOT / "target" / "release" / "dormant")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "blender-roundtrip")
    ap.add_argument("--count", type=int, default=300)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--size", default="320x180")
    ap.add_argument("--max-depth", type=int, default=4)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--only", choices=("blender", "dormant"), help="run only one direction")
    ap.add_argument("--specular", type=float, default=0.0,
                    help="Principled Specular IOR Level of every material (0: Lambertian in both renderers)")
    args = ap.parse_args()
    SPECULAR[0] = args.specular
    args.out.mkdir(parents=True, exist_ok=True)
    report = {"count": args.count, "frames": args.frames}
    if args.only != "dormant":
        report["images"] = from_blender(args)
        log(f"images: {report['images']}")
    if args.only != "blender":
        report["import"] = import_check(args, args.out)
        log(f"import: {report['import']}")
    (args.out / "report.json").write_text(json.dumps(report, indent=1))
    sys.exit(0 if all(r["passed"] for r in report.values() if isinstance(r, dict)) else 1)


def from_blender(args):
    """Blender's bake into dormant: build, bake, export, simulate (rests found), compare."""
    glb = args.out / "rigid.glb"
    bodies = build_scene(args.count, args.frames, args.seed)
    bake_and_export(bodies, args.frames, glb)
    log(f"exported {glb} ({glb.stat().st_size} bytes, {len(bodies)} bodies, {args.frames} frames)")
    simulated = subprocess.run([str(args.dormant), "simulate", str(glb), "--out", str(args.out / "rigid.traj")],
                               check=True, capture_output=True, text=True)
    result = images(args, args.out, glb, args.frames)
    result.update({"glb_bytes": glb.stat().st_size, "rests": simulated.stdout.strip().splitlines()[-1]})
    return result



if __name__ == "__main__":
    main()
