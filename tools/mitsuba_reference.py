#!/usr/bin/env python3
"""Renders a farm job with Mitsuba 3, an independent path tracer, for reference images and timings.

The job file is read as `farm render` reads it (camera, objects, OBJ/MTL materials, point lights,
background or environment, max_depth) and turned into the same scene in Mitsuba:

  * Phong kd becomes a diffuse BSDF, two-sided like ours; a map_Kd (with Kd 1 1 1, which the
    texture then is) its reflectance as an sRGB bitmap, bilinear and repeating, with the OBJ's vt
    (Mitsuba flips v at load as the farm does); Ke becomes an area emitter. Emitters
    shine from their front face (the side the triangle's counter-clockwise winding faces) in both
    renderers. Mitsuba has no two-sided area light, so an object whose job material says
    "emission_sides": "both" gets a back-to-back twin of each emissive triangle 1e-4 behind it.
  * scene.environment becomes an `envmap` of the same map, its rows laid out as Mitsuba reads
    them (mitsuba_layout_map), its `scale` our intensity, a turn about +y its to_world; or a
    `constant` emitter without a map.
  * Our max_depth counts scattering events, Mitsuba's path segments: Mitsuba's is ours + 1.
  * A box pixel filter, as ours, and the `independent` sampler.

Only what the reference scenes need is supported (OBJ models, diffuse + emissive materials,
translate/rotate/scale, a material override of emission_sides alone); anything else is refused
with a message rather than silently changed.

Set-up (a venv, since Mitsuba comes from PyPI, not Debian):
  python3 -m venv build/mitsuba-venv
  build/mitsuba-venv/bin/pip install -r tools/requirements-mitsuba.txt
Reference images (what tests/data/reference/ holds):
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py jobs/cornell_path.json \\
      --width 128 --height 128 --spp 4096 -o tests/data/reference/cornell_path_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py tests/data/cornell_gap/cornell_gap.json \\
      --spp 2048 --half -o tests/data/reference/cornell_gap_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py jobs/cornell_textured.json \\
      --width 128 --height 128 --spp 4096 --half -o tests/data/reference/cornell_textured_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py jobs/environment.json \\
      --width 160 --height 120 --spp 4096 --half -o tests/data/reference/environment_mitsuba.exr
Throughput beside `farm bench path`:
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py jobs/cornell_path.json \\
      --width 512 --height 512 --spp 16 --threads 1 --bench
"""
import argparse
import json
import math
import os
import sys
import tempfile
import time


class RefusedScene(Exception):
    pass


def parse_mtl(path):
    materials, current = {}, None
    with open(path) as f:
        for number, line in enumerate(f, 1):
            words = line.split()
            if not words or words[0].startswith("#"):
                continue
            key, values = words[0], words[1:]
            if key == "newmtl":
                current = materials.setdefault(values[0], {"Kd": [0.5] * 3, "Ke": [0.0] * 3, "Ks": [0.0] * 3})
            elif current is not None and key == "map_Kd":
                current["map_Kd"] = os.path.join(os.path.dirname(path), values[-1])
            elif current is not None and key in ("Kd", "Ke", "Ks"):
                current[key] = [float(v) for v in values[:3]]
            elif current is not None and key in ("d", "Tr", "Ni", "Ns", "Ka", "illum"):
                current[key] = [float(v) for v in values]
    return materials


def parse_obj(path):
    """Triangles grouped by material name: {material: [(c0, c1, c2), ...]}, each corner a
    (position, uv) pair, uv None where the face gives none."""
    folder = os.path.dirname(path)
    vertices, uvs, groups, materials, material = [], [], {}, {}, "default"
    with open(path) as f:
        for number, line in enumerate(f, 1):
            words = line.split()
            if not words or words[0].startswith("#"):
                continue
            if words[0] == "v":
                vertices.append(tuple(float(v) for v in words[1:4]))
            elif words[0] == "vt":
                uvs.append(tuple(float(v) for v in words[1:3]))
            elif words[0] == "mtllib":
                materials.update(parse_mtl(os.path.join(folder, words[1])))
            elif words[0] == "usemtl":
                material = words[1]
            elif words[0] == "f":
                def corner(word):
                    parts = word.split("/")
                    uv = uvs[int(parts[1]) - 1] if len(parts) > 1 and parts[1] else None
                    return vertices[int(parts[0]) - 1], uv
                corners = [corner(w) for w in words[1:]]
                for i in range(1, len(corners) - 1):  # a fan: the polygons are planar and convex
                    groups.setdefault(material, []).append((corners[0], corners[i], corners[i + 1]))
    return groups, materials


def transform_of(mi, obj):
    t = mi.ScalarTransform4f()
    if "translate" in obj:
        t = t.translate(obj["translate"])
    if "rotate" in obj:
        t = t.rotate(obj["rotate"].get("axis", [0, 1, 0]), obj["rotate"].get("degrees", 0))
    if "scale" in obj:
        t = t.scale(obj["scale"])
    return t


