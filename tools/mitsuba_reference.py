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
  * A glTF model's metal-roughness material (factors only, ior from KHR_materials_ior or 1.5)
    becomes what our path tracer's metal-roughness BSDF is: its dielectric half (diffuse base
    under a rough coat) `roughplastic` with GGX alpha = roughness^2, nonlinear=false, the base
    colour as diffuse_reflectance and int_ior the ior; its metal half `principled` with
    metallic=1 and the same roughness (GGX of Schlick's Fresnel from the base colour); between
    them a `blendbsdf` weighted by metallic; all two-sided. KHR_materials_transmission's share of
    the dielectric half, t (1 - metallic), is a `roughdielectric` of GGX alpha roughness^2, or a
    smooth `dielectric` below alpha 1e-3 (specular_transmittance the base colour's square root:
    tinted by it over two crossings), blended with that two-sided rest (whose metallic becomes
    metallic / (1 - t (1 - metallic))); smooth glass in a blend is a `roughdielectric` of alpha
    1e-4, as blendbsdf mishandles a delta component (see metal_roughness_bsdf). The mesh is
    read from the file's buffers with its normals (positions baked: no node transforms).
  * MTL's `norm` wraps that in a `normalmap` of the same image (raw, bilinear, repeating), with
    its shadowing function off (Mitsuba adds one by default; the normal-mapped surface itself,
    ours, and the direct-light integral have none).
  * MTL's `bump` (a height map, -bm its multiplier) wraps it in a `bumpmap` of the same image,
    its shadowing function off as well, its scale -bm times the world length of a uv unit (our
    heights are in uv units, Mitsuba's in world units; one scale across the group, or refused).
  * scene.environment becomes an `envmap` of the same map, its rows laid out as Mitsuba reads
    them (mitsuba_layout_map), its `scale` our intensity, a turn about +y its to_world; or a
    `constant` emitter without a map.
  * Our max_depth counts scattering events, Mitsuba's path segments: Mitsuba's is ours + 1.
  * Russian roulette from the same depth as ours (renderer/trace/path_tracer.cpp, kRouletteStart:
    a path may end after its third surface, Mitsuba's rr_depth 3; the same survival odds, the
    throughput's largest channel capped at 0.95), so a sample is the same work in both and
    `farm bench path` compares like with like. Mitsuba's default, 5, traces longer paths: 20-25%
    fewer samples a second on the Cornell box, for the same mean.
  * A box pixel filter, as ours, and the `independent` sampler.

Only what the reference scenes need is supported (OBJ models with diffuse + emissive materials,
a map_Kd, a norm and a bump, glTF models with factor-only metal-roughness materials and transmission,
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
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py tests/data/metal_roughness/balls.json \\
      --spp 4096 --half -o tests/data/reference/metal_roughness_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py tests/data/metal_roughness/glass_balls.json \\
      --spp 4096 --half -o tests/data/reference/glass_balls_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py tests/data/normal_mapped/floor.json \\
      --spp 4096 --half -o tests/data/reference/normal_mapped_mitsuba.exr
  build/mitsuba-venv/bin/python tools/mitsuba_reference.py tests/data/normal_mapped/bumped_floor.json \\
      --spp 4096 --half -o tests/data/reference/bump_mapped_mitsuba.exr
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
            elif current is not None and key in ("map_Kd", "norm", "bump"):
                current[key] = os.path.join(os.path.dirname(path), values[-1])
                if key == "bump":
                    options = dict(zip(values[:-1:2], values[1:-1:2]))
                    if set(options) - {"-bm"}:
                        raise RefusedScene(f"{path}:{number}: only -bm is supported on a bump here")
                    current["bump_multiplier"] = float(options.get("-bm", 1.0))
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


GLTF_COMPONENTS = {5121: "B", 5123: "H", 5125: "I", 5126: "f"}
GLTF_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}


def parse_gltf(path):
    """[(material, positions, normals, triangles)] of a glTF file's primitives: its root nodes'
    meshes, which must have no transforms and no children."""
    import base64
    import struct
    with open(path) as f:
        gltf = json.load(f)
    buffers = []
    for b in gltf.get("buffers", []):
        uri = b["uri"]
        if uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            with open(os.path.join(os.path.dirname(path), uri), "rb") as f:
                buffers.append(f.read())

    def accessor(index):
        a = gltf["accessors"][index]
        view = gltf["bufferViews"][a["bufferView"]]
        width = GLTF_WIDTHS[a["type"]]
        fmt = "<" + GLTF_COMPONENTS[a["componentType"]] * width
        stride = view.get("byteStride", struct.calcsize(fmt))
        offset = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        data = buffers[view["buffer"]]
        return [struct.unpack_from(fmt, data, offset + k * stride) for k in range(a["count"])]

    primitives = []
    for node_index in gltf["scenes"][gltf.get("scene", 0)]["nodes"]:
        node = gltf["nodes"][node_index]
        if set(node) & {"matrix", "translation", "rotation", "scale", "children"}:
            raise RefusedScene(f"{path}: node {node_index}: only nodes without transforms or children are supported")
        for prim in gltf["meshes"][node["mesh"]]["primitives"]:
            if prim.get("mode", 4) != 4 or "NORMAL" not in prim["attributes"] or "indices" not in prim:
                raise RefusedScene(f"{path}: only indexed triangles with normals are supported")
            indices = [i[0] for i in accessor(prim["indices"])]
            triangles = [tuple(indices[k:k + 3]) for k in range(0, len(indices), 3)]
            material = gltf["materials"][prim["material"]] if "material" in prim else {}
            primitives.append((material, accessor(prim["attributes"]["POSITION"]),
                               accessor(prim["attributes"]["NORMAL"]), triangles))
    return primitives


def internal_reflectance(alpha, eta, mus, strata=128):
    """2 * the mean over `mus` of R(mu) mu, R(mu) the share of light inside a GGX dielectric
    interface (relative index 1 / eta) arriving at cos(theta) = mu that the interface reflects back
    in: Fresnel (total beyond the critical angle) times the reflected ray's masking, averaged over
    visible normals (Heitz 2018) on a strata x strata grid."""
    import numpy as np
    u1, u2 = np.meshgrid((np.arange(strata) + 0.5) / strata, (np.arange(strata) + 0.5) / strata)
    u1, u2 = u1.ravel(), u2.ravel()

    def g1(z, alpha):
        tan2 = np.maximum(0.0, 1.0 - z * z) / np.maximum(z * z, 1e-12)
        return 1.0 / (1.0 + 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * tan2)))

    total = 0.0
    for mu in mus:
        w = np.array([math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
        v = np.array([alpha * w[0], 0.0, w[2]])
        v /= np.linalg.norm(v)
        t1 = np.array([0.0, 1.0, 0.0]) if v[0] > 0 else np.array([1.0, 0.0, 0.0])
        t2 = np.cross(v, t1)
        r, phi = np.sqrt(u1), 2.0 * math.pi * u2
        p1 = r * np.cos(phi)
        s = 0.5 * (1.0 + v[2])
        p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * r * np.sin(phi)
        pz = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
        n = p1[:, None] * t1 + p2[:, None] * t2 + pz[:, None] * v
        m = np.stack([alpha * n[:, 0], alpha * n[:, 1], np.maximum(1e-6, n[:, 2])], axis=1)
        m /= np.linalg.norm(m, axis=1)[:, None]
        cos_i = m @ w
        reflected_z = 2.0 * cos_i * m[:, 2] - w[2]
        sin_t = eta * np.sqrt(np.maximum(0.0, 1.0 - cos_i * cos_i))  # from inside, index eta to 1
        cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t * sin_t))
        rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
        rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
        fresnel = np.where(sin_t >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp))
        weight = np.where((cos_i > 0) & (reflected_z > 0), fresnel * g1(reflected_z, alpha), 0.0)
        total += weight.mean() * mu
    return 2.0 * total / len(mus)


