#!/usr/bin/env python3
"""Writes balls.gltf for balls.json: three glTF metal-roughness balls on the floor of the Cornell
box, for the path tracer's check against Mitsuba 3 (tests/image/mitsuba_reference_test.cpp).
From left to right: a rough gold conductor (metallic 1), a half-metallic copper (metallic 0.5)
and a rough red dielectric (metallic 0). Factors only, positions baked into the mesh (no node
transforms), smooth normals, so that tools/mitsuba_reference.py reads it without a glTF library.

And glass_balls.gltf for glass_balls.json, the same balls with KHR_materials_transmission: a
half-transmissive clear dielectric (transmission 0.5), a blue-tinted glass (transmission 1) and
a half-metallic copper that is 80% transmissive (of which its metal half lets nothing through).

    python3 tests/data/metal_roughness/make_balls.py
"""
import base64
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
RADIUS = 0.3
BALLS = [  # centre, material
    ((-0.62, -1.0 + RADIUS, 0.1), 0),
    ((0.0, -1.0 + RADIUS, -0.3), 1),
    ((0.62, -1.0 + RADIUS, 0.1), 2),
]
MATERIALS = [
    {"name": "rough gold", "pbrMetallicRoughness": {
        "baseColorFactor": [1.0, 0.78, 0.34, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.35}},
    {"name": "half copper", "pbrMetallicRoughness": {
        "baseColorFactor": [0.95, 0.64, 0.54, 1.0], "metallicFactor": 0.5, "roughnessFactor": 0.5}},
    {"name": "red plastic", "pbrMetallicRoughness": {
        "baseColorFactor": [0.8, 0.15, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.3}},
]

GLASS_EXTENSIONS = ["KHR_materials_ior", "KHR_materials_transmission"]


def glass(name, base, metallic, roughness, transmission):
    return {"name": name, "pbrMetallicRoughness": {
        "baseColorFactor": base + [1.0], "metallicFactor": metallic, "roughnessFactor": roughness},
        "extensions": {"KHR_materials_ior": {"ior": 1.5},
                       "KHR_materials_transmission": {"transmissionFactor": transmission}}}


GLASS_MATERIALS = [
    glass("half glass", [0.9, 0.9, 0.9], 0.0, 0.2, 0.5),
    glass("blue glass", [0.6, 0.8, 1.0], 0.0, 0.3, 1.0),
    glass("copper glass", [0.95, 0.64, 0.54], 0.5, 0.5, 0.8),
]


def sphere(centre, rings=24, segments=48):
    positions, normals, indices = [], [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            normals.append(n)
            positions.append(tuple(c + RADIUS * k for c, k in zip(centre, n)))
    for r in range(rings):
        for s in range(segments):
            a, b = r * (segments + 1) + s, r * (segments + 1) + s + 1
            c, d = (r + 1) * (segments + 1) + s + 1, (r + 1) * (segments + 1) + s
            if r != 0:
                indices += [a, d, b]
            if r != rings - 1:
                indices += [b, d, c]
    return positions, normals, indices


def write(file_name, materials, extensions):
    buffer, views, accessors, meshes = b"", [], [], []

    def add(data, target, accessor):
        nonlocal buffer
        views.append({"buffer": 0, "byteOffset": len(buffer), "byteLength": len(data), "target": target})
        buffer += data
        accessors.append(dict(accessor, bufferView=len(views) - 1))
        return len(accessors) - 1

    for i, (centre, material) in enumerate(BALLS):
        positions, normals, indices = sphere(centre)
        lo = [min(p[k] for p in positions) for k in range(3)]
        hi = [max(p[k] for p in positions) for k in range(3)]
        pos = add(b"".join(struct.pack("<3f", *p) for p in positions), 34962,
                  {"componentType": 5126, "count": len(positions), "type": "VEC3", "min": lo, "max": hi})
        nrm = add(b"".join(struct.pack("<3f", *n) for n in normals), 34962,
                  {"componentType": 5126, "count": len(normals), "type": "VEC3"})
        idx = add(b"".join(struct.pack("<H", k) for k in indices), 34963,
                  {"componentType": 5123, "count": len(indices), "type": "SCALAR"})
        meshes.append({"name": f"ball{i}", "primitives": [
            {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": material}]})
    gltf = {
        "asset": {"version": "2.0", "generator": "farm tests/data/metal_roughness/make_balls.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(meshes)))}],
        "nodes": [{"name": m["name"], "mesh": i} for i, m in enumerate(meshes)],
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": len(buffer),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    if extensions:
        gltf["extensionsUsed"] = extensions
    with open(os.path.join(HERE, file_name), "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")


def main():
    write("balls.gltf", MATERIALS, [])
    write("glass_balls.gltf", GLASS_MATERIALS, GLASS_EXTENSIONS)


if __name__ == "__main__":
    main()
