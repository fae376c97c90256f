#!/usr/bin/env python3
"""The installed farm_client package (proto/python) against schedulers that misbehave: a reply from
another process is checked before it is trusted (docs/architecture.md, section 3.1).

  farm_client_plan_check.py

Run with the python of a venv that has farm-client installed. Each case starts a fake
farm.v1.Scheduler in this process, on loopback, and prepares a job (an OBJ in a fresh folder)
against it; the case holds when prepare() raises the error it names. Prints one JSON line,
{"cases": N} or {"error": "CHECK_FAILED", "message": ...}, and exits 0 only when every case held.
"""
import concurrent.futures
import json
import os
import sys
import tempfile

import grpc

import farm_client
from farm_client import pb, rpc


class CheckFailed(Exception):
    pass


class Older(rpc.SchedulerServicer):
    """A scheduler from before PlanSubmission: the generated servicer answers UNIMPLEMENTED."""


class Asking(rpc.SchedulerServicer):
    """Answers every plan by asking for `paths` (the model's own hash counts as held)."""

    def __init__(self, paths, complete=False):
        self.paths = paths
        self.complete = complete
        self.calls = 0

    def PlanSubmission(self, request, context):
        self.calls += 1
        needed = [pb.NeededFile(path=p, named_by="m.obj", reference=p) for p in self.paths]
        return pb.PlanSubmissionResponse(needed=needed, complete=self.complete)


def prepare_against(servicer, folder):
    server = grpc.server(concurrent.futures.ThreadPoolExecutor(max_workers=2))
    rpc.add_SchedulerServicer_to_server(servicer, server)
    port = server.add_insecure_port("127.0.0.1:0")
    server.start()
    try:
        with farm_client.Farm(f"127.0.0.1:{port}", timeout=20) as farm:
            return farm.prepare(os.path.join(folder, "job.json"))
    finally:
        server.stop(None)


def expect_refusal(servicer, folder, kind, words):
    try:
        prepare_against(servicer, folder)
    except farm_client.FarmError as err:
        if type(err) is not kind or words not in err.message:
            raise CheckFailed(f"{type(servicer).__name__}: {type(err).__name__} '{err.message}', expected "
                              f"{kind.__name__} with '{words}'") from None
        return
    raise CheckFailed(f"{type(servicer).__name__}: prepare() trusted the scheduler")


def run():
    with tempfile.TemporaryDirectory() as top:
        folder = os.path.join(top, "job")
        os.makedirs(folder)
        with open(os.path.join(folder, "job.json"), "w") as f:
            json.dump({"version": 1, "scene": {"objects": [{"file": "m.obj"}]}}, f)
        with open(os.path.join(folder, "m.obj"), "w") as f:
            f.write("mtllib m.mtl\nv 0 0 0\n")
        with open(os.path.join(folder, "m.mtl"), "w") as f:
            f.write("newmtl a\n")
        with open(os.path.join(top, "secret.png"), "w") as f:
            f.write("not the job's")
        os.symlink(os.path.join(top, "secret.png"), os.path.join(folder, "link.png"))

        cases = [
            (Older(), farm_client.FarmError, "older than this client"),
            (Asking(["../secret.png"]), farm_client.FarmError, "not a relative, normalised path"),
            (Asking(["/etc/passwd"]), farm_client.FarmError, "not a relative, normalised path"),
            (Asking(["./m.mtl"]), farm_client.FarmError, "not a relative, normalised path"),
            (Asking(["m.mtl"]), farm_client.FarmError, "asked again for 'm.mtl'"),
            (Asking([]), farm_client.FarmError, "asked for nothing"),
            (Asking(["m.mtl"], complete=True), farm_client.FarmError, "answered complete while asking"),
            # A link out of the root is refused here, naming the file that names it and the reference.
            (Asking(["link.png"]), farm_client.FarmInputError, "m.obj: 'link.png': 'link.png' lies outside"),
        ]
        for servicer, kind, words in cases:
            expect_refusal(servicer, folder, kind, words)
        return {"cases": len(cases)}


def main():
    try:
        result = run()
    except CheckFailed as err:
        print(json.dumps({"error": "CHECK_FAILED", "message": str(err)}))
        return 1
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