def metal_roughness_bsdf(path, material):
    """Mitsuba's counterpart of our metal-roughness BSDF for a glTF material's factors."""
    name = material.get("name", "(unnamed)")
    pbr = material.get("pbrMetallicRoughness", {})
    if any(key.endswith("Texture") for key in list(pbr) + list(material)):
        raise RefusedScene(f"{path}: material '{name}': textures are not supported here")
    extensions = material.get("extensions", {})
    if set(extensions) - {"KHR_materials_ior", "KHR_materials_transmission"} or \
            max(material.get("emissiveFactor", [0])) > 0:
        raise RefusedScene(f"{path}: material '{name}': only metal-roughness factors, ior and transmission "
                           "are supported here")
    base = {"type": "rgb", "value": pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]}
    metallic, roughness = pbr.get("metallicFactor", 1.0), pbr.get("roughnessFactor", 1.0)
    ior = extensions.get("KHR_materials_ior", {}).get("ior", 1.5)
    # The smooth glass share of the surface, and the metal's share of the rest.
    glass = extensions.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0) * (1.0 - metallic)
    if glass > 0 and ior > 1:
        metallic = metallic / (1.0 - glass) if glass < 1 else 0.0
    else:
        glass = 0.0
    alpha = max(roughness ** 2, 1e-3)
    # roughplastic divides its diffuse reflectance by 1 - R_int, R_int twice the mean of R(mu) mu
    # over 64 points from 0 to 1 inclusive: about (63/64) of the integral, which leaves its base
    # about 2% darker than the model it describes at ior 1.5. Its reflectance is scaled here so
    # that it divides by 1 - the integral itself, as our coat does.
    import numpy as np
    mitsubas = internal_reflectance(alpha, ior, np.maximum(1e-6, np.linspace(0.0, 1.0, 64)))
    integral = internal_reflectance(alpha, ior, (np.arange(256) + 0.5) / 256)
    base_under_coat = {"type": "rgb", "value": [c * (1.0 - mitsubas) / (1.0 - integral) for c in base["value"]]}
    plastic = {"type": "roughplastic", "distribution": "ggx", "alpha": alpha, "int_ior": ior, "ext_ior": 1.0,
               "nonlinear": False, "diffuse_reflectance": base_under_coat}
    metal = {"type": "principled", "base_color": base, "metallic": 1.0, "roughness": roughness,
             "spec_tint": 0.0, "sheen": 0.0, "clearcoat": 0.0, "spec_trans": 0.0, "anisotropic": 0.0}
    if metallic <= 0:
        bsdf = plastic
    elif metallic >= 1:
        bsdf = metal
    else:
        bsdf = {"type": "blendbsdf", "weight": metallic, "plastic": plastic, "metal": metal}
    bsdf = {"type": "twosided", "bsdf": bsdf}
    if glass > 0:
        # Tinted by the base colour over two crossings: its square root at each.
        tint = {"type": "rgb", "value": [math.sqrt(c) for c in base["value"]]}
        dielectric = {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0, "specular_transmittance": tint}
        if roughness * roughness >= 1e-3:  # as rough as the rest of the surface, as ours
            dielectric = dict(dielectric, type="roughdielectric", distribution="ggx", alpha=roughness * roughness)
        if glass >= 1:
            return dielectric
        if dielectric["type"] == "dielectric":
            # Mitsuba 3.9's blendbsdf weighs a sample of a delta component (its discrete
            # probability) against the other component's density in the same direction, which
            # dims the glass's reflection (to 4% of it under a coat of alpha 0.04): a GGX
            # roughdielectric of alpha 1e-4, smooth for every purpose here, has a density and
            # blends correctly.
            dielectric = dict(dielectric, type="roughdielectric", distribution="ggx", alpha=1e-4)
        bsdf = {"type": "blendbsdf", "weight": glass, "rest": bsdf, "glass": dielectric}
    return bsdf


def uv_scale(obj, name, triangles):
    """The world length of one uv unit on a group of triangles, which must be the same along u and
    v on every one: our bump heights are in uv units, Mitsuba's bumpmap's in world units."""
    if any(key in obj for key in ("scale", "matrix")):
        raise RefusedScene(f"{obj['file']}: material '{name}': a bump map on a scaled object is not supported here")
    lengths = set()
    for t in triangles:
        if any(uv is None for _, uv in t):
            raise RefusedScene(f"{obj['file']}: material '{name}': a face without vt")
        (p0, t0), (p1, t1), (p2, t2) = t
        e1, e2 = [b - a for a, b in zip(p0, p1)], [b - a for a, b in zip(p0, p2)]
        du1, dv1, du2, dv2 = t1[0] - t0[0], t1[1] - t0[1], t2[0] - t0[0], t2[1] - t0[1]
        det = du1 * dv2 - du2 * dv1
        dp_du = [(dv2 * a - dv1 * b) / det for a, b in zip(e1, e2)]
        dp_dv = [(du1 * b - du2 * a) / det for a, b in zip(e1, e2)]
        lengths |= {round(math.sqrt(sum(c * c for c in d)), 4) for d in (dp_du, dp_dv)}
    if len(lengths) != 1:
        raise RefusedScene(f"{obj['file']}: material '{name}': a bump map needs one uv scale, found {sorted(lengths)}")
    return lengths.pop()


