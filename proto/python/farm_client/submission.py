"""A job file turned into what a scheduler is sent (farm.v1.JobSpec): the job's text and every file
it reads, named by content, as server/client/job_submission.cpp makes it for `farm submit`.

Which files a job reads besides its models is the scheduler's to say: this package reads no model
format. The job's models are found, confined and hashed here; then the scheduler is asked
(PlanSubmission) which of the files it lacks and which files the models name, read with the code
`farm submit` scans with. Each needed file is confined under the asset root here (confine.py),
hashed and described, or listed absent when there is no file; what the scheduler lacks is
uploaded; until the plan is complete. A reply is checked before it is trusted: every path asked
for must be relative, lexically normal and inside the root, asked for once.

Asset paths in the spec are relative to the asset root (the job file's folder unless asset_root
says otherwise). When the job's own folder is that root, the job text goes as it is, byte for
byte; otherwise its model paths are rewritten relative to the root (the scheduler lays the files
out under the root and reads the job from there).

The job is not validated here beyond what finding its models needs (the JSON,
scene.objects[].file): the scheduler judges the rest and its refusal names the file and the JSON
path.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import posixpath
import stat

from .confine import (ALLOWED, MISSING, absolute, confine_file, lexically_normal, lexically_relative,
                      open_confined, shown, weakly_canonical)
from ._gen import farm_pb2 as pb
from .errors import FarmError, FarmInputError

__all__ = ["JobSubmission", "make_job_submission", "MAX_JOB_FILE_BYTES", "MAX_JOB_ASSETS",
           "MAX_ASSET_BYTES", "MAX_JOB_ASSET_BYTES"]

# The C++ side's bounds, so that a job the scheduler would refuse is refused before anything is
# hashed or sent: the job file (renderer/job/job_limits.h), the number of a job's files
# (server/common/scene_materializer.h) and the scheduler's default --max-asset-bytes and
# --max-job-asset-bytes (server/scheduler/options/submit_limits.h).
MAX_JOB_FILE_BYTES = 16 << 20
MAX_JOB_ASSETS = 10000
MAX_ASSET_BYTES = 2 << 30
MAX_JOB_ASSET_BYTES = 4 << 30

_READ_BYTES = 1 << 20
_MAX_ASSET_PATH_BYTES = 1024  # server/common/scene_materializer.h, kMaxAssetPathBytes
_UPLOADS_OF_ONE_FILE = 2      # a blob the scheduler found damaged and removed is sent once more
_SHOWN_TEXT = 64  # a user's string inside a job error, as renderer/job/job.cpp shortens it


@dataclasses.dataclass
class Asset:
    path: str      # the AssetRef path: relative to the asset root, '/'-separated
    sha256: str
    size: int
    file: str      # the local file with those bytes (resolved)


@dataclasses.dataclass
class JobSubmission:
    """What Farm.submit sends. `assets` is sorted by path, each path once; `files` maps each
    sha256 to a local file with those bytes. `uploaded` is set once the missing ones are sent."""
    job_file: str
    file_name: str
    job_json: str
    asset_root: str
    assets: list[Asset]
    files: dict[str, str]
    files_scanned: int = 0   # 0: the scheduler reads the models for the files they name
    files_hashed: int = 0
    uploaded: int | None = None
    rounds: int = 0          # PlanSubmission calls it took
    absent: list[str] = dataclasses.field(default_factory=list)  # named by a model, no file here

    @property
    def total_bytes(self) -> int:
        return sum(asset.size for asset in self.assets)


def _read_job_file(path: str) -> bytes:
    """As renderer/job/job.cpp's read_job_file: a regular file of at most 16 MiB."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FarmInputError(f"{path}: no such job file") from None
    except OSError as err:
        raise FarmInputError(f"{path}: cannot read the job file: {err.strerror}") from None
    # Devices and FIFOs could block or never end; a job is always a plain file.
    if not stat.S_ISREG(st.st_mode):
        raise FarmInputError(f"{path}: the job file is not a regular file")
    if st.st_size > MAX_JOB_FILE_BYTES:
        raise FarmInputError(f"{path}: the job file is {st.st_size} bytes; the limit is {MAX_JOB_FILE_BYTES}")
    return read_at_most(path, MAX_JOB_FILE_BYTES, "the job file")


def read_at_most(path, limit: int, what: str) -> bytes:
    """The bytes of `path`, refused (FarmInputError naming it and `what`) beyond `limit`: a file
    that grew, or never ends, is not read without bound."""
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
    except OSError as err:
        raise FarmInputError(f"{os.fsdecode(path)}: cannot read {what}: {err.strerror}") from None
    if len(data) > limit:
        raise FarmInputError(f"{os.fsdecode(path)}: {what} is over {limit} bytes")
    return data


def _no_duplicates(pairs):
    doc = {}
    for key, value in pairs:
        if key in doc:
            raise ValueError(f"duplicate key '{shown(key, _SHOWN_TEXT)}'")
        doc[key] = value
    return doc


def _reject_constant(name):
    raise ValueError(f"invalid literal '{name}'")


def _parse_int(text: str):
    # nlohmann::json keeps integers in int64 or uint64 and anything larger as a double; the
    # rewritten text must print them as the C++ client would.
    value = int(text)
    return value if -(1 << 63) <= value < (1 << 64) else float(value)


def _parse_job_json(text: str, job_file: str):
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates, parse_constant=_reject_constant,
                          parse_int=_parse_int)
    except json.JSONDecodeError as err:
        raise FarmInputError(f"{job_file}:{err.lineno}:{err.colno}: JSON syntax error: {err.msg}") from None
    except (ValueError, RecursionError) as err:
        raise FarmInputError(f"{job_file}: JSON syntax error: {err}") from None


