#!/usr/bin/env python3
"""Writes the small generated seeds of the fuzz corpora (docs/fuzzing.md): tiny glTF files
(`.glb` for gltf_glb, `.gltf` JSON with its buffer after a NUL for gltf_json), trajectories of
format versions 1, 2 and 3, and command-line values. Deterministic: running it again writes
the same bytes. Usage: scripts/fuzz-seeds.py [CORPUS_DIR] (default fuzz/corpus)."""

import base64
import json
import os
import struct
import sys
import zlib


def png_rgba(width, height, pixel):
    """A width x height PNG filled with one RGBA pixel."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    rows = b"".join(b"\x00" + bytes(pixel) * width for _ in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")


def pad4(data, fill=b"\x00"):
    return data + fill * (-len(data) % 4)


class Builder:
    """A glTF document with one binary buffer, built view by view."""

    def __init__(self):
        self.bin = b""
        self.doc = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [], "accessors": []}

    def view(self, data, target=None):
        self.bin = pad4(self.bin)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            view["target"] = target
        self.bin += data
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, fmt, values, kind, component, **extra):
        data = b"".join(struct.pack("<" + fmt, *v) if isinstance(v, tuple) else struct.pack("<" + fmt, v)
                        for v in values)
        acc = {"bufferView": self.view(data), "componentType": component, "count": len(values), "type": kind}
        if kind == "VEC3" and component == 5126:
            acc["min"] = [min(v[i] for v in values) for i in range(3)]
            acc["max"] = [max(v[i] for v in values) for i in range(3)]
        acc.update(extra)
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def finish(self, uri=None):
        buffer = {"byteLength": len(pad4(self.bin))}
        if uri:
            buffer["uri"] = uri
        self.doc["buffers"] = [buffer]
        return self.doc, pad4(self.bin)


def quad(textured):
    """An indexed quad with normals, UVs and a material (with an embedded PNG texture)."""
    b = Builder()
    pos = b.accessor("fff", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], "VEC3", 5126)
    nrm = b.accessor("fff", [(0, 0, 1)] * 4, "VEC3", 5126)
    uv = b.accessor("ff", [(0, 0), (1, 0), (1, 1), (0, 1)], "VEC2", 5126)
    idx = b.accessor("H", [0, 1, 2, 0, 2, 3], "SCALAR", 5123)
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1], "roughnessFactor": 0.5}}
    if textured:
        image = b.view(png_rgba(2, 2, (200, 100, 50, 255)))
        b.doc["images"] = [{"bufferView": image, "mimeType": "image/png"}]
        b.doc["samplers"] = [{"wrapS": 33071, "wrapT": 33648}]
        b.doc["textures"] = [{"source": 0, "sampler": 0}]
        material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        material["emissiveTexture"] = {"index": 0}
    b.doc["materials"] = [material]
    attributes = {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}
    b.doc["meshes"] = [{"primitives": [{"attributes": attributes, "indices": idx, "material": 0}]}]
    b.doc["nodes"] = [{"mesh": 0, "translation": [0, 1, 0]}]
    b.doc["scenes"] = [{"nodes": [0]}]
    b.doc["scene"] = 0
    return b


def scene_graph():
    """Two meshes (one unindexed, one with u8 indices and no material) in a node hierarchy
    with a camera, punctual lights and a rotation, scale and matrix."""
    b = Builder()
    tri = b.accessor("fff", [(0, 0, 0), (1, 0, 0), (0, 0, 1)], "VEC3", 5126)
    pos = b.accessor("fff", [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)], "VEC3", 5126)
    idx = b.accessor("B", [0, 1, 2, 0, 2, 3], "SCALAR", 5121)
    uv = b.accessor("BB", [(0, 0), (255, 0), (255, 255), (0, 255)], "VEC2", 5121, normalized=True)
    b.doc["meshes"] = [
        {"primitives": [{"attributes": {"POSITION": tri}, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "indices": idx},
                        {"attributes": {"POSITION": tri}, "mode": 1}]},
    ]
    b.doc["materials"] = [{"emissiveFactor": [1, 0.5, 0], "extensions": {
        "KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}]
    b.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}},
                        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]
    b.doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength", "EXT_unknown"]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 10, "color": [1, 0.9, 0.8]},
        {"type": "spot", "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 2}]}}
    b.doc["nodes"] = [
        {"children": [1, 2, 3], "rotation": [0, 0.7071068, 0, 0.7071068], "scale": [2, 2, 2]},
        {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 3, 0, 0, 1]},
        {"mesh": 1, "camera": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"camera": 1, "children": [4], "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}},
    ]
    b.doc["scenes"] = [{"nodes": [0]}]
    return b


def sparse():
    """A mesh whose positions are a sparse accessor over a base view, with no scene (its
    root nodes are used)."""
    b = Builder()
    base = b.view(struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0))
    ix = b.view(struct.pack("<H", 2))
    vals = b.view(struct.pack("<3f", 0, 2, 0))
    b.doc["accessors"].append({"bufferView": base, "componentType": 5126, "count": 3, "type": "VEC3",
                               "min": [0, 0, 0], "max": [1, 2, 0],
                               "sparse": {"count": 1, "indices": {"bufferView": ix, "componentType": 5123},
                                          "values": {"bufferView": vals}}})
    b.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0}}]}]
    b.doc["nodes"] = [{"mesh": 0}]
    return b


def glb(doc, bin_data):
    text = pad4(json.dumps(doc, separators=(",", ":")).encode(), b" ")
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(bin_data), b"BIN\x00") + bin_data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def gltf_with_bin(builder):
    """gltf_json's input: the JSON referencing its buffer as "@BIN@", a NUL, the buffer."""
    doc, bin_data = builder.finish(uri="@BIN@")
    return json.dumps(doc, indent=1).encode() + b"\x00" + bin_data


