#!/usr/bin/env python3
"""End-to-end check of the installed farm_client package (proto/python) against a running farm.

  farm_client_package_check.py --scheduler HOST:PORT --job JOB.json [--asset-root DIR] --out DIR
      [--token-file FILE] [--timeout SECONDS] [--prepare-only]

Run with the python of a venv that has farm-client installed (the stubs come from the package,
never from this script). It prepares the job with the scheduler (PlanSubmission: the scheduler
says which files the models name, only the missing ones are uploaded), submits it, follows its events with watch(), checking their order (tiles_done never decreases, the
final state comes last and only last), waits for the job, fetches the EXR and the preview into
--out, and checks that list() shows the job. Prints one JSON line:

  {"job_id": ..., "state": "SUCCEEDED", "uploaded": N, "events": N, "exr": PATH, "exr_bytes": N, "listed": true,
   "rounds": N, "asset_paths": [PATH, ...], "absent": [PATH, ...]}

(rounds: the PlanSubmission calls preparing took; asset_paths: the spec's, sorted; absent: the
files the models name that were not there.) With --prepare-only it stops once the job is prepared
(its files planned and uploaded, nothing submitted) and prints only uploaded, rounds, asset_paths
and absent.

and exits 0 only when all of that held. A gRPC or input error prints
{"error": CODE, "message": ...} and exits 1; so does a check that fails (error "CHECK_FAILED").
"""
import argparse
import json
import os
import sys

import farm_client
from farm_client import pb


class CheckFailed(Exception):
    pass


def check(condition, message):
    if not condition:
        raise CheckFailed(message)


def run(args):
    with farm_client.Farm(args.scheduler, token_file=args.token_file, timeout=args.timeout) as farm:
        submission = farm.prepare(args.job, args.asset_root)
        planned = {"uploaded": submission.uploaded, "rounds": submission.rounds,
                   "asset_paths": [a.path for a in submission.assets], "absent": submission.absent}
        if args.prepare_only:
            return planned
        job = farm.submit(submission)
        check(job.job_id, "SubmitJob answered no job id")

        events = []
        for event in farm.watch(job.job_id, timeout=args.timeout):
            events.append(event)
        check(events, "WatchJob sent no event")
        check(all(e.job.job_id == job.job_id for e in events), "an event of another job arrived")
        check(events[0].WhichOneof("event") == "snapshot",
              f"the first event is {events[0].WhichOneof('event')}, not the snapshot")
        done = [e.job.tiles_done for e in events]
        check(all(a <= b for a, b in zip(done, done[1:])), f"tiles_done went down: {done}")
        finals = [i for i, e in enumerate(events) if farm_client.is_final(e.job.state)]
        check(finals == [len(events) - 1], f"the final state is not last and alone (at {finals} of {len(events)})")

        final = farm.wait(job.job_id, timeout=args.timeout)
        check(final.state == events[-1].job.state, "wait() and watch() disagree on the final state")
        state = pb.JobState.Name(final.state).removeprefix("JOB_STATE_")
        check(final.state == pb.JOB_STATE_SUCCEEDED, f"the job ended {state}: {final.failure_reason}")
        check(final.tiles_done == final.tiles_total, f"{final.tiles_done} of {final.tiles_total} tiles done")

        os.makedirs(args.out, exist_ok=True)
        exr = farm.fetch(job.job_id, args.out, kind="exr")
        preview = farm.fetch(job.job_id, args.out, kind="preview")
        exr_bytes = os.path.getsize(exr)
        with open(exr, "rb") as f:
            check(f.read(4) == b"\x76\x2f\x31\x01", f"{exr} is not an OpenEXR file")
        with open(preview, "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", f"{preview} is not a PNG file")

        listed = any(j.job_id == job.job_id for j in farm.list(limit=0))
        check(listed, f"list() does not show {job.job_id}")
        # The scheduler's filters too: by state and by a name glob.
        filtered = farm.list(states=["succeeded"], name=final.name, limit=0)
        check(any(j.job_id == job.job_id for j in filtered),
              f"list(states=['succeeded'], name={final.name!r}) does not show {job.job_id}")
        # A unique start of the id finds the job, as `farm status ID` does.
        check(farm.get(job.job_id[:6]).job_id == job.job_id, "the id prefix did not resolve to the job")

        return {"job_id": job.job_id, "state": state, "events": len(events), "exr": exr,
                "exr_bytes": exr_bytes, "listed": listed, "preview": preview,
                "assets": len(submission.assets), **planned}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scheduler", required=True, help="HOST:PORT")
    parser.add_argument("--job", required=True, help="job file")
    parser.add_argument("--asset-root", help="folder the job's files must lie in (default: the job's folder)")
    parser.add_argument("--out", required=True, help="folder for the EXR and the preview")
    parser.add_argument("--token-file", help="file whose first line is the token (default: $FARM_TOKEN)")
    parser.add_argument("--timeout", type=float, default=300, help="seconds for each step (default 300)")
    parser.add_argument("--prepare-only", action="store_true", help="stop once the job is prepared")
    args = parser.parse_args()
    try:
        result = run(args)
    except farm_client.FarmError as err:
        print(json.dumps({"error": err.code_name, "message": err.message}))
        return 1
    except CheckFailed as err:
        print(json.dumps({"error": "CHECK_FAILED", "message": str(err)}))
        return 1
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
