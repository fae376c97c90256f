"""A job file turned into what a scheduler is sent (farm.v1.JobSpec): the job's text and every file
it reads, named by content, as server/client/job_submission.cpp makes it for `farm submit`.

Asset paths in the spec are relative to the asset root (the job file's folder unless asset_root
says otherwise). When the job's own folder is that root, the job text goes as it is, byte for
byte; otherwise its model paths are rewritten relative to the root (the scheduler lays the files
out under the root and reads the job from there).

The job is not validated here beyond what finding its files needs (the JSON, scene.objects[].file):
the scheduler judges the rest and its refusal names the file and the JSON path.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import posixpath
import stat

from .confine import (ALLOWED, MISSING, absolute, confine_file, lexically_relative, open_confined,
                      shown, weakly_canonical)
from .dependencies import ModelDependencyScanner
from .errors import FarmInputError

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
    files_scanned: int = 0   # models and material libraries read to find references
    files_hashed: int = 0
    uploaded: int | None = None

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


def make_job_submission(job_file, asset_root=None, *, max_assets: int = MAX_JOB_ASSETS,
                        max_asset_bytes: int = MAX_ASSET_BYTES,
                        max_total_bytes: int = MAX_JOB_ASSET_BYTES) -> JobSubmission:
    """The job file and every file it reads (its models, and what they name), hashed. Raises
    FarmInputError, naming the file and the place, for a job whose files cannot be found or a
    model reference that confine_file refuses: nothing refused is read."""
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
        # Model paths relative to the root, the rest as written, in the user's key order; printed
        # as nlohmann's dump(2) prints it.
        for item, model in zip(doc["scene"]["objects"], models):
            item["file"] = lexically_relative(model, root)
        job_json = json.dumps(doc, indent=2, ensure_ascii=False) + "\n"

    # spec path -> the file to read (resolved). The models go under their resolved names, what
    # they reference under the names the models use, since a worker lays the files out by those.
    by_path: dict[str, str] = {}
    scanner = ModelDependencyScanner(root, max_read_bytes=max_asset_bytes)
    for model in models:
        by_path.setdefault(lexically_relative(model, root), model)
        for dependency in scanner.dependencies(model):
            by_path.setdefault(lexically_relative(dependency.named, root), dependency.resolved)
        if len(by_path) > max_assets:
            raise FarmInputError(f"{job_file}: the job reads more than {max_assets} files; a scheduler "
                                 f"takes at most {max_assets}")

    assets: list[Asset] = []
    files: dict[str, str] = {}
    digests: dict[str, tuple[str, int]] = {}  # resolved file -> digest: each file hashed once
    total = 0
    for path in sorted(by_path):  # str order is UTF-8 byte order: the C++ std::map's
        resolved = by_path[path]
        if resolved not in digests:
            digests[resolved] = _digest(root, resolved, path, max_asset_bytes)
        sha, size = digests[resolved]
        total += size
        if total > max_total_bytes:
            raise FarmInputError(f"{job_file}: the job's files are more than {max_total_bytes} bytes "
                                 "together; a scheduler takes at most that a job")
        assets.append(Asset(path=path, sha256=sha, size=size, file=resolved))
        files.setdefault(sha, resolved)
    return JobSubmission(job_file=job_file, file_name=posixpath.basename(job_file), job_json=job_json,
                         asset_root=root, assets=assets, files=files,
                         files_scanned=scanner.files_scanned, files_hashed=len(digests))
