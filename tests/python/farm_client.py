#!/usr/bin/env python3
"""A farm client in Python: proof that proto/farm.proto is the whole wire contract.

Generates its stubs from the .proto with grpc_tools (into --gen-dir), then submits a job to a
scheduler the way `farm submit --wait` does: HasAssets, UploadAsset for the missing files,
SubmitJob, WatchJob to the end, GetResult into --out (checking the SHA-256 the scheduler sends).

  farm_client.py --proto proto/farm.proto --gen-dir DIR --scheduler HOST:PORT \\
      --job jobs/cornell.json --asset assets/cornell_box.obj=jobs/assets/cornell_box.obj ... --out x.exr

A scheduler started with --tokens needs a token: --token-file FILE (its first line) or FARM_TOKEN,
sent as `authorization: Bearer <token>` metadata on every call, as `farm` does. --tls-ca CA talks
TLS, verifying the scheduler against CA (with --tls-cert/--tls-key for mTLS).

Prints one JSON line with the job id, its final state and the bytes fetched; exit 0 only when the
job succeeded and the result arrived intact. A refused call prints its status code and exits 1.
"""
import argparse
import hashlib
import importlib
import json
import os
import subprocess
import sys


def generate_stubs(proto, gen_dir):
    os.makedirs(gen_dir, exist_ok=True)
    include = os.path.dirname(os.path.abspath(proto))
    command = [sys.executable, "-m", "grpc_tools.protoc", f"-I{include}", "-I/usr/include",
               f"--python_out={gen_dir}", f"--grpc_python_out={gen_dir}", os.path.abspath(proto)]
    subprocess.run(command, check=True)
    sys.path.insert(0, gen_dir)
    return importlib.import_module("farm_pb2"), importlib.import_module("farm_pb2_grpc")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--proto", required=True)
    parser.add_argument("--gen-dir", required=True)
    parser.add_argument("--scheduler", required=True)
    parser.add_argument("--job", required=True, help="job file (sent byte for byte)")
    parser.add_argument("--asset", action="append", default=[], help="PATH_IN_JOB=LOCAL_FILE")
    parser.add_argument("--out", required=True, help="where to write the EXR")
    parser.add_argument("--timeout", type=float, default=120)
    parser.add_argument("--token-file", help="file whose first line is the token (default: $FARM_TOKEN)")
    parser.add_argument("--tls-ca", help="talk TLS, verifying the scheduler against this CA (PEM)")
    parser.add_argument("--tls-cert", help="client certificate (PEM), for mTLS")
    parser.add_argument("--tls-key", help="its private key (PEM)")
    args = parser.parse_args()

    import grpc
    pb, rpc = generate_stubs(args.proto, args.gen_dir)
    if args.tls_ca:
        def read(path):
            with open(path, "rb") as f:
                return f.read()
        credentials = grpc.ssl_channel_credentials(
            root_certificates=read(args.tls_ca),
            private_key=read(args.tls_key) if args.tls_key else None,
            certificate_chain=read(args.tls_cert) if args.tls_cert else None)
        channel = grpc.secure_channel(args.scheduler, credentials)
    else:
        channel = grpc.insecure_channel(args.scheduler)
    token = os.environ.get("FARM_TOKEN", "")
    if args.token_file:
        with open(args.token_file, encoding="utf-8") as f:
            token = f.readline().strip()
    metadata = [("authorization", "Bearer " + token)] if token else []
    scheduler = rpc.SchedulerStub(channel)
    try:
        return run(args, pb, scheduler, metadata)
    except grpc.RpcError as e:
        print(json.dumps({"error": e.code().name, "message": e.details()}))
        return 1


def run(args, pb, scheduler, metadata):
    spec = pb.JobSpec(file_name=os.path.basename(args.job))
    with open(args.job, "rb") as f:
        spec.job_json = f.read().decode("utf-8")
    local = {}
    for item in args.asset:
        path, file = item.split("=", 1)
        with open(file, "rb") as f:
            data = f.read()
        sha = hashlib.sha256(data).hexdigest()
        spec.assets.add(path=path, sha256=sha, size=len(data))
        local[sha] = data

    missing = scheduler.HasAssets(pb.HasAssetsRequest(sha256=list(local)), timeout=args.timeout,
                                  metadata=metadata).missing
    for sha in missing:
        data = local[sha]

        def parts(sha=sha, data=data):
            yield pb.UploadAssetRequest(header=pb.AssetHeader(sha256=sha, size=len(data)))
            for offset in range(0, len(data), 1 << 20):
                yield pb.UploadAssetRequest(data=data[offset:offset + (1 << 20)])
        scheduler.UploadAsset(parts(), timeout=args.timeout, metadata=metadata)

    job = scheduler.SubmitJob(pb.SubmitJobRequest(job=spec), timeout=args.timeout, metadata=metadata).job
    final = {pb.JOB_STATE_SUCCEEDED, pb.JOB_STATE_FAILED, pb.JOB_STATE_CANCELLED}
    state = job.state
    for event in scheduler.WatchJob(pb.WatchJobRequest(job_id=job.job_id), timeout=args.timeout,
                                    metadata=metadata):
        state = event.job.state
        if state in final:
            break
    result = {"job_id": job.job_id, "state": pb.JobState.Name(state), "uploaded": len(missing)}
    if state != pb.JOB_STATE_SUCCEEDED:
        print(json.dumps(result))
        return 1

    digest, expected, size = hashlib.sha256(), None, 0
    with open(args.out, "wb") as out:
        for chunk in scheduler.GetResult(pb.GetResultRequest(job_id=job.job_id, kind=pb.RESULT_KIND_EXR),
                                         timeout=args.timeout, metadata=metadata):
            if expected is None:
                expected = chunk.sha256
            out.write(chunk.data)
            digest.update(chunk.data)
            size += len(chunk.data)
    result["bytes"] = size
    result["sha256_ok"] = digest.hexdigest() == expected
    print(json.dumps(result))
    return 0 if result["sha256_ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
