#!/usr/bin/env python3
"""End-to-end check of the installed farm_client package (proto/python) against a running farm.

  farm_client_package_check.py --scheduler HOST:PORT --job JOB.json [--asset-root DIR] --out DIR
      [--token-file FILE] [--timeout SECONDS] [--prepare-only]

Run with the python of a venv that has farm-client installed (the stubs come from the package,
never from this script). It prepares the job with the scheduler (PlanSubmission: the scheduler
says which files the models name, only the missing ones are uploaded), submits it, follows its events with watch(), checking their order (tiles_done never decreases, the
final state comes last and only last), waits for the job, fetches the EXR and the preview into
--out, and checks that list() shows the job. Then dependencies and caps (#36: check_dependencies
says how, with no timing in it). Prints one JSON line:

  {"job_id": ..., "state": "SUCCEEDED", "uploaded": N, "events": N, "exr": PATH, "exr_bytes": N, "listed": true,
   "rounds": N, "asset_paths": [PATH, ...], "absent": [PATH, ...],
   "dependencies": {"z": ID, "b": ID, "c": ID, "b_failure": TEXT}}

(rounds: the PlanSubmission calls preparing took; asset_paths: the spec's, sorted; absent: the
files the models name that were not there.) With --prepare-only it stops once the job is prepared
(its files planned and uploaded, nothing submitted) and prints only uploaded, rounds, asset_paths
and absent.

and exits 0 only when all of that held. A gRPC or input error prints
{"error": CODE, "message": ...} and exits 1; so does a check that fails (error "CHECK_FAILED").
"""
import argparse
import dataclasses
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

        dependencies = check_dependencies(farm, submission, job, args.timeout)

        return {"job_id": job.job_id, "state": state, "events": len(events), "exr": exr,
                "exr_bytes": exr_bytes, "listed": listed, "preview": preview,
                "assets": len(submission.assets), **planned, "dependencies": dependencies}


def check_dependencies(farm, submission, earlier, timeout):
    """#36, with no timing in it: Z needs a worker tag no worker has, so it never starts. B after Z
    waits; its caps change while it waits; GetJob shows what each waits for and is waited for by;
    Z after B would be a cycle; a started job takes no more dependencies. Cancelling Z fails B,
    naming Z, and C, after any end of Z, runs and succeeds."""
    name = lambda s: pb.JobState.Name(s).removeprefix("JOB_STATE_")
    check(not farm_client.is_final(pb.JOB_STATE_WAITING), "is_final() takes WAITING for a final state")
    stuck = json.loads(submission.job_json)
    stuck["requirements"] = {"tags": ["no-worker-has-this"]}
    z = farm.submit(dataclasses.replace(submission, job_json=json.dumps(stuck)))
    b = farm.submit(submission, after=[z], max_workers=1)
    check(b.state == pb.JOB_STATE_WAITING, f"B was {name(b.state)} when submitted after Z, not WAITING")
    check(list(b.after) == [z.job_id], f"SubmitJob answered B.after {list(b.after)}, not [{z.job_id}]")
    limited = farm.set_limits(b, max_units_in_flight=2)
    check((limited.max_workers, limited.max_units_in_flight) == (1, 2),
          f"set_limits answered max_workers {limited.max_workers}, max_units_in_flight "
          f"{limited.max_units_in_flight}; expected 1 (kept) and 2")
    got_b, got_z = farm.get(b), farm.get(z)
    check(got_b.state == pb.JOB_STATE_WAITING, f"B is {name(got_b.state)} while Z cannot start, not WAITING")
    check(list(got_b.after) == [z.job_id] and not got_b.after_any and not got_b.after_frames,
          f"GetJob shows B after {list(got_b.after)}, after_any {list(got_b.after_any)}, after_frames "
          f"'{got_b.after_frames}'; expected after [{z.job_id}] alone")
    check(list(got_z.dependents) == [b.job_id], f"GetJob shows Z's dependents {list(got_z.dependents)}, not [B]")
    check((got_b.max_workers, got_b.max_units_in_flight) == (1, 2),
          f"GetJob shows B's caps {got_b.max_workers}, {got_b.max_units_in_flight}; expected 1, 2")

    def refused(code, call):
        try:
            call()
        except farm_client.FarmInputError as err:
            check(err.code is not None and err.code.name == code, f"{err.code_name} ({err.message}), not {code}")
            return err.message
        check(False, f"accepted where {code} was expected")

    cycle = refused("INVALID_ARGUMENT", lambda: farm.add_dependencies(z, after=[b]))
    check("cycle" in cycle, f"Z after B was refused, but not as a cycle: {cycle}")
    refused("FAILED_PRECONDITION", lambda: farm.add_dependencies(earlier, after=[z]))  # ended long ago

    c = farm.submit(submission, after_any=[z])
    farm.cancel(z)
    final_b, final_c = farm.wait(b, timeout=timeout), farm.wait(c, timeout=timeout)
    check(final_b.state == pb.JOB_STATE_FAILED and z.job_id in final_b.failure_reason,
          f"B ended {name(final_b.state)} ({final_b.failure_reason}), not FAILED naming Z")
    check(final_c.state == pb.JOB_STATE_SUCCEEDED, f"C ended {name(final_c.state)}: {final_c.failure_reason}")
    return {"z": z.job_id, "b": b.job_id, "c": c.job_id, "b_failure": final_b.failure_reason}


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
