"""The gate every file a job names passes before anything reads it, as the C++ side has it
(renderer/util/confined_file.{h,cpp}, renderer/util/path_confinement.cpp).

A reference is refused when
  - it is absolute (unless allow_absolute: a job's own model paths; a model travels to other
    machines as it is, where an absolute path means another file),
  - it leads out of the root: lexically (`..` past the root) or through a symbolic link,
  - what it names is not a regular file: a FIFO (opening one would wait for a writer), a device,
    a socket, a directory.
Containment is checked before existence, so probing outside the root reveals nothing. A reference
to a file that does not exist is not refused: its verdict is MISSING, and callers leave it out.

Paths are str as os.fsdecode gives them (bytes that are not UTF-8 survive as surrogates), so a
name reaches the file system exactly as the model wrote it, as in C++.

The path helpers follow std::filesystem (libstdc++) rather than os.path where the two differ:
lexically_normal keeps a trailing separator ("a/b/.." is "a/"), and weakly_canonical resolves the
existing part of a path through the file system before it drops any "..", so a ".." after a
symbolic link goes where the kernel would go.
"""
from __future__ import annotations

import dataclasses
import errno
import os
import posixpath
import stat

__all__ = ["ALLOWED", "MISSING", "ABSOLUTE", "OUTSIDE", "NOT_REGULAR", "INACCESSIBLE",
           "ConfinedFile", "confine_file", "open_confined", "lexically_normal",
           "weakly_canonical", "lies_within", "lexically_relative", "absolute"]

ALLOWED = "allowed"            # a regular file inside the root
MISSING = "missing"            # inside the root, but nothing there
ABSOLUTE = "absolute"          # an absolute reference where only relative ones are allowed
OUTSIDE = "outside"            # leads out of the root
NOT_REGULAR = "not_regular"    # a directory, FIFO, device or socket
INACCESSIBLE = "inaccessible"  # cannot be looked at (permissions, a NUL in the name, ...)

_MAX_SHOWN = 1024  # a path in a message, not a flood


def shown(text: str, limit: int = _MAX_SHOWN) -> str:
    """`text` shortened, so that a hostile model cannot flood a message or a log."""
    return text if len(text) <= limit else text[:limit] + "..."


@dataclasses.dataclass
class ConfinedFile:
    verdict: str = MISSING
    # The file under the name its referrer uses, lexically normal: where a farm lays it out.
    named: str = ""
    # Where it really is (no "..", no symbolic link): what is opened.
    resolved: str = ""
    size: int = 0
    # Why it is not allowed: reason ("'<reference>' lies outside ..."), and message, the same
    # after "<referrer>: ". Empty when allowed.
    reason: str = ""
    message: str = ""
    # The file that was checked, so that open_confined can tell it was not swapped since.
    device: int = 0
    inode: int = 0

    @property
    def allowed(self) -> bool:
        return self.verdict == ALLOWED

    @property
    def refused(self) -> bool:
        return self.verdict not in (ALLOWED, MISSING)


def _elements(path: str) -> list[str]:
    """The path's elements as std::filesystem::path iterates them: "/" for the root, the names,
    and "" for a trailing separator."""
    names = [name for name in path.split("/") if name]
    out = ["/"] if path.startswith("/") else []
    out += names
    if path.endswith("/") and names:
        out.append("")
    return out


def lexically_normal(path: str) -> str:
    """std::filesystem::path::lexically_normal on POSIX: "." and "name/.." removed, ".." at the
    root dropped, the trailing separator of a folder-like path kept."""
    if not path:
        return ""
    rooted = path.startswith("/")
    names = [name for name in path.split("/") if name]
    trailing = path.endswith("/") and bool(names)
    out: list[str] = []
    for i, name in enumerate(names):
        last = i == len(names) - 1
        if name == ".":
            trailing = trailing or last  # "a/." is "a/"
            continue
        if name == "..":
            if out and out[-1] != "..":
                out.pop()
                trailing = trailing or last  # "a/b/.." is "a/"
                continue
            if rooted:
                continue  # nothing above the root
        out.append(name)
    if not out:
        return "/" if rooted else "."
    text = ("/" if rooted else "") + "/".join(out)
    if trailing and out[-1] != "..":
        text += "/"
    return text


def lexically_relative(path: str, base: str) -> str:
    """`path` relative to `base`, both absolute and lexically normal, `path` inside `base`."""
    return posixpath.relpath(path, base)


def absolute(path: str) -> str:
    """std::filesystem::absolute: joined to the working directory, NOT normalised (a ".." after a
    symbolic link must be left to weakly_canonical)."""
    return path if path.startswith("/") else posixpath.join(os.getcwd(), path)


def _not_found(err: OSError) -> bool:
    return err.errno in (errno.ENOENT, errno.ENOTDIR)