def write_triangles(path, triangles, flip=False, offset=0.0):
    """A plain OBJ of separate triangles; `flip` reverses them and moves them `offset` behind."""
    lines, uv_lines, with_uvs = [], [], all(uv is not None for t in triangles for _, uv in t)
    for corners in triangles:
        (a, ua), (b, ub), (c, uc) = corners
        if flip:
            e1 = [b[k] - a[k] for k in range(3)]
            e2 = [c[k] - a[k] for k in range(3)]
            n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            shift = [-offset * x / length for x in n]
            a, b, c = [tuple(p[k] + shift[k] for k in range(3)) for p in (a, c, b)]
            ub, uc = uc, ub
        for p in (a, b, c):
            lines.append("v %.9g %.9g %.9g" % p)
        if with_uvs:
            for uv in (ua, ub, uc):
                uv_lines.append("vt %.9g %.9g" % uv)
    lines += uv_lines
    for i in range(len(triangles)):
        k = 3 * i
        if with_uvs:
            lines.append("f %d/%d %d/%d %d/%d" % (k + 1, k + 1, k + 2, k + 2, k + 3, k + 3))
        else:
            lines.append("f %d %d %d" % (k + 1, k + 2, k + 3))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def mitsuba_layout_map(mi, path, workdir):
    """The lat-long map at `path` laid out as Mitsuba's envmap reads one, written as a PFM.

    Both map a direction to (u, v) alike and both filter bilinearly, but the farm puts row j's
    value at v = (j + 0.5) / H, as for every texture, and Mitsuba at v = j / (H - 1), its rows
    running from pole to pole. Mitsuba is handed 2H + 1 rows holding the farm's bilinear value at
    v = k / 2H: every knot of the farm's piecewise-linear rows is among those, so Mitsuba's
    bilinear lookup between them is the farm's function exactly."""
    import numpy as np
    bitmap = mi.Bitmap(path).convert(pixel_format=mi.Bitmap.PixelFormat.RGB,
                                     component_format=mi.Struct.Type.Float32, srgb_gamma=False)
    texels = np.array(bitmap, dtype=np.float64)
    height = texels.shape[0]
    rows = []
    for k in range(2 * height + 1):
        y = k / (2 * height) * height - 0.5
        y0 = int(np.floor(y))
        f = y - y0
        above, below = texels[min(max(y0, 0), height - 1)], texels[min(max(y0 + 1, 0), height - 1)]
        rows.append((1 - f) * above + f * below)
    # PFM: float32 exactly, and no OpenEXR writer (whose thread pool deadlocks under
    # --threads 1).
    out = os.path.join(workdir, "environment_mitsuba_layout.pfm")
    mi.Bitmap(np.array(rows, dtype=np.float32)).write(out)
    return out


