"""The errors farm_client raises: one base class, split the way `farm` splits its exit codes.

FarmInputError      the request was wrong (a bad job, a model reference that is refused, an
                    unknown job): `farm` exits 2 for these. INVALID_ARGUMENT, NOT_FOUND,
                    FAILED_PRECONDITION, ALREADY_EXISTS, OUT_OF_RANGE, RESOURCE_EXHAUSTED, and
                    local file problems (code None).
FarmUnavailable     the scheduler could not be reached (UNAVAILABLE); the message says where.
FarmAccessDenied    the scheduler refused the caller (UNAUTHENTICATED, PERMISSION_DENIED).
FarmTimeout         a deadline passed (DEADLINE_EXCEEDED).
FarmError           anything else, e.g. a download that arrived damaged.
"""
from __future__ import annotations

import grpc

__all__ = ["FarmError", "FarmInputError", "FarmUnavailable", "FarmAccessDenied", "FarmTimeout",
           "error_from_rpc"]


class FarmError(Exception):
    """A farm call or a local step failed.

    code:    the grpc.StatusCode the scheduler answered, or None for a local problem.
    message: what went wrong, in words (also str(error)).
    details: the scheduler's own message, unchanged ("" for a local problem).
    """

    def __init__(self, message: str, code: grpc.StatusCode | None = None, details: str = ""):
        super().__init__(message)
        self.message = message
        self.code = code
        self.details = details

    @property
    def code_name(self) -> str:
        """The status code's name ("NOT_FOUND"), or the class name for a local problem."""
        return self.code.name if self.code is not None else type(self).__name__


class FarmInputError(FarmError):
    """The job, a file it names, or a request was wrong; asking again will not help."""


class FarmUnavailable(FarmError):
    """The scheduler could not be reached."""


class FarmAccessDenied(FarmError):
    """The scheduler refused the caller: no token, an unknown one, or one without the role."""


class FarmTimeout(FarmError):
    """A deadline passed before the scheduler answered."""


_INPUT_CODES = {
    grpc.StatusCode.INVALID_ARGUMENT,
    grpc.StatusCode.NOT_FOUND,
    grpc.StatusCode.FAILED_PRECONDITION,
    grpc.StatusCode.ALREADY_EXISTS,
    grpc.StatusCode.OUT_OF_RANGE,
    grpc.StatusCode.RESOURCE_EXHAUSTED,  # a job over a scheduler's limit: the job is too big
}


def error_from_rpc(error: grpc.RpcError, what: str, address: str) -> FarmError:
    """The FarmError for a failed call, worded as the C++ client words it (throw_for_status)."""
    code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
    details = (error.details() if hasattr(error, "details") else None) or ""
    if code in _INPUT_CODES:
        return FarmInputError(details or f"{what}: {code.name}", code, details)
    if code == grpc.StatusCode.UNAVAILABLE:
        return FarmUnavailable(
            f"{what}: cannot reach the scheduler at {address} ({details}); is `farm scheduler` "
            "running there? (the address argument or FARM_SCHEDULER say where)", code, details)
    if code in (grpc.StatusCode.UNAUTHENTICATED, grpc.StatusCode.PERMISSION_DENIED):
        return FarmAccessDenied(
            f"{what}: the scheduler at {address} refused ({code.name}): {details}", code, details)
    if code == grpc.StatusCode.DEADLINE_EXCEEDED:
        return FarmTimeout(f"{what}: no answer from the scheduler at {address} in time ({details})",
                           code, details)
    return FarmError(f"{what}: the scheduler at {address} answered {code.name}: {details}", code,
                     details)