def gltf_data_uri(builder):
    doc, bin_data = builder.finish()
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(bin_data).decode()
    return json.dumps(doc, indent=1).encode()


def fnv1a64(data, h=0xCBF29CE484222325):
    for byte in data:
        h = ((h ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def trajectory(version):
    """Three bodies over four frames: spawned, fallen asleep as one island, woken."""
    u32 = lambda v: struct.pack("<I", v)
    text = lambda s: u32(len(s.encode())) + s.encode()
    pose = lambda x, y: struct.pack("<7f", x, y, 0, 0, 0, 0, 1)
    scene = '[scene]\nname = "t"\nframes = 9\n[environment]\ngenerator = "ground"\n' \
            '[[prototypes]]\nname = "box"\nshape = "box"\nhalf_extents = [0.5, 0.5, 0.5]\n'
    # The hash of the scene with its `frames = 4` override (SceneFile::with_frames).
    scene_hash = fnv1a64(u32(4), fnv1a64(b"frames", fnv1a64(scene.encode())))
    out = b"DORMTRAJ" + u32(version) + struct.pack("<Qf", scene_hash, 1 / 60)
    if version >= 2:
        out += b"\x01" + text("scenes/t.toml") + text("/nonexistent/assets") + text(scene)
        out += b"\x00" + u32(0) + b"\x01" + u32(4)
    out += u32(1) + text("box")
    out += u32(3) + b"".join(u32(0) + bytes([kind]) + u32(spawn) for kind, spawn in [(1, 0), (0, 0), (0, 1)])
    slept = b"\x00" + struct.pack("<Q", 7) + u32(2) + u32(1) + pose(1, 1) + u32(2) + pose(2, 3)
    woke = b"\x01" + struct.pack("<Q", 7)
    # (states of the three bodies, poses written, events) per frame
    frames = [
        ([1, 1, 0], [(0, pose(0, 0)), (1, pose(1, 2))], []),
        ([1, 1, 1], [(0, pose(0, 1)), (1, pose(1, 1)), (2, pose(2, 3))], []),
        ([1, 2, 2], [(0, pose(0, 2))], [slept]),
        ([1, 1, 1], [(0, pose(0, 3))], [woke]),
    ]
    out += u32(len(frames))
    previous = [0, 0, 0]
    for states, poses, events in frames:
        if version >= 3:
            changed = [(i, s) for i, s in enumerate(states) if s != previous[i]]
            out += u32(len(changed)) + b"".join(u32(i) + bytes([s]) for i, s in changed)
        else:
            out += bytes(states)
        previous = states
        out += u32(len(poses)) + b"".join(u32(i) + p for i, p in poses)
        out += u32(len(events)) + b"".join(events)
    return out + struct.pack("<Q", fnv1a64(out))


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "fuzz/corpus"
    seeds = {
        "gltf_glb/quad-textured.glb": glb(*quad(True).finish()),
        "gltf_glb/quad.glb": glb(*quad(False).finish()),
        "gltf_glb/scene-graph.glb": glb(*scene_graph().finish()),
        "gltf_glb/sparse.glb": glb(*sparse().finish()),
        "gltf_json/quad-textured.gltf": gltf_with_bin(quad(True)),
        "gltf_json/scene-graph.gltf": gltf_with_bin(scene_graph()),
        "gltf_json/sparse.gltf": gltf_with_bin(sparse()),
        "gltf_json/quad-data-uri.gltf": gltf_data_uri(quad(False)),
        "trajectory/generated-v1.traj": trajectory(1),
        "trajectory/generated-v2.traj": trajectory(2),
        "trajectory/generated-v3.traj": trajectory(3),
    }
    for i, value in enumerate(["0..120", "3..10", " 7 .. 8", "0..4294967295", "640x360", "1280X720",
                               "16384x16384", "1x1", "960x540"]):
        seeds[f"cli_values/value-{i}"] = value.encode()
    for name, data in seeds.items():
        path = os.path.join(root, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
    print(f"wrote {len(seeds)} seeds under {root}")


if __name__ == "__main__":
    main()