def scene_of(mi, job_path, job, width, height, spp, seed, workdir):
    folder = os.path.dirname(os.path.abspath(job_path))
    scene_json = job["scene"]
    render = job.get("render", {})
    camera = scene_json.get("camera", {})
    if not camera:
        raise RefusedScene("the job must give its camera (model cameras are not read here)")
    max_depth = render.get("max_depth", 5)
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1 if max_depth < 0 else max_depth + 1},
        "sensor": {
            "type": "perspective",
            "fov": camera.get("fov_y", 45),
            "fov_axis": "y",
            "near_clip": camera.get("near", 0.1),
            "far_clip": camera.get("far", 10),
            "to_world": mi.ScalarTransform4f().look_at(
                origin=camera.get("position", [5, 5, 5]), target=camera.get("target", [0, 0, 0]),
                up=camera.get("up", [0, 1, 0])),
            "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
    }
    environment = scene_json.get("environment")
    if environment is not None:
        # Our lat-long layout is Mitsuba's envmap's, and a turn about +y its to_world's.
        intensity = environment.get("intensity", 1.0)
        radiance = environment.get("radiance", [1.0, 1.0, 1.0])
        if not isinstance(radiance, list):
            radiance = [radiance] * 3
        if "map" in environment:
            if radiance != [1.0, 1.0, 1.0]:
                raise RefusedScene("scene.environment: a map tinted by a radiance is not supported here")
            scene["environment"] = {
                "type": "envmap", "filename": mitsuba_layout_map(mi, os.path.join(folder, environment["map"]), workdir),
                "scale": intensity,
                "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], environment.get("rotate_degrees", 0.0))}
        else:
            scene["environment"] = {"type": "constant",
                                    "radiance": {"type": "rgb", "value": [c * intensity for c in radiance]}}
    else:
        background = scene_json.get("background", [100 / 255] * 3)
        if max(background) > 0:
            scene["background"] = {"type": "constant", "radiance": {"type": "rgb", "value": background}}
    for i, light in enumerate(scene_json.get("lights", [])):
        if "position" not in light:
            raise RefusedScene(f"scene.lights[{i}]: only point lights are supported")
        intensity = light.get("intensity", 10)
        if not isinstance(intensity, list):
            intensity = [intensity] * 3
        scene[f"light_{i}"] = {"type": "point", "position": light["position"],
                               "intensity": {"type": "rgb", "value": intensity}}
    for i, obj in enumerate(scene_json["objects"]):
        if not obj["file"].lower().endswith(".obj"):
            raise RefusedScene(f"scene.objects[{i}].file: only OBJ models are supported")
        override = obj.get("material", {})
        if set(override) - {"emission_sides"}:
            raise RefusedScene(f"scene.objects[{i}].material: only emission_sides can be overridden here")
        two_sided_emission = override.get("emission_sides", "front") == "both"
        groups, materials = parse_obj(os.path.join(folder, obj["file"]))
        to_world = transform_of(mi, obj)
        for name, triangles in groups.items():
            m = materials.get(name, {"Kd": [0.5] * 3, "Ke": [0.0] * 3, "Ks": [0.0] * 3})
            if max(m["Ks"]) > 0 or m.get("d", [1])[0] < 1 or m.get("Tr", [0])[0] > 0:
                raise RefusedScene(f"{obj['file']}: material '{name}': only diffuse and emissive materials are supported")
            reflectance = {"type": "rgb", "value": m["Kd"]}
            if "map_Kd" in m:
                if m["Kd"] != [1.0, 1.0, 1.0]:
                    raise RefusedScene(f"{obj['file']}: material '{name}': a map_Kd needs Kd 1 1 1 here")
                if any(uv is None for t in triangles for _, uv in t):
                    raise RefusedScene(f"{obj['file']}: material '{name}': a face without vt")
                reflectance = {"type": "bitmap", "filename": m["map_Kd"], "raw": False,
                               "filter_type": "bilinear", "wrap_mode": "repeat"}
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": reflectance}}
            emits = max(m["Ke"]) > 0
            twins = [("front", False)] + ([("back", True)] if emits and two_sided_emission else [])
            for side, flip in twins:
                path = os.path.join(workdir, f"object{i}_{name}_{side}.obj")
                write_triangles(path, triangles, flip=flip, offset=1e-4)
                shape = {"type": "obj", "filename": path, "face_normals": True, "to_world": to_world,
                         "bsdf": bsdf}
                if emits:
                    shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["Ke"]}}
                scene[f"object{i}_{name}_{side}"] = shape
    return scene


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("job", help="farm job file (JSON)")
    parser.add_argument("-o", "--output", help="EXR to write (float RGB)")
    parser.add_argument("--width", type=int, help="image width (default: the job's)")
    parser.add_argument("--height", type=int, help="image height (default: the job's)")
    parser.add_argument("--spp", type=int, help="samples per pixel (default: the job's)")
    parser.add_argument("--max-depth", type=int, help="scattering events, ours (default: the job's)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=0, help="render threads (0: all)")
    parser.add_argument("--variant", default="scalar_rgb")
    parser.add_argument("--half", action="store_true", help="write the EXR as half floats (smaller)")
    parser.add_argument("--bench", action="store_true", help="print throughput as one JSON line")
    args = parser.parse_args()

    import mitsuba as mi
    import drjit as dr
    mi.set_variant(args.variant)
    if args.threads > 0:
        dr.set_thread_count(args.threads)

    with open(args.job) as f:
        job = json.load(f)
    render = job.get("render", {})
    width = args.width or render.get("width", 640)
    height = args.height or render.get("height", 480)
    spp = args.spp or render.get("spp", 1)
    if args.max_depth is not None:
        job.setdefault("render", {})["max_depth"] = args.max_depth
    with tempfile.TemporaryDirectory() as workdir:
        try:
            scene = mi.load_dict(scene_of(mi, args.job, job, width, height, spp, args.seed, workdir))
        except RefusedScene as e:
            print(f"{args.job}: {e}", file=sys.stderr)
            return 2
        start = time.perf_counter()
        image = mi.render(scene, spp=spp, seed=args.seed)
        seconds = time.perf_counter() - start
    samples = width * height * spp
    if args.bench:
        print(json.dumps({"renderer": f"mitsuba {mi.__version__} {args.variant}", "threads": dr.thread_count(),
                          "width": width, "height": height, "spp": spp, "seconds": seconds,
                          "msamples_per_s": samples / seconds / 1e6}))
    else:
        print(f"mitsuba {mi.__version__} {args.variant}: {width}x{height}, {spp} spp, "
              f"{seconds:.1f} s on {dr.thread_count()} threads ({samples / seconds / 1e6:.3f} Msamples/s)")
    if args.output:
        bitmap = mi.Bitmap(image)
        if args.half:
            bitmap = bitmap.convert(component_format=mi.Struct.Type.Float16)
        metadata = bitmap.metadata()  # written into the EXR header, so the file says what it is
        metadata["farm.job"] = os.path.basename(args.job)
        metadata["farm.spp"] = str(spp)
        metadata["farm.renderer"] = f"mitsuba {mi.__version__} {args.variant}"
        bitmap.write(args.output)
        print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
