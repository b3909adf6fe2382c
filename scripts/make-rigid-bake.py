#!/usr/bin/env python3
"""Writes a rigid-body bake as Blender's glTF exporter lays one out, for timing the animated
glTF import: a static ground, and N boxes (each its own mesh, as Cell Fracture shards are)
that fall from staggered heights and land at different frames; one animation per object
with translation and rotation keys at every frame (LINEAR), as a baked simulation has.

    python3 scripts/make-rigid-bake.py --bodies 10000 --frames 60 --fps 24 --out bake.glb

Standard library only."""

import argparse
import json
import math
import struct


def pack(values, fmt):
    return b"".join(struct.pack("<" + fmt, v) for v in values)


class Glb:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def accessor(self, data, count, kind, component=5126, bounds=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)})
        self.bin += data
        a = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if bounds:
            a["min"], a["max"] = bounds
        self.accessors.append(a)
        return len(self.accessors) - 1


def box(glb, hx, hy, hz):
    corners = [((i & 1) * 2 - 1) * hx for i in range(8)], [((i >> 1 & 1) * 2 - 1) * hy for i in range(8)], [((i >> 2 & 1) * 2 - 1) * hz for i in range(8)]
    positions = [c for i in range(8) for c in (corners[0][i], corners[1][i], corners[2][i])]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    indices = [i for f in faces for i in (f[0], f[1], f[2], f[0], f[2], f[3])]
    p = glb.accessor(pack(positions, "f"), 8, "VEC3", bounds=([-hx, -hy, -hz], [hx, hy, hz]))
    i = glb.accessor(pack(indices, "I"), len(indices), "SCALAR", component=5125)
    return {"primitives": [{"attributes": {"POSITION": p}, "indices": i, "material": 1}]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bodies", type=int, default=10000)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--fps", type=float, default=24.0)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    glb = Glb()
    ground = glb.accessor(pack([-200, 0, -200, 200, 0, -200, 200, 0, 200, -200, 0, 200], "f"), 4, "VEC3", bounds=([-200, 0, -200], [200, 0, 200]))
    ground_ix = glb.accessor(pack([0, 2, 1, 0, 3, 2], "I"), 6, "SCALAR", component=5125)
    meshes = [{"name": "Ground", "primitives": [{"attributes": {"POSITION": ground}, "indices": ground_ix, "material": 0}]}]
    nodes = [{"name": "Ground", "mesh": 0}]
    animations = []
    times = [i / args.fps for i in range(args.frames)]
    time_accessor = glb.accessor(pack(times, "f"), len(times), "SCALAR", bounds=([times[0]], [times[-1]]))
    side = math.ceil(math.sqrt(args.bodies))
    for b in range(args.bodies):
        h = 0.2 + 0.1 * ((b * 7) % 5) / 4
        meshes.append({"name": f"Shard.{b:05d}", **box(glb, 0.25, h, 0.25)})
        x, z = (b % side - side / 2) * 0.8, (b // side - side / 2) * 0.8
        drop = 1.0 + 3.0 * ((b * 13) % 17) / 16
        translations, rotations = [], []
        for t in times:
            y = max(h, h + drop - 4.9 * t * t)
            spin = 0.0 if y == h else 2.0 * t
            translations += [x, y, z]
            rotations += [0.0, math.sin(spin / 2), 0.0, math.cos(spin / 2)]
        node = len(nodes)
        nodes.append({"name": f"Shard.{b:05d}", "mesh": len(meshes) - 1})
        tr = glb.accessor(pack(translations, "f"), len(times), "VEC3")
        ro = glb.accessor(pack(rotations, "f"), len(times), "VEC4")
        animations.append({
            "name": f"Shard.{b:05d}Action",
            "samplers": [{"input": time_accessor, "output": tr, "interpolation": "LINEAR"}, {"input": time_accessor, "output": ro, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": node, "path": "translation"}}, {"sampler": 1, "target": {"node": node, "path": "rotation"}}],
        })
    while len(glb.bin) % 4:
        glb.bin.append(0)
    doc = {
        "asset": {"version": "2.0", "generator": "dormant scripts/make-rigid-bake.py"},
        "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}},
                      {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.4, 0.2, 1], "metallicFactor": 0}}],
        "animations": animations, "accessors": glb.accessors, "bufferViews": glb.views,
        "buffers": [{"byteLength": len(glb.bin)}],
    }
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(glb.bin)
    with open(args.out, "wb") as f:
        f.write(b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON" + text)
        f.write(struct.pack("<I", len(glb.bin)) + b"BIN\0" + bytes(glb.bin))


if __name__ == "__main__":
    main()
