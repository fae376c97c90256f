"""farm_client.Farm: the client side of farm.v1.Scheduler, as the `farm` commands use it
(server/client/scheduler_client.cpp, scheduler_connection.cpp, server/common/client_identity.cpp).
"""
from __future__ import annotations

import collections
import errno
import hashlib
import os
import posixpath
import secrets
import stat
import time
from typing import Iterable, Iterator

import grpc

from ._gen import farm_pb2 as pb
from ._gen import farm_pb2_grpc as rpc
from .errors import FarmError, FarmInputError, FarmUnavailable, error_from_rpc
from .submission import JobSubmission, make_job_submission, read_at_most

__all__ = ["Farm", "DEFAULT_ADDRESS", "FINAL_STATES", "is_final", "state_name"]

DEFAULT_ADDRESS = "localhost:50051"
FINAL_STATES = frozenset({pb.JOB_STATE_SUCCEEDED, pb.JOB_STATE_FAILED, pb.JOB_STATE_CANCELLED})

_CHUNK_BYTES = 1 << 20    # UploadAsset pieces: well under gRPC's 4 MiB message limit
_LIST_PAGE = 1000         # the scheduler's largest ListJobs page
_MAX_PEM_BYTES = 1 << 20  # as server/common/tls_files.cpp reads them
_MAX_WATCH_RESTARTS = 10  # streams that may end early (a scheduler restart) during one watch
_RESOLVED_CACHE = 1024    # job ids whose prefix was resolved, remembered per Farm

_RESULT_KINDS = {
    "exr": pb.RESULT_KIND_EXR,
    "preview": pb.RESULT_KIND_PREVIEW,
    "video": pb.RESULT_KIND_VIDEO,
    "progressive": pb.RESULT_KIND_PROGRESSIVE,
}
_DEFAULT_SUFFIX = {pb.RESULT_KIND_EXR: ".exr", pb.RESULT_KIND_PREVIEW: ".png",
                   pb.RESULT_KIND_VIDEO: ".mp4", pb.RESULT_KIND_PROGRESSIVE: ".png"}


def is_final(state: int) -> bool:
    """SUCCEEDED, FAILED or CANCELLED: the job will not change again (until a retry)."""
    return state in FINAL_STATES


def state_name(state: int) -> str:
    """"succeeded" for JOB_STATE_SUCCEEDED, as `farm status` prints it."""
    return pb.JobState.Name(state).removeprefix("JOB_STATE_").lower()


def _job_state(value) -> int:
    """A state given as the enum value, "queued", "QUEUED" or "JOB_STATE_QUEUED"."""
    if isinstance(value, int):
        return value
    name = str(value).upper()
    if not name.startswith("JOB_STATE_"):
        name = "JOB_STATE_" + name
    try:
        return pb.JobState.Value(name)
    except ValueError:
        raise FarmInputError(f"unknown job state '{value}' (expected waiting, queued, running, "
                             "succeeded, failed or cancelled)") from None


