"""farm_client: a Python client of the render farm's scheduler (farm.v1.Scheduler).

    import farm_client
    with farm_client.Farm("localhost:50051") as farm:
        job = farm.submit("jobs/cornell.json")      # hashes and uploads its assets (the scheduler says which)
        for event in farm.watch(job):              # JobEvent, until a final state
            print(event.job.tiles_done, "/", event.job.tiles_total)
        farm.fetch(job, "cornell.exr")

farm_client.pb holds the generated messages (farm_client.pb.Job, pb.JOB_STATE_SUCCEEDED, ...),
farm_client.rpc the generated stubs; both are generated from proto/farm.proto when the package is
built (setup.py), never committed.
"""
import sys

try:
    from ._gen import farm_pb2 as pb
    from ._gen import farm_pb2_grpc as rpc
except ImportError as err:  # pragma: no cover - only a source checkout that was never built
    raise ImportError(
        "farm_client's gRPC stubs are missing: they are generated when the package is built; "
        "install it (pip install --no-build-isolation proto/python) rather than importing it "
        f"from the source tree ({err})") from err

# `import farm_client.pb` (and `from farm_client.pb import Job`) find the generated modules too.
sys.modules[__name__ + ".pb"] = pb
sys.modules[__name__ + ".rpc"] = rpc

from .client import DEFAULT_ADDRESS, FINAL_STATES, Farm, is_final, state_name  # noqa: E402
from .errors import (FarmAccessDenied, FarmError, FarmInputError, FarmTimeout,  # noqa: E402
                     FarmUnavailable)
from .submission import Asset, JobSubmission, make_job_submission  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "Farm", "JobSubmission", "Asset", "make_job_submission",
    "FarmError", "FarmInputError", "FarmUnavailable", "FarmAccessDenied", "FarmTimeout",
    "DEFAULT_ADDRESS", "FINAL_STATES", "is_final", "state_name", "pb", "rpc",
]