def write_smooth_mesh(path, positions, normals, triangles):
    """An OBJ with per-vertex normals, for Mitsuba to interpolate as we do."""
    lines = ["v %.9g %.9g %.9g" % p for p in positions] + ["vn %.9g %.9g %.9g" % n for n in normals]
    lines += ["f %d//%d %d//%d %d//%d" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1) for a, b, c in triangles]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


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


# The depth from which our path tracer plays Russian roulette (kRouletteStart in
# renderer/trace/path_tracer.cpp), as Mitsuba's rr_depth.
ROULETTE_START = 3


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
        "integrator": {"type": "path", "max_depth": -1 if max_depth < 0 else max_depth + 1,
                       "rr_depth": ROULETTE_START},
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
        if obj["file"].lower().endswith(".gltf"):
            if set(obj) - {"file"}:
                raise RefusedScene(f"scene.objects[{i}]: a glTF model without transforms or overrides only")
            path = os.path.join(folder, obj["file"])
            for k, (material, positions, normals, triangles) in enumerate(parse_gltf(path)):
                mesh = os.path.join(workdir, f"object{i}_primitive{k}.obj")
                write_smooth_mesh(mesh, positions, normals, triangles)
                scene[f"object{i}_primitive{k}"] = {"type": "obj", "filename": mesh, "face_normals": False,
                                                    "bsdf": metal_roughness_bsdf(path, material)}
            continue
        if not obj["file"].lower().endswith(".obj"):
            raise RefusedScene(f"scene.objects[{i}].file: only OBJ and glTF models are supported")
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
            if "norm" in m:
                if any(uv is None for t in triangles for _, uv in t):
                    raise RefusedScene(f"{obj['file']}: material '{name}': a face without vt")
                # Mitsuba's normalmap darkens by default with a shadowing term for bumps
                # (Estevez et al. 2019) that the normal map itself does not have, and we do not:
                # off here. Its flip of a normal facing away from the viewer is ours too.
                bsdf = {"type": "normalmap", "use_shadowing_function": False, "bsdf": bsdf,
                        "normalmap": {"type": "bitmap", "filename": m["norm"], "raw": True,
                                      "filter_type": "bilinear", "wrap_mode": "repeat"}}
            if "bump" in m:
                bsdf = {"type": "bumpmap", "use_shadowing_function": False, "bsdf": bsdf,
                        "scale": m["bump_multiplier"] * uv_scale(obj, name, triangles),
                        "heights": {"type": "bitmap", "filename": m["bump"], "raw": True,
                                    "filter_type": "bilinear", "wrap_mode": "repeat"}}
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
    parser.add_argument("--warmup", action="store_true",
                        help="render once untimed first (a JIT variant compiles its kernels then) and report "
                             "how long that took apart")
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
        warmup_seconds = 0.0
        if args.warmup:
            start = time.perf_counter()
            dr.eval(mi.render(scene, spp=spp, seed=args.seed))
            dr.sync_thread()
            warmup_seconds = time.perf_counter() - start
        start = time.perf_counter()
        image = mi.render(scene, spp=spp, seed=args.seed)
        dr.eval(image)  # a JIT variant's render returns before its kernels have run
        dr.sync_thread()
        seconds = time.perf_counter() - start
    samples = width * height * spp
    if args.bench:
        print(json.dumps({"renderer": f"mitsuba {mi.__version__} {args.variant}", "threads": dr.thread_count(),
                          "width": width, "height": height, "spp": spp, "seconds": seconds,
                          "warmup_seconds": warmup_seconds,
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
