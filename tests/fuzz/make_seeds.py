#!/usr/bin/env python3
"""Writes the seed corpus of tests/fuzz (corpus/<target>/): small files copied from jobs/,
tests/data and the lab's malformed models (../shared/assets/bad), plus the protobuf inputs of the
service targets, built here from proto/farm.proto so that they stay valid as the messages grow.

Run from anywhere with Debian's python3 (python3-grpc-tools, python3-protobuf):
    /usr/bin/python3 tests/fuzz/make_seeds.py
The seeds are committed; rerun it after changing the jobs or the protocol. It only adds and
overwrites seeds of its own names (seed-*), so seeds added by hand, or by a fuzzing run worth
keeping, stay.
"""
import hashlib
import json
import pathlib
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = ROOT / "tests" / "fuzz" / "corpus"
SHARED = ROOT.parent / "shared" / "assets"


def farm_pb2():
    """proto/farm.proto compiled for Python in a temporary folder."""
    out = pathlib.Path(tempfile.mkdtemp(prefix="farm-fuzz-seeds-"))
    subprocess.run([sys.executable, "-m", "grpc_tools.protoc", f"-I{ROOT}", f"--python_out={out}",
                    "proto/farm.proto"], check=True, cwd=ROOT)
    sys.path.insert(0, str(out))
    from proto import farm_pb2 as pb  # noqa: E402 (made just above)
    return pb


def put(target, name, data):
    folder = CORPUS / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"seed-{name}").write_bytes(data if isinstance(data, bytes) else data.encode())


def copy(target, source, name=None):
    if source.is_file():
        put(target, name or source.name, source.read_bytes())


def asset_ref(pb, job_dir, path):
    data = (job_dir / path).read_bytes()
    return pb.AssetRef(path=path, sha256=hashlib.sha256(data).hexdigest(), size=len(data)), data


def cornell_spec(pb, job_name="cornell.json", engine=None, width=None):
    jobs = ROOT / "jobs"
    job = json.loads((jobs / job_name).read_text())
    if engine:
        job["render"]["engine"] = engine
    if width:
        job["render"]["width"] = job["render"]["height"] = width
    spec = pb.JobSpec(job_json=json.dumps(job), file_name=job_name)
    files = []
    for path in ["assets/cornell_box.obj", "assets/cornell_box.mtl"]:
        ref, data = asset_ref(pb, jobs, path)
        spec.assets.append(ref)
        files.append((ref.sha256, data))
    return spec, files


def tile(pb, x0, y0, w, h, aovs=("depth",)):
    n = w * h
    floats = lambda k, v: struct.pack(f"<{n * k}f", *([v] * (n * k)))
    t = pb.TileData(rect=pb.TileRect(x0=x0, y0=y0, x1=x0 + w, y1=y0 + h), width=w, height=h,
                    rgba=struct.pack(f"<{n * 4}f", *([0.5, 0.25, 0.125, 1.0] * n)))
    if "depth" in aovs:
        t.depth = floats(1, 2.0)
    if "normal" in aovs:
        t.normal = struct.pack(f"<{n * 3}f", *([0.0, 0.0, 1.0] * n))
    if "albedo" in aovs:
        t.albedo = floats(3, 0.5)
    return t


def model_seeds():
    for f in ["jobs/assets/cornell_box.obj", "tests/data/cornell_gap/cornell_box.obj"]:
        copy("obj_loader", ROOT / f, f.replace("/", "_"))
    for f in sorted((SHARED / "bad").glob("*.obj")) + [SHARED / "obj" / "cube.obj",
                                                       SHARED / "obj" / "catmark_torus_creases0.obj"]:
        copy("obj_loader", f)
    for f in ["sphere_diffuse.dae", "plane64.dae"]:
        copy("collada_loader", SHARED / "dae" / f)
    put("collada_loader", "triangle.dae", """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Y_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
""")
    for f in ["tests/data/quad_scene.gltf", "tests/data/quad_scene.glb",
              "tests/data/animated_nodes.gltf"]:
        copy("gltf_loader", ROOT / f, f.replace("/", "_"))
    ascii_ply = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