def weakly_canonical(path: str) -> str:
    """std::filesystem::weakly_canonical for an absolute path: the longest existing prefix
    resolved (symbolic links, "..") by the file system, the rest appended and lexically
    normalised. OSError when a prefix cannot be looked at (a loop of links, permissions)."""
    try:
        os.stat(path)
        return os.path.realpath(path, strict=True)
    except OSError as err:
        if not _not_found(err):
            raise
    names = [name for name in path.split("/") if name]
    trailing = path.endswith("/") and bool(names)
    result = "/" if path.startswith("/") else ""
    rest = 0
    for i, name in enumerate(names):
        candidate = posixpath.join(result, name) if result else name
        try:
            os.stat(candidate)
        except OSError as err:
            if not _not_found(err):
                raise
            rest = i
            break
        result = candidate
    else:
        rest = len(names)
    if result:
        result = os.path.realpath(result, strict=True)
    for name in names[rest:]:
        result = posixpath.join(result, name) if result else name
    if trailing:
        result += "/"
    return lexically_normal(result)


def lies_within(resolved_root: str, resolved_path: str) -> bool:
    """True when `resolved_path` is `resolved_root` or lies below it, compared folder by folder
    (so /data/jobs2 is not inside /data/jobs). Both already resolved."""
    path = _elements(resolved_path)
    i = 0
    for element in _elements(resolved_root):
        # As in C++, an empty element (a trailing separator of the root) still moves on in path.
        if element != "":
            if i >= len(path) or path[i] != element:
                return False
        i += 1
    return True


def _kind_of(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISLNK(mode):
        return "a symbolic link to no file"
    return "not a plain file"


def confine_file(root: str, referrer: str, reference: str, allow_absolute: bool = False) -> ConfinedFile:
    """`reference`, as `referrer` writes it, resolved and confined to `root` (already resolved by
    weakly_canonical). `referrer` is a file named under the root (a model's resolved path, or a
    name this returned); a relative reference is taken from its folder. Never raises for a bad
    reference: the verdict says."""
    out = ConfinedFile()

    def refuse(verdict: str, why: str) -> ConfinedFile:
        out.verdict = verdict
        out.reason = f"'{shown(reference)}' {why}"
        out.message = f"{referrer}: {out.reason}"
        return out

    if not reference:
        return out  # names nothing: missing
    if "\0" in reference:
        return refuse(INACCESSIBLE, "contains a NUL character")
    if reference.startswith("/"):
        if not allow_absolute:
            return refuse(ABSOLUTE, "is an absolute path (a model names its files relative to its own folder)")
        out.named = lexically_normal(reference)
    else:
        out.named = lexically_normal(posixpath.join(posixpath.dirname(referrer), reference))

    # A model's reference must stay in the root as written, since a farm lays the files out by
    # the names models use: ".." past the root is refused before anything is looked up. A job's
    # path is judged by where it resolves to alone (a submission renames it relative to the root).
    outside = f"lies outside the asset root ({root})"
    named_inside = lies_within(root, out.named)
    if not named_inside and not allow_absolute:
        return refuse(OUTSIDE, outside)

    # Every symbolic link along the existing part resolved, so the test below sees where it leads.
    try:
        out.resolved = weakly_canonical(out.named)
    except OSError as err:
        return refuse(INACCESSIBLE, f"cannot be resolved: {err.strerror or err}")
    if not lies_within(root, out.resolved):
        return refuse(OUTSIDE, outside + ": a symbolic link on the way leads out" if named_inside else outside)

    # lstat, not stat: `resolved` holds no link but the last component of a dangling one, which
    # must not be followed later. Nothing is opened here, so a FIFO cannot make this wait.
    try:
        st = os.lstat(out.resolved)
    except OSError as err:
        if _not_found(err):
            out.verdict = MISSING
            out.reason = f"'{shown(reference)}': no such file"
            out.message = f"{referrer}: {out.reason}"
            return out
        return refuse(INACCESSIBLE, f"cannot be looked at: {err.strerror or err}")
    if not stat.S_ISREG(st.st_mode):
        return refuse(NOT_REGULAR, f"is {_kind_of(st.st_mode)}, not a regular file")
    out.verdict = ALLOWED
    out.size = st.st_size
    out.device = st.st_dev
    out.inode = st.st_ino
    return out


def open_confined(file: ConfinedFile) -> int:
    """A read-only descriptor of an allowed file. OSError when it is no longer the regular file
    confine_file saw (replaced by a link, a FIFO, another file) or cannot be opened."""
    if not file.allowed:
        raise OSError(errno.EPERM, file.message or "no such file")
    # O_NONBLOCK: should a FIFO have taken the file's place since it was looked at, opening it
    # returns at once instead of waiting for a writer. O_NOFOLLOW: nor is a link followed.
    flags = os.O_RDONLY | os.O_CLOEXEC | os.O_NOCTTY | os.O_NOFOLLOW | os.O_NONBLOCK
    try:
        fd = os.open(file.resolved, flags)
    except OSError as err:
        raise OSError(err.errno, f"{file.resolved}: cannot open: {err.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_dev != file.device or st.st_ino != file.inode:
            raise OSError(errno.ESTALE, f"{file.resolved}: was replaced after it was checked; not read")
        # A regular file ignores O_NONBLOCK; cleared all the same, so readers get a plain descriptor.
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd
