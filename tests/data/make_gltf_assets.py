#!/usr/bin/env python3
"""Writes quad_scene.gltf and quad_scene.glb, the small glTF scene the loader tests own, and
animated_nodes.gltf, the node animations of tests/unit/gltf_animation_test.cpp.

Run from anywhere: python3 tests/data/make_gltf_assets.py. Layout, so tests can predict results:
  node 0 "root"   translation (0,1,0), child node 1
  node 1 "quad"   T (1,2,3) * R (90 deg about +Y) * S (2): mesh 0, a unit quad in z=0 with
                  normals, interleaved position+normal (byteStride 24), uint16 indices, material 0
  node 2 "strip"  matrix translating by (0,0,-5): mesh 1, a 4-vertex TRIANGLE_STRIP without
                  normals or indices and without a material
  node 3 "camera" at (0,1,10), perspective yfov 0.8 rad, znear 0.05, zfar 200, aspect 1.5
  node 4 "lamp"   at (0,4,0), KHR_lights_punctual point light 0: colour (1,0.5,0.25), intensity 20
  node 5 "sun"    rotated -90 deg about +X, so its -Z points down: directional light 1
  material 0 "emitter": base (0.8,0.2,0.1), metallic 0, roughness 0.5, emissive (1,0.5,0.25) x 4
  material 1 "glass":   base (1,1,1), metallic 0, roughness 0, ior 1.5, transmission 0.9,
                        doubleSided (material 0 is not: one-sided, glTF's default)

animated_nodes.gltf (one embedded buffer; every mesh is the triangle (0,0,0) (1,0,0) (0,1,0)):
  node 0 "arm"    translation (0,2,0), mesh "arm"; a child of node 1 that comes before it
  node 1 "base"   root, translation (1,0,0), children 0 and 2
  node 2 "head"   no transform, mesh "head", child node 3
  node 3 "hat"    translation (0,0,1), mesh "hat"
  node 4 "fixed"  root, matrix translating by (0,0,-3), mesh "fixed" (not animatable)
  animation 0 "walk", LINEAR, keys at 0 s and 2 s:
    channel 0: arm translation (0,2,0) -> (4,2,0)
    channel 1: head rotation 0 -> 90 deg about +Y (quaternions (0,0,0,1) -> (0,s,0,s), s = 1/sqrt2)
  animation 1 "hop", STEP, keys at 0, 1 and 2 s:
    channel 0: base scale 1 -> 2 -> 0.5 (uniform)
  animation 2 "spline", CUBICSPLINE, keys at 0 s and 2 s (in-tangent, value, out-tangent each):
    channel 0: hat translation, key 0: (0,0,0) (0,0,1) (3,0,0); key 1: (0,1,0) (2,0,1) (0,0,0).
    Halfway (t = 1, s = 1/2, td = 2) the Hermite basis is 1/2, 1/8, 1/2, -1/8, so the value is
    (0,0,1)/2 + 2*(3,0,0)/8 + (2,0,1)/2 - 2*(0,1,0)/8 = (1.75, -0.25, 1); linear would be (1,0,1).
  accessors: 0 triangle positions, 1 times [0,2], 2 times [0,1,2], 3 walk translations,
             4 walk rotations, 5 hop scales, 6 spline translations (each its own bufferView)
"""
import base64
import json
import math
import struct
from pathlib import Path

HERE = Path(__file__).resolve().parent

quad = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
quad_indices = [0, 1, 2, 0, 2, 3]
strip = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]

interleaved = b"".join(struct.pack("<6f", *p, 0, 0, 1) for p in quad)  # 96 bytes
indices = struct.pack("<6H", *quad_indices)                             # 12 bytes
strip_bytes = b"".join(struct.pack("<3f", *p) for p in strip)           # 48 bytes
blob = interleaved + indices + strip_bytes
assert len(interleaved) == 96 and len(indices) == 12 and len(blob) == 156

s45 = math.sqrt(0.5)
doc = {
    "asset": {"version": "2.0", "generator": "tests/data/make_gltf_assets.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                       "KHR_materials_ior", "KHR_materials_transmission"],
    "scene": 0,
    "scenes": [{"nodes": [0, 2, 3, 4, 5]}],
    "nodes": [
        {"name": "root", "translation": [0, 1, 0], "children": [1]},
        {"name": "quad", "mesh": 0, "translation": [1, 2, 3],
         "rotation": [0, s45, 0, s45], "scale": [2, 2, 2]},
        {"name": "strip", "mesh": 1,
         "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -5, 1]},
        {"name": "camera", "camera": 0, "translation": [0, 1, 10]},
        {"name": "lamp", "translation": [0, 4, 0],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "sun", "rotation": [-s45, 0, 0, s45],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
    ],
    "meshes": [
        {"name": "quad", "primitives": [
            {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0, "mode": 4}]},
        {"name": "strip", "primitives": [{"attributes": {"POSITION": 3}, "mode": 5}]},
    ],
    "materials": [
        {"name": "emitter",
         "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.5},
         "emissiveFactor": [1.0, 0.5, 0.25],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}},
        {"name": "glass", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.0},
         "extensions": {"KHR_materials_ior": {"ior": 1.5},
                        "KHR_materials_transmission": {"transmissionFactor": 0.9}}},
    ],
    "cameras": [{"type": "perspective",
                 "perspective": {"yfov": 0.8, "znear": 0.05, "zfar": 200, "aspectRatio": 1.5}}],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 20.0},
        {"type": "directional", "color": [1, 1, 1], "intensity": 3.0},
    ]}},
    "buffers": [{"byteLength": len(blob)}],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 24, "target": 34962},
        {"buffer": 0, "byteOffset": 96, "byteLength": 12, "target": 34963},
        {"buffer": 0, "byteOffset": 108, "byteLength": 48, "target": 34962},
    ],
    "accessors": [
        {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [0, 0, 0], "max": [1, 1, 0]},
        {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [0, 0, 0], "max": [1, 1, 0]},
    ],
}


def write_gltf():
    text = dict(doc)
    text["buffers"] = [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(blob).decode("ascii")}]
    (HERE / "quad_scene.gltf").write_text(json.dumps(text, indent=1) + "\n")


def write_glb():
    json_chunk = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    json_chunk += b" " * (-len(json_chunk) % 4)  # chunks are 4-byte aligned
    bin_chunk = blob + b"\0" * (-len(blob) % 4)
    body = (struct.pack("<I4s", len(json_chunk), b"JSON") + json_chunk
            + struct.pack("<I4s", len(bin_chunk), b"BIN\0") + bin_chunk)
    header = struct.pack("<4sII", b"glTF", 2, 12 + len(body))
    (HERE / "quad_scene.glb").write_bytes(header + body)


def write_animated():
    tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    parts = [
        b"".join(struct.pack("<3f", *p) for p in tri),                     # 0 positions
        struct.pack("<2f", 0, 2),                                           # 1 times
        struct.pack("<3f", 0, 1, 2),                                        # 2 times
        struct.pack("<6f", 0, 2, 0, 4, 2, 0),                               # 3 walk translation
        struct.pack("<8f", 0, 0, 0, 1, 0, s45, 0, s45),                     # 4 walk rotation
        struct.pack("<9f", 1, 1, 1, 2, 2, 2, 0.5, 0.5, 0.5),                # 5 hop scale
        struct.pack("<18f", 0, 0, 0, 0, 0, 1, 3, 0, 0, 0, 1, 0, 2, 0, 1, 0, 0, 0),  # 6 spline
    ]
    views, offset = [], 0
    for part in parts:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(part)})
        offset += len(part)
    data = b"".join(parts)

    def accessor(view, count, kind, **extra):
        return {"bufferView": view, "componentType": 5126, "count": count, "type": kind, **extra}

    def sampler(input_accessor, output_accessor, interpolation):
        return {"input": input_accessor, "output": output_accessor, "interpolation": interpolation}

    def channel(sampler_index, node, path):
        return {"sampler": sampler_index, "target": {"node": node, "path": path}}

    def triangle(name):
        return {"name": name, "primitives": [{"attributes": {"POSITION": 0}, "mode": 4}]}

    animated = {
        "asset": {"version": "2.0", "generator": "tests/data/make_gltf_assets.py"},
        "scene": 0,
        "scenes": [{"nodes": [1, 4]}],
        "nodes": [
            {"name": "arm", "mesh": 0, "translation": [0, 2, 0]},
            {"name": "base", "translation": [1, 0, 0], "children": [0, 2]},
            {"name": "head", "mesh": 1, "children": [3]},
            {"name": "hat", "mesh": 2, "translation": [0, 0, 1]},
            {"name": "fixed", "mesh": 3,
             "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1]},
        ],
        "meshes": [triangle("arm"), triangle("head"), triangle("hat"), triangle("fixed")],
        "animations": [
            {"name": "walk",
             "samplers": [sampler(1, 3, "LINEAR"), sampler(1, 4, "LINEAR")],
             "channels": [channel(0, 0, "translation"), channel(1, 2, "rotation")]},
            {"name": "hop",
             "samplers": [sampler(2, 5, "STEP")],
             "channels": [channel(0, 1, "scale")]},
            {"name": "spline",
             "samplers": [sampler(1, 6, "CUBICSPLINE")],
             "channels": [channel(0, 3, "translation")]},
        ],
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode("ascii")}],
        "bufferViews": views,
        "accessors": [
            accessor(0, 3, "VEC3", min=[0, 0, 0], max=[1, 1, 0]),
            accessor(1, 2, "SCALAR", min=[0], max=[2]),
            accessor(2, 3, "SCALAR", min=[0], max=[2]),
            accessor(3, 2, "VEC3"),
            accessor(4, 2, "VEC4"),
            accessor(5, 3, "VEC3"),
            accessor(6, 6, "VEC3"),
        ],
    }
    (HERE / "animated_nodes.gltf").write_text(json.dumps(animated, indent=1) + "\n")


if __name__ == "__main__":
    write_gltf()
    write_glb()
    write_animated()