def _cap(value, name: str) -> int:
    """A job cap (uint32 on the wire): a whole number from 0; refused here rather than by protobuf."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 1 << 32:
        raise FarmInputError(f"{name} must be a whole number from 0 (0: no cap), not {value!r}")
    return value


def _well_formed_token(token: str) -> bool:
    # server/common/token_table.cpp: 16 to 512 printable ASCII characters, no spaces.
    return 16 <= len(token) <= 512 and all(" " < c <= "~" for c in token)


def _read_token(token: str | None, token_file) -> str:
    """The token: given, else the first line of token_file, else FARM_TOKEN; "" for none."""
    if token:
        origin = "the token given"
    elif token_file:
        origin = os.fsdecode(token_file)
        try:
            with open(token_file, encoding="utf-8", errors="replace") as f:
                token = f.readline(1024).rstrip("\n")  # longer than any token: refused below
        except OSError as err:
            raise FarmInputError(f"{origin}: cannot read the token file: {err.strerror}") from None
    elif os.environ.get("FARM_TOKEN"):
        token, origin = os.environ["FARM_TOKEN"], "FARM_TOKEN"
    else:
        return ""
    token = token.rstrip("\r \t")
    if not _well_formed_token(token):
        raise FarmInputError(f"{origin}: not a farm token (16 to 512 printable characters, no spaces; "
                             "`farm token` makes one)")
    return token


def _read_pem(path, what: str) -> bytes:
    return read_at_most(path, _MAX_PEM_BYTES, "the " + what)


class Farm:
    """A connection to a farm scheduler.

    address   HOST:PORT; default $FARM_SCHEDULER, else localhost:50051.
    token     the bearer token; default: the first line of token_file, else $FARM_TOKEN. Sent as
              `authorization: Bearer <token>` metadata on every call, as `farm` sends it.
    tls_ca    talk TLS, verifying the scheduler against this CA (PEM file; default $FARM_TLS_CA).
              tls_cert and tls_key (default $FARM_TLS_CERT, $FARM_TLS_KEY): a client certificate
              for mTLS; either alone also means TLS, against the system's roots.
    timeout   seconds each unary call may take. Streams (watch, uploads, downloads) are not
              bounded by it: watch and wait take their own, transfers `transfer_timeout`.

    Every method that names a job takes its whole id or any unique start of it (as `farm` does),
    or a Job message. Failures raise FarmError subclasses (farm_client.errors).
    """

    def __init__(self, address: str | None = None, token: str | None = None, token_file=None,
                 tls_ca=None, tls_cert=None, tls_key=None, timeout: float | None = 60.0,
                 transfer_timeout: float | None = None, channel_options: Iterable | None = None):
        self.address = address or os.environ.get("FARM_SCHEDULER") or DEFAULT_ADDRESS
        self.timeout = timeout
        self.transfer_timeout = transfer_timeout
        token = _read_token(token, token_file)
        # Metadata on each call rather than call credentials: gRPC sends call credentials only
        # over TLS, and a loopback farm with tokens may run without it (client_identity.cpp).
        self._metadata = (("authorization", "Bearer " + token),) if token else ()
        tls_ca = tls_ca or os.environ.get("FARM_TLS_CA") or None
        tls_cert = tls_cert or os.environ.get("FARM_TLS_CERT") or None
        tls_key = tls_key or os.environ.get("FARM_TLS_KEY") or None
        if bool(tls_cert) != bool(tls_key):
            raise FarmInputError("a client certificate needs both tls_cert and tls_key")
        options = list(channel_options or ())
        if tls_ca or tls_cert:
            credentials = grpc.ssl_channel_credentials(
                root_certificates=_read_pem(tls_ca, "CA certificates") if tls_ca else None,
                private_key=_read_pem(tls_key, "private key") if tls_key else None,
                certificate_chain=_read_pem(tls_cert, "certificate") if tls_cert else None)
            self._channel = grpc.secure_channel(self.address, credentials, options)
        else:
            self._channel = grpc.insecure_channel(self.address, options)
        self._stub = rpc.SchedulerStub(self._channel)
        self._resolved: collections.OrderedDict[str, str] = collections.OrderedDict()

    # ---- plumbing ------------------------------------------------------------------------------

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> "Farm":
        return self

    def __exit__(self, *_exc) -> None:
        self.close()

    def _call(self, method: str, request, timeout: float | None = None):
        """One unary call; a failure raised as the FarmError its status code calls for."""
        try:
            return getattr(self._stub, method)(request, timeout=timeout or self.timeout,
                                               metadata=self._metadata)
        except grpc.RpcError as err:
            raise error_from_rpc(err, method, self.address) from None

    def _id(self, job) -> str:
        if isinstance(job, pb.Job):
            return job.job_id
        return self.resolve_job_id(job)

    def _ids(self, jobs) -> list:
        """Ids of a list of jobs; one job alone (an id, a Job) is a list of one, not of characters."""
        if isinstance(jobs, (str, pb.Job)):
            jobs = [jobs]
        return [self._id(j) for j in jobs or ()]

    # ---- jobs ----------------------------------------------------------------------------------

    def prepare(self, job_file, asset_root=None) -> JobSubmission:
        """The job file and every file it reads, hashed, and those the scheduler lacks uploaded;
        the job not yet submitted (farm_client.submission). The scheduler says which files the
        models name (PlanSubmission): this package reads no model format, so preparing needs the
        scheduler. FarmInputError for a bad job or a refused reference; FarmError for a scheduler
        older than this client (no PlanSubmission)."""
        return make_job_submission(job_file, asset_root, farm=self)

    def _plan(self, spec, absent):
        """One PlanSubmission call: PlanSubmissionResponse."""
        request = pb.PlanSubmissionRequest(job=spec, absent=absent)
        try:
            return self._stub.PlanSubmission(request, timeout=self.timeout, metadata=self._metadata)
        except grpc.RpcError as err:
            if hasattr(err, "code") and err.code() == grpc.StatusCode.UNIMPLEMENTED:
                raise FarmError(f"PlanSubmission: the scheduler at {self.address} does not offer it: the "
                                "scheduler is older than this client, which asks it which files a job "
                                "needs; upgrade the scheduler", err.code(), err.details() or "") from None
            raise error_from_rpc(err, "PlanSubmission", self.address) from None

    def upload_missing(self, submission: JobSubmission) -> int:
        """Uploads the files the scheduler lacks (HasAssets first); returns how many were sent."""
        shas = sorted(submission.files)
        missing = list(self._call("HasAssets", pb.HasAssetsRequest(sha256=shas)).missing)
        sent = 0
        for sha in missing:
            file = submission.files.get(sha)
            if file is None:
                continue  # not one we asked about
            self._upload(sha, file)
            sent += 1
        submission.uploaded = sent
        return sent

    def _upload(self, sha: str, file: str) -> None:
        # Hashed when the submission was made; opened again without following a link or waiting
        # on a FIFO, in case it was swapped since. Its bytes are hashed again as they go, so a
        # file changed since is refused here rather than sent under a wrong name.
        try:
            fd = os.open(file, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError as err:
            raise FarmInputError(f"{file}: cannot read the asset: {err.strerror}") from None
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                raise FarmInputError(f"{file}: cannot read the asset (no longer a regular file)")
            os.set_blocking(fd, True)
            problem: list[FarmError] = []

            def parts():
                # An exception raised in here would only be logged by gRPC: a problem ends the
                # stream short instead (which the scheduler refuses) and is raised below.
                yield pb.UploadAssetRequest(header=pb.AssetHeader(sha256=sha, size=st.st_size))
                digest, sent = hashlib.sha256(), 0
                while sent < st.st_size:
                    try:
                        chunk = os.read(fd, min(_CHUNK_BYTES, st.st_size - sent))
                    except OSError as err:
                        problem.append(FarmInputError(f"{file}: cannot read the asset: {err.strerror}"))
                        return
                    if not chunk:
                        break
                    digest.update(chunk)
                    sent += len(chunk)
                    if sent == st.st_size and digest.hexdigest() != sha:
                        break
                    yield pb.UploadAssetRequest(data=chunk)
                if sent != st.st_size or digest.hexdigest() != sha:
                    problem.append(FarmInputError(f"{file}: changed since it was hashed; not uploaded"))

            try:
                self._stub.UploadAsset(parts(), timeout=self.transfer_timeout, metadata=self._metadata)
            except grpc.RpcError as err:
                if problem:
                    raise problem[0] from None
                raise error_from_rpc(err, f"uploading {file}", self.address) from None
            if problem:
                raise problem[0]
        finally:
            os.close(fd)

    def submit(self, job, asset_root=None, priority: int = 0, after=(), after_any=(), after_frames=None,
               max_workers: int = 0, max_units_in_flight: int = 0) -> pb.Job:
        """Sends a job: `job` is a job file (prepared: its files found with the scheduler, hashed,
        and the missing ones uploaded) or a JobSubmission from prepare(). Returns the Job, QUEUED,
        or WAITING when it waits for others; the submission's `uploaded` says how many files were
        sent.

        after         jobs it waits for to succeed (FAILED, naming the job, if one does not).
        after_any     jobs it waits for to end, whatever their end.
        after_frames  a job of frames it follows frame by frame (its frame N once that job's is merged).
        max_workers, max_units_in_flight   caps over the job file's `limits`; 0: the file's."""
        # The jobs it waits for are found first: a wrong id fails before anything is uploaded.
        dependencies = {"after": self._ids(after), "after_any": self._ids(after_any),
                        "after_frames": self._id(after_frames)
                        if isinstance(after_frames, pb.Job) or after_frames else ""}
        caps = {"max_workers": _cap(max_workers, "max_workers"),
                "max_units_in_flight": _cap(max_units_in_flight, "max_units_in_flight")}
        submission = job if isinstance(job, JobSubmission) else self.prepare(job, asset_root)
        try:
            spec = pb.JobSpec(job_json=submission.job_json, file_name=submission.file_name)
            for asset in submission.assets:
                spec.assets.add(path=asset.path, sha256=asset.sha256, size=asset.size)
        except (ValueError, TypeError) as err:
            # A proto string must be UTF-8: a path of bytes that are not cannot be sent.
            raise FarmInputError(f"{submission.job_file}: cannot be sent: {err}") from None
        if submission.uploaded is None:
            self.upload_missing(submission)
        request = pb.SubmitJobRequest(job=spec, priority=priority, **dependencies, **caps)
        return self._call("SubmitJob", request).job

    def get(self, job) -> pb.Job:
        return self._call("GetJob", pb.GetJobRequest(job_id=self._id(job)))

    def list(self, states=None, name: str | None = None, id_prefix: str | None = None,
             limit: int | None = 50) -> list:
        """Jobs, newest first: those in `states` (any of waiting, queued, running, succeeded,
        failed, cancelled), whose name matches the glob `name` (`*`, `?`; case-insensitive) and whose id
        starts with `id_prefix`; at most `limit` (None or 0: every one)."""
        return self._list(states, name, id_prefix, limit)[0]

    def _list(self, states, name, id_prefix, limit) -> tuple[list, bool]:
        wanted_states = [_job_state(s) for s in (states or ())]
        jobs: list = []
        token = ""
        while True:
            # One more than the limit, so that whether others match too can be told.
            page = _LIST_PAGE if not limit else min(limit + 1 - len(jobs), _LIST_PAGE)
            request = pb.ListJobsRequest(states=wanted_states, page_size=page, page_token=token,
                                         name=name or "", id_prefix=id_prefix or "")
            response = self._call("ListJobs", request)
            jobs.extend(response.jobs)
            if response.next_page_token == token and token:
                raise FarmError("ListJobs: the scheduler sent the same page token again")
            token = response.next_page_token
            if not token or (limit and len(jobs) > limit):
                break
        more = bool(limit) and len(jobs) > limit
        return (jobs[:limit] if limit else jobs), more

    def resolve_job_id(self, id_or_prefix: str) -> str:
        """The id of the one job whose id starts with `id_or_prefix` (a whole id is its own
        prefix). FarmInputError (NOT_FOUND) when none does, FarmInputError naming a few when
        several do. Anything but lowercase hex is passed on as it is, for the scheduler to judge."""
        text = str(id_or_prefix)
        if not text or any(c not in "0123456789abcdef" for c in text):
            return text
        if text in self._resolved:
            return self._resolved[text]
        matches, more = self._list(None, None, text, 3)
        if not matches:
            raise FarmInputError(f"no job on {self.address} whose id starts with '{text}'",
                                 grpc.StatusCode.NOT_FOUND)
        if len(matches) > 1:
            named = ", ".join(f"{j.job_id} '{j.name}'" for j in matches)
            raise FarmInputError(f"job id '{text}' is ambiguous on {self.address}: {named}"
                                 f"{' and more' if more else ''}; give more of it")
        # An id, once a prefix found it, never changes: later calls need not ask again.
        self._resolved[text] = matches[0].job_id
        if len(self._resolved) > _RESOLVED_CACHE:
            self._resolved.popitem(last=False)
        return matches[0].job_id

    def watch(self, job, timeout: float | None = None) -> Iterator:
        """The job's events (farm.v1.JobEvent), a snapshot first, until the event that puts it in
        a final state (the last one yielded). Should the stream end early (the scheduler
        restarted), the job is watched again, from a new snapshot. `timeout`: seconds for the
        whole watch (FarmTimeout past it)."""
        job_id = self._id(job)
        deadline = None if timeout is None else time.monotonic() + timeout
        for _ in range(_MAX_WATCH_RESTARTS + 1):
            left = None if deadline is None else max(deadline - time.monotonic(), 0.001)
            call = self._stub.WatchJob(pb.WatchJobRequest(job_id=job_id), timeout=left,
                                       metadata=self._metadata)
            try:
                for event in call:
                    yield event
                    if is_final(event.job.state):
                        return
            except grpc.RpcError as err:
                raise error_from_rpc(err, "WatchJob", self.address) from None
            finally:
                call.cancel()  # the stream ends after the final event; no need to wait for it
            # The stream ended without a final state: where is the job now?
            now = self.get(job_id)
            if is_final(now.state):
                yield pb.JobEvent(job=now, snapshot=pb.JobSnapshot())
                return
        raise FarmUnavailable(f"WatchJob: the scheduler at {self.address} ended the watch of {job_id} "
                              f"{_MAX_WATCH_RESTARTS + 1} times before the job finished")

    def wait(self, job, timeout: float | None = None) -> pb.Job:
        """Follows the job until it is SUCCEEDED, FAILED or CANCELLED; returns that Job."""
        last = None
        for event in self.watch(job, timeout):
            last = event.job
        return last

    def cancel(self, job) -> pb.Job:
        return self._call("CancelJob", pb.CancelJobRequest(job_id=self._id(job))).job

    def pause(self, job) -> pb.Job:
        """No more of its units handed out (those in flight finish) until resume()."""
        return self._call("PauseJob", pb.PauseJobRequest(job_id=self._id(job), paused=True)).job

    def resume(self, job) -> pb.Job:
        return self._call("PauseJob", pb.PauseJobRequest(job_id=self._id(job), paused=False)).job

    def set_priority(self, job, priority: int) -> pb.Job:
        return self._call("SetPriority", pb.SetPriorityRequest(job_id=self._id(job), priority=priority)).job

    def set_limits(self, job, max_workers: int | None = None,
                   max_units_in_flight: int | None = None) -> pb.Job:
        """The job's caps from now on: each one given replaces the job's (0 lifts it), one left
        None stays as it is; units already out finish. FarmInputError for a job that has ended."""
        request = pb.SetJobLimitsRequest(job_id=self._id(job))
        if max_workers is not None:
            request.max_workers = _cap(max_workers, "max_workers")
        if max_units_in_flight is not None:
            request.max_units_in_flight = _cap(max_units_in_flight, "max_units_in_flight")
        return self._call("SetJobLimits", request).job

    def add_dependencies(self, job, after=(), after_any=()) -> pb.Job:
        """More jobs for a job none of whose units has been handed out to wait for, as submit's
        `after` and `after_any`; it is WAITING until they end. FarmInputError: FAILED_PRECONDITION
        for a job that has started or ended, INVALID_ARGUMENT for a cycle (named)."""
        request = pb.AddDependenciesRequest(job_id=self._id(job), after=self._ids(after),
                                            after_any=self._ids(after_any))
        return self._call("AddDependencies", request).job

    def retry(self, job):
        """A FAILED or CANCELLED job's units that are not done queued again: RetryJobResponse
        (job, units_queued)."""
        return self._call("RetryJob", pb.RetryJobRequest(job_id=self._id(job)))

    def delete(self, job):
        """A final job removed with its results: DeleteJobResponse (job_id, bytes_freed)."""
        return self._call("DeleteJob", pb.DeleteJobRequest(job_id=self._id(job)))

    def log(self, job) -> list:
        """The job's whole event log (JobLogEntry), page after page."""
        job_id = self._id(job)
        entries: list = []
        after = 0
        while True:
            page = self._call("GetJobLog", pb.GetJobLogRequest(job_id=job_id, after=after))
            for entry in page.entries:
                # A page that does not move past where it began would loop for ever.
                if entry.number <= after:
                    raise FarmError("GetJobLog: the scheduler sent entries out of order")
                after = entry.number
                entries.append(entry)
            if not page.more or not page.entries:
                return entries

    def workers(self) -> list:
        """Every worker the scheduler knows (WorkerInfo)."""
        return list(self._call("ListWorkers", pb.ListWorkersRequest()).workers)

    # ---- results -------------------------------------------------------------------------------

    def fetch(self, job, out, kind="exr", frame: int | None = None) -> str:
        """Downloads a result: kind "exr", "preview", "video" or "progressive" (or a ResultKind);
        `frame` one of a job's frames (none: its first, once it has SUCCEEDED). `out` is the file to
        write, or an existing folder to write the scheduler's suggested file name into. The bytes
        go to a temporary file beside it, are checked against the size and SHA-256 the scheduler
        announces, and are renamed into place only then. Returns the path written."""
        job_id = self._id(job)
        result_kind = _RESULT_KINDS.get(kind, kind) if isinstance(kind, str) else kind
        if result_kind not in _DEFAULT_SUFFIX:
            raise FarmInputError(f"unknown result kind '{kind}' (expected exr, preview, video or progressive)")
        request = pb.GetResultRequest(job_id=job_id, kind=result_kind)
        if frame is not None:
            request.frame = frame
        out = os.fsdecode(out)
        call = self._stub.GetResult(request, timeout=self.transfer_timeout, metadata=self._metadata)
        target = temp = None
        fd = -1
        try:
            digest, written = hashlib.sha256(), 0
            expected_sha, total = "", 0
            for chunk in call:
                if fd < 0:
                    target = self._destination(out, chunk.file_name, job_id, result_kind)
                    fd, temp = _create_temp_beside(target)
                    expected_sha, total = chunk.sha256, chunk.total_size
                if chunk.offset != written:
                    raise FarmError(f"GetResult: chunk at offset {chunk.offset} where {written} was expected")
                written += len(chunk.data)
                if total and written > total:
                    raise FarmError(f"GetResult: {target}: more than the {total} bytes announced arrived")
                digest.update(chunk.data)
                _write_all(fd, chunk.data)
            if fd < 0:
                raise FarmError("GetResult: the scheduler sent no data")
            got = digest.hexdigest()
            if (total and written != total) or (expected_sha and got != expected_sha):
                raise FarmError(f"GetResult: {target} arrived damaged ({written} of {total} bytes, "
                                f"sha256 {got}, announced {expected_sha})")
            os.fsync(fd)
            os.close(fd)
            fd = -1
            os.replace(temp, target)
            temp = None
            return target
        except grpc.RpcError as err:
            raise error_from_rpc(err, "GetResult", self.address) from None
        except OSError as err:
            raise FarmInputError(f"{temp or target or out}: cannot write: {err.strerror}") from None
        finally:
            call.cancel()
            if fd >= 0:
                os.close(fd)
            if temp is not None:
                try:
                    os.unlink(temp)
                except OSError:
                    pass

    @staticmethod
    def _destination(out: str, suggested: str, job_id: str, kind: int) -> str:
        if not os.path.isdir(out):
            return out
        # Only a plain file name from the scheduler is used, never a path.
        name = suggested if suggested and suggested == posixpath.basename(suggested) \
            and suggested not in (".", "..") else ""
        return os.path.join(out, name or job_id + _DEFAULT_SUFFIX[kind])


def _create_temp_beside(target: str) -> tuple[int, str]:
    """A new file next to `target`, so that the rename into place stays on one file system; made
    with the permissions the umask gives a new file, as the C++ client's ofstream does."""
    folder = os.path.dirname(target) or "."
    os.makedirs(folder, exist_ok=True)
    base = os.path.basename(target)
    for _ in range(16):
        temp = os.path.join(folder, f".{base}.{secrets.token_hex(4)}.part")
        try:
            return os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666), temp
        except FileExistsError:
            continue
    raise OSError(errno.EEXIST, f"no free temporary name beside {target}")


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