def _describe(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"a boolean ({'true' if value else 'false'})"
    if isinstance(value, (int, float)):
        return f"a number ({json.dumps(value)})"
    if isinstance(value, str):
        return f"a string (\"{shown(value, _SHOWN_TEXT)}\")"
    if isinstance(value, list):
        return f"an array of {len(value)}"
    return "an object"


def _model_paths(doc, job_file: str) -> list[str]:
    """scene.objects[i].file, each checked as far as finding the files needs."""
    def fail(path: str, message: str):
        raise FarmInputError(f"{job_file}: {path}: {message}")

    if not isinstance(doc, dict):
        fail("(the top level)", f"expected an object, got {_describe(doc)}")
    if "scene" not in doc:
        fail("scene", "required key is missing")
    scene = doc["scene"]
    if not isinstance(scene, dict):
        fail("scene", f"expected an object, got {_describe(scene)}")
    if "objects" not in scene:
        fail("scene.objects", "required key is missing")
    objects = scene["objects"]
    if not isinstance(objects, list):
        fail("scene.objects", f"expected an array, got {_describe(objects)}")
    if not objects:
        fail("scene.objects", "expected at least one object, got an empty array")
    out = []
    for i, item in enumerate(objects):
        where = f"scene.objects[{i}]"
        if not isinstance(item, dict):
            fail(where, f"expected an object, got {_describe(item)}")
        if "file" not in item:
            fail(where + ".file", "required key is missing")
        written = item["file"]
        if not isinstance(written, str):
            fail(where + ".file", f"expected a string, got {_describe(written)}")
        if not written:
            fail(where + ".file", "expected a file path, got an empty string")
        out.append(written)
    return out


def _digest(root: str, resolved: str, path: str, max_bytes: int) -> tuple[str, int]:
    """sha256 and size of a file the scan allowed, read through the same gate again: a file swapped
    for a FIFO or a link since it was scanned is refused, not waited on or followed."""
    checked = confine_file(root, resolved, resolved, allow_absolute=True)
    if checked.verdict != ALLOWED:
        raise FarmInputError(f"{resolved}: cannot read '{path}': {checked.reason or 'no such file'}")
    if checked.size > max_bytes:
        raise FarmInputError(f"{resolved}: asset '{path}' is {checked.size} bytes; the scheduler takes at "
                             f"most {max_bytes} an asset")
    try:
        fd = open_confined(checked)
    except OSError as err:
        raise FarmInputError(f"{resolved}: cannot read '{path}': {err.strerror or err}") from None
    digest = hashlib.sha256()
    size = 0
    try:
        while True:
            chunk = os.read(fd, _READ_BYTES)
            if not chunk:
                break
            size += len(chunk)
            if size > max_bytes:  # it grew since it was looked at
                raise FarmInputError(f"{resolved}: asset '{path}' is over {max_bytes} bytes")
            digest.update(chunk)
    except OSError as err:
        raise FarmInputError(f"{resolved}: cannot read: {err.strerror}") from None
    finally:
        os.close(fd)
    return digest.hexdigest(), size


def _checked_needed_path(path: str) -> str:
    """A path the scheduler asked for, refused unless it is one an asset can have: relative,
    '/'-separated, lexically normal (no ".", no ".."), naming a file, bounded."""
    if (not path or "\0" in path or path.startswith("/") or path.endswith("/")
            or len(path.encode("utf-8", "surrogatepass")) > _MAX_ASSET_PATH_BYTES
            or lexically_normal(path) != path or path.split("/")[0] in (".", "..")):
        raise FarmError(f"PlanSubmission: the scheduler asked for '{shown(path, _SHOWN_TEXT)}', which is not a "
                        "relative, normalised path inside the asset root; nothing was read")
    return path


def _spec_of(job_json: str, file_name: str, assets, job_file: str):
    try:
        spec = pb.JobSpec(job_json=job_json, file_name=file_name)
        for asset in assets:
            spec.assets.add(path=asset.path, sha256=asset.sha256, size=asset.size)
    except (ValueError, TypeError) as err:
        # A proto string must be UTF-8: a path of bytes that are not cannot be sent.
        raise FarmInputError(f"{job_file}: cannot be sent: {err}") from None
    return spec


def make_job_submission(job_file, asset_root=None, *, farm, max_assets: int = MAX_JOB_ASSETS,
                        max_asset_bytes: int = MAX_ASSET_BYTES,
                        max_total_bytes: int = MAX_JOB_ASSET_BYTES) -> JobSubmission:
    """The job file and every file it reads (its models, and what the scheduler finds they name),
    hashed, the ones `farm` (a Farm) lacks uploaded. Raises FarmInputError, naming the file and
    the place, for a job whose models cannot be found or a file that confine_file refuses (the
    message names the file that names it and the reference): nothing refused is read; FarmError
    for a scheduler without PlanSubmission or whose replies cannot be trusted."""
    job_file = os.fsdecode(job_file)
    data = _read_job_file(job_file)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise FarmInputError(f"{job_file}: the job file is not UTF-8 (byte {err.start})") from None
    doc = _parse_job_json(text, job_file)
    written_models = _model_paths(doc, job_file)

    # As parse_job: the root resolved, model paths taken from the job file's (resolved) folder.
    job_dir_unresolved = posixpath.dirname(absolute(job_file))
    root_unresolved = absolute(os.fsdecode(asset_root)) if asset_root else job_dir_unresolved
    try:
        root = weakly_canonical(root_unresolved)
    except OSError as err:
        raise FarmInputError(f"{job_file}: cannot resolve the asset root '{root_unresolved}': {err.strerror}") from None
    try:
        job_dir = weakly_canonical(job_dir_unresolved)
    except OSError as err:
        raise FarmInputError(f"{job_file}: cannot resolve its folder: {err.strerror}") from None
    referrer = posixpath.join(job_dir, posixpath.basename(job_file))

    models: list[str] = []
    resolved_by_written: dict[str, str] = {}
    for i, written in enumerate(written_models):
        if written not in resolved_by_written:
            # A person writes a job on their own machine: an absolute path is fine if it lies in
            # the root (the rewrite below makes it relative before it travels).
            file = confine_file(root, referrer, written, allow_absolute=True)
            where = f"{job_file}: scene.objects[{i}].file"
            if file.verdict == MISSING:
                raise FarmInputError(f"{where}: no such file '{shown(written, _SHOWN_TEXT)}'")
            if file.verdict != ALLOWED:
                raise FarmInputError(f"{where}: {file.reason}")
            resolved_by_written[written] = file.resolved
        models.append(resolved_by_written[written])

    if job_dir == root:
        job_json = text  # byte for byte, as written
    else:
        # Model paths relative to the root, the rest as written; printed as the C++ client prints
        # it (nlohmann's dump(2): keys sorted, two spaces an indent).
        for item, model in zip(doc["scene"]["objects"], models):
            item["file"] = lexically_relative(model, root)
        job_json = json.dumps(doc, indent=2, ensure_ascii=False, sort_keys=True) + "\n"

    submission = JobSubmission(job_file=job_file, file_name=posixpath.basename(job_file), job_json=job_json,
                               asset_root=root, assets=[], files={}, uploaded=0)
    by_path: dict[str, Asset] = {}
    digests: dict[str, tuple[str, int]] = {}  # resolved file -> digest: each file hashed once
    total = 0

    def describe(path: str, resolved: str) -> None:
        nonlocal total
        if len(by_path) + len(submission.absent) >= max_assets:
            raise FarmInputError(f"{job_file}: the job reads more than {max_assets} files; a scheduler "
                                 f"takes at most {max_assets}")
        if resolved not in digests:
            digests[resolved] = _digest(root, resolved, path, max_asset_bytes)
        sha, size = digests[resolved]
        total += size
        if total > max_total_bytes:
            raise FarmInputError(f"{job_file}: the job's files are more than {max_total_bytes} bytes "
                                 "together; a scheduler takes at most that a job")
        by_path[path] = Asset(path=path, sha256=sha, size=size, file=resolved)
        submission.files.setdefault(sha, resolved)

    # The models under their resolved names, relative to the root, as the rewrite names them.
    for model in models:
        path = lexically_relative(model, root)
        if path not in by_path:
            describe(path, model)

    uploads: dict[str, int] = {}
    # Each round uploads a file or describes one asked for (each asked for once, each uploaded at
    # most twice), so a scheduler that keeps answering without asking anything new is cut short.
    for _ in range(3 * max_assets + 2):
        assets = [by_path[p] for p in sorted(by_path)]  # str order is UTF-8 byte order: the C++ std::map's
        plan = farm._plan(_spec_of(job_json, submission.file_name, assets, job_file), submission.absent)
        submission.rounds += 1
        if plan.complete:
            if plan.missing_sha256 or plan.needed:
                raise FarmError("PlanSubmission: the scheduler answered complete while asking for files")
            submission.assets = assets
            submission.files_hashed = len(digests)
            return submission
        progress = False
        for sha in plan.missing_sha256:
            if sha not in submission.files:
                raise FarmError(f"PlanSubmission: the scheduler asked for '{shown(sha, _SHOWN_TEXT)}', a hash this "
                                "job does not have")
            uploads[sha] = uploads.get(sha, 0) + 1
            if uploads[sha] > _UPLOADS_OF_ONE_FILE:
                raise FarmError(f"PlanSubmission: the scheduler keeps asking for {sha} "
                                f"({submission.files[sha]}), uploaded {_UPLOADS_OF_ONE_FILE} times")
            farm._upload(sha, submission.files[sha])
            submission.uploaded += 1
            progress = True
        absent = set(submission.absent)
        for needed in plan.needed:
            path = _checked_needed_path(needed.path)
            if path in by_path or path in absent:
                raise FarmError(f"PlanSubmission: the scheduler asked again for '{shown(path, _SHOWN_TEXT)}', "
                                "which this client has described already")
            # Confined here, under the root, as the C++ client confines a model's reference.
            file = confine_file(root, posixpath.join(root, ".plan"), path)
            if file.verdict == MISSING:
                submission.absent.append(path)
                absent.add(path)
            elif file.verdict == ALLOWED:
                describe(path, file.resolved)
            else:
                named_by = posixpath.join(root, shown(needed.named_by, _SHOWN_TEXT))
                raise FarmInputError(f"{named_by}: '{shown(needed.reference, _SHOWN_TEXT)}': {file.reason}")
            progress = True
        if not progress:
            raise FarmError("PlanSubmission: the scheduler answered that the job is not ready to submit, "
                            "but asked for nothing")
    raise FarmError(f"PlanSubmission: no complete plan after {submission.rounds} rounds")