3 0 1 2
3 0 2 3
"""
    put("ply_loader", "quad-ascii.ply", ascii_ply)
    header = ascii_ply.split("end_header\n")[0].replace("ascii", "binary_little_endian") + "end_header\n"
    body = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0)
    body += struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B3i", 3, 0, 2, 3)
    put("ply_loader", "quad-binary.ply", header.encode() + body)
    for f in sorted((ROOT / "jobs").glob("*.json")) + [ROOT / "tests/data/cornell_gap/cornell_gap.json"]:
        copy("job_file", f)


def service_seeds(pb):
    # tile_codec: replies a worker sends (raster with depth, whitted with rays, one bare row).
    put("tile_codec", "raster-2x2", pb.RenderTileResponse(tile=tile(pb, 4, 4, 2, 2)).SerializeToString())
    put("tile_codec", "whitted-3x1",
        pb.RenderTileResponse(tile=tile(pb, 0, 0, 3, 1, ("depth", "normal", "albedo")),
                              stats=pb.TileStats(rays=3, render_ms=0.5)).SerializeToString())
    reply = pb.RenderTileResponse(tile=tile(pb, 8, 0, 4, 2), stats=pb.TileStats(render_ms=1.0))
    payload = reply.SerializeToString()
    header = b"FARMTIL1" + struct.pack("<Q", len(payload)) + hashlib.sha256(payload).hexdigest().encode()
    put("tile_results", "framed", b"\x01" + payload)
    put("tile_results", "whole-file", b"\x00" + header + payload)
    put("tile_results", "cut-short", b"\x02" + payload)

    # scheduler_requests: one call of each RPC (first byte: the RPC, in farm.proto's order).
    spec, files = cornell_spec(pb)
    calls = {
        "0-submit-cornell": (0, pb.SubmitJobRequest(job=spec)),
        "1-get-job": (1, pb.GetJobRequest(job_id="@")),
        "2-list-jobs": (2, pb.ListJobsRequest(page_size=3)),
        "3-watch-job": (3, pb.WatchJobRequest(job_id="@")),
        "4-cancel-job": (4, pb.CancelJobRequest(job_id="@")),
        "5-get-result": (5, pb.GetResultRequest(job_id="@", kind=2)),
        "7-has-assets": (7, pb.HasAssetsRequest(sha256=[files[0][0], "0" * 64])),
        "8-get-asset": (8, pb.GetAssetRequest(sha256=files[1][0])),
        "9-register-worker": (9, pb.RegisterWorkerRequest(address="127.0.0.1:1", threads=1,
                                                          engines=["raster"])),
        "10-heartbeat": (10, pb.HeartbeatRequest(worker_id="w1")),
        "11-plan-submission": (11, pb.PlanSubmissionRequest(job=spec, absent=["assets/none.png"])),
    }
    for name, (rpc, message) in calls.items():
        put("scheduler_requests", name, bytes([rpc]) + message.SerializeToString())
    data = b"a small asset\n"
    parts = [pb.UploadAssetRequest(header=pb.AssetHeader(sha256=hashlib.sha256(data).hexdigest(),
                                                         size=len(data))),
             pb.UploadAssetRequest(data=data[:5]), pb.UploadAssetRequest(data=data[5:])]
    stream = b"".join(struct.pack("<H", len(p.SerializeToString())) + p.SerializeToString() for p in parts)
    put("scheduler_requests", "6-upload-asset", b"\x06" + stream)

    # worker_render_tile: the Cornell box with its files inline, under each engine.
    for engine in ["raster", "whitted", "path"]:
        spec, files = cornell_spec(pb, engine=engine, width=16)
        request = pb.RenderTileRequest(job=spec, rect=pb.TileRect(x0=0, y0=0, x1=8, y1=8),
                                       job_id="fuzz", tile_index=0)
        for sha, data in files:
            request.assets.append(pb.InlineAsset(sha256=sha, data=data))
        put("worker_render_tile", f"cornell-{engine}", request.SerializeToString())


def main():
    model_seeds()
    service_seeds(farm_pb2())
    for folder in sorted(CORPUS.iterdir()):
        print(f"{folder.name}: {len(list(folder.iterdir()))} seeds")


if __name__ == "__main__":
    main()
