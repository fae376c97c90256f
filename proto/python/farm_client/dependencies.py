"""The files a model reads besides itself, found as `farm submit` finds them
(server/client/model_dependencies.cpp, server/client/collada_images.cpp), so that a job sent from
Python carries exactly the files the C++ client would send:

  .obj   its `mtllib` material libraries, and the maps those name (map_*, bump, disp, decal, refl)
  .gltf  the uris of its buffers and images (not data: URIs)
  .glb   the same, from its JSON chunk
  .dae   the files its <image> elements name (<init_from>, or <init_from><ref> in COLLADA 1.5)

Every reference passes confine_file first: one that is absolute, leads out of the asset root, or
names no regular file raises FarmInputError naming the model and the reference, and that file is
neither read nor sent. References to files that do not exist are left out: the loaders treat
those the same way on every machine.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import struct
import xml.parsers.expat

from .confine import (ALLOWED, MISSING, OUTSIDE, ConfinedFile, absolute, confine_file,
                      lexically_normal, open_confined, weakly_canonical, _elements)
from .errors import FarmInputError

__all__ = ["ModelDependencyScanner", "collada_image_uris", "lowercase_extension"]

_READ_BYTES = 1 << 20
_SPACE = b" \t\r\n"          # what the C++ trim() strips
_HEX = re.compile(rb"%([0-9A-Fa-f]{2})")
_MAP_KEYS = (b"bump", b"disp", b"decal", b"refl")


def lowercase_extension(path: str) -> str:
    """The extension as std::filesystem::path::extension gives it, ASCII lower case (".dae")."""
    name = path.rsplit("/", 1)[-1]
    if name in (".", ".."):
        return ""
    dot = name.rfind(".")
    if dot <= 0:  # none, or a dot file such as ".obj"
        return ""
    return name[dot:].encode("utf-8", "surrogateescape").lower().decode("utf-8", "surrogateescape")


def _percent_decode(uri: bytes) -> bytes:
    """%20 and friends in URIs (glTF, COLLADA); other bytes are kept as they are."""
    return _HEX.sub(lambda m: bytes([int(m.group(1), 16)]), uri)


# ---- What each format names ---------------------------------------------------------------------

def _obj_material_libraries(lines) -> list[bytes]:
    """OBJ: `mtllib a.mtl [b.mtl ...]`, the names as written. bytes.split() splits on the ASCII
    whitespace C++'s `>>` splits on."""
    out: list[bytes] = []
    for line in lines:
        words = line.split()
        if words and words[0] == b"mtllib":
            out += words[1:]
    return out


def _mtl_maps(lines) -> list[bytes]:
    """MTL: map_Kd, bump, disp, ... whose last word is the file ("" when there is none)."""
    out: list[bytes] = []
    for line in lines:
        words = line.split()
        if not words:
            continue
        key = words[0].lower()
        if not key.startswith(b"map_") and key not in _MAP_KEYS:
            continue
        out.append(words[-1] if len(words) > 1 else b"")
    return out


def _reject_constant(name):
    raise ValueError(f"{name} is not JSON")


def _gltf_json_uris(text: bytes) -> list[bytes]:
    """glTF: the uris of buffers and images. Nothing when the JSON does not parse: the loader
    reports the syntax error with its position."""
    try:
        if text.startswith(b"\xef\xbb\xbf"):
            text = text[3:]
        doc = json.loads(text.decode("utf-8"), parse_constant=_reject_constant)
        if not isinstance(doc, dict):
            return []
        out = []
        for key in ("buffers", "images"):
            items = doc.get(key)
            if not isinstance(items, list):
                continue
            for item in items:
                if isinstance(item, dict) and isinstance(item.get("uri"), str):
                    # A lone surrogate (\ud800) does not encode: C++'s parser refuses it too.
                    out.append(item["uri"].encode("utf-8"))
        return out
    except (ValueError, UnicodeError, RecursionError):
        return []


def collada_image_uris(read_chunks) -> list[str]:
    """The URIs the COLLADA document's images name, as written (entities decoded; not trimmed,
    not percent-decoded), in document order; [] when it is not well-formed XML.

    Both schemas: 1.4 `<image><init_from>skin.png</init_from></image>`, 1.5
    `<image><init_from><ref>skin.png</ref></init_from></image>` (also nested in create_2d and the
    like); an <init_from> with element children but no <ref> (a 1.5 <hex>) names no file, and an
    <init_from> outside <image> (a 1.4 <surface>'s) names an image by id, not a file. Elements
    are matched by their local name (an exporter may write <c:image>).

    pugixml's reading is mirrored: an element's text is its first text child, a run of character
    data up to the next tag, comment or CDATA boundary, whitespace-only runs skipped (CDATA never).
    Expat streams the file, so a large mesh is never held whole. A document that declares its own
    entities is treated as malformed: pugixml would not expand them, and expanding them here could
    be made to cost without bound.
    """
    parser = xml.parsers.expat.ParserCreate()  # no namespace processing: names stay "c:image"
    stack: list[dict] = []   # one frame per open element
    slots: list[list[str]] = []  # per <init_from>, in document (pre-)order
    images_open = 0
    text: list[str] = []
    in_cdata = False

    def flush(cdata: bool = False) -> None:
        # A run of character data ends here: it becomes a text child of the open element.
        segment = "".join(text)
        text.clear()
        if not stack:
            return
        if cdata or segment.strip(" \t\r\n"):
            frame = stack[-1]
            if frame["text"] is None:
                frame["text"] = segment

    def start(name, _attrs):
        nonlocal images_open
        flush()
        local = name.split(":", 1)[-1]
        parent = stack[-1] if stack else None
        if parent is not None:
            parent["children"] = True
        frame = {"local": local, "text": None, "children": False, "role": None}
        if local == "init_from" and images_open > 0:
            frame.update(role="init", slot=len(slots), refs=[])
            slots.append([])
        elif local == "ref" and parent is not None and parent["role"] == "init":
            frame.update(role="ref", init=parent)
        if local == "image":
            images_open += 1
        stack.append(frame)

    def end(_name):
        nonlocal images_open
        flush()
        frame = stack.pop()
        if frame["local"] == "image":
            images_open -= 1
        if frame["role"] == "ref":
            frame["init"]["refs"].append(frame["text"] or "")
        elif frame["role"] == "init":
            slots[frame["slot"]] = frame["refs"] if frame["children"] else [frame["text"] or ""]

    def characters(data):
        text.append(data)

    def cdata_start():
        nonlocal in_cdata
        flush()
        in_cdata = True

    def cdata_end():
        nonlocal in_cdata
        flush(cdata=True)
        in_cdata = False

    def boundary(*_args):
        flush(cdata=in_cdata)

    def entity_declared(*_args):
        raise ValueError("the document declares entities")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = characters
    parser.StartCdataSectionHandler = cdata_start
    parser.EndCdataSectionHandler = cdata_end
    parser.CommentHandler = boundary
    parser.ProcessingInstructionHandler = boundary
    parser.EntityDeclHandler = entity_declared
    parser.SetParamEntityParsing(xml.parsers.expat.XML_PARAM_ENTITY_PARSING_NEVER)
    try:
        for chunk in read_chunks:
            parser.Parse(chunk, False)
        parser.Parse(b"", True)
    except (xml.parsers.expat.ExpatError, ValueError, RecursionError):
        return []
    return [uri for slot in slots for uri in slot]


# ---- The scanner --------------------------------------------------------------------------------

def _named_key(file: ConfinedFile):
    return _elements(file.named)  # std::filesystem::path orders element by element


class ModelDependencyScanner:
    """Finds the dependencies of many models, reading each file once: a job names the same model
    for every copy of it, and OBJs often share a material library. What it remembers is never
    re-checked, so a scanner lives as long as one submission."""

    def __init__(self, asset_root: str, max_read_bytes: int = 2 << 30):
        self.root = weakly_canonical(absolute(asset_root))
        self.files_scanned = 0
        # A model or library read whole to find its references (glTF JSON) is bounded by this,
        # the scheduler's largest asset: a bigger one could never be sent anyway.
        self._max_read_bytes = max_read_bytes
        self._models: dict[str, list[ConfinedFile]] = {}
        self._libraries: dict[str, list[ConfinedFile]] = {}

    def dependencies(self, model: str) -> list[ConfinedFile]:
        """The existing files `model` (a resolved path inside the root) references, not itself,
        allowed by confine_file, sorted by name without duplicates. FarmInputError naming the
        model when it cannot be read or a reference is refused."""
        key = lexically_normal(model)
        if key in self._models:
            return self._models[key]
        found = {}
        for file in self._scan_model(key):
            found.setdefault(file.named, file)
        found.pop(key, None)
        files = sorted(found.values(), key=_named_key)
        # Stored only once the scan succeeded: a file that could not be read is not remembered as
        # having no dependencies.
        self._models[key] = files
        return files

    # -- reading --

    def _open(self, file: ConfinedFile, what: str) -> int:
        try:
            fd = open_confined(file)
        except OSError as err:
            raise FarmInputError(f"{file.named}: cannot read the {what}: {err.strerror or err}") from None
        self.files_scanned += 1
        return fd

    def _chunks(self, file: ConfinedFile, what: str):
        fd = self._open(file, what)
        try:
            while True:
                chunk = os.read(fd, _READ_BYTES)
                if not chunk:
                    return
                yield chunk
        except OSError as err:
            raise FarmInputError(f"{file.named}: cannot read the {what}: {err.strerror}") from None
        finally:
            os.close(fd)

    def _lines(self, file: ConfinedFile, what: str):
        """The file's lines (split on "\\n", as std::getline does), read as a stream."""
        pending = b""
        for chunk in self._chunks(file, what):
            pending += chunk
            *lines, pending = pending.split(b"\n")
            yield from lines
        if pending:
            yield pending

    def _read(self, file: ConfinedFile, what: str, limit: int) -> bytes:
        out = bytearray()
        for chunk in self._chunks(file, what):
            out += chunk
            if len(out) > limit:
                raise FarmInputError(f"{file.named}: the {what} is over {limit} bytes; not read to the end")
        return bytes(out)

    # -- references --

    def _reference(self, model: str, referrer: str, written: bytes) -> ConfinedFile | None:
        """A reference as written in `referrer`: None when it names no local file or no file that
        exists; FarmInputError when refused."""
        written = written.strip(_SPACE)
        if not written or written.startswith(b"data:"):
            return None
        if written.startswith(b"file://"):
            written = written[7:]
        if b"://" in written:
            return None  # http and the like: never fetched
        written = written.replace(b"\\", b"/")
        file = confine_file(self.root, referrer, os.fsdecode(_percent_decode(written)))
        if file.verdict == ALLOWED:
            return file
        if file.verdict == MISSING:
            return None
        # Named by the model, or by a material library the model names.
        message = file.message if referrer == model else f"{model}: {file.message}"
        if file.verdict == OUTSIDE:
            message += " (give asset_root a folder that holds both)"
        raise FarmInputError(message)

    def _scan_model(self, model: str) -> list[ConfinedFile]:
        # The model itself, as the job named it (job paths may be absolute).
        me = confine_file(self.root, model, model, allow_absolute=True)
        if me.verdict == MISSING:
            raise FarmInputError(f"{model}: cannot read the model file")
        if not me.allowed:
            raise FarmInputError(f"{model}: {me.reason}")
        ext = lowercase_extension(model)
        if ext == ".obj":
            return self._scan_obj(model, me)
        uris: list[bytes] = []
        if ext == ".gltf":
            uris = _gltf_json_uris(self._read(me, "model file", self._max_read_bytes))
        elif ext == ".glb":
            uris = self._glb_uris(me)
        elif ext == ".dae":
            # closing(): a parse that stops early still closes the file at once.
            with contextlib.closing(self._chunks(me, "model file")) as chunks:
                uris = [uri.encode("utf-8", "surrogateescape") for uri in collada_image_uris(chunks)]
        out = []
        for uri in uris:
            file = self._reference(model, model, uri)
            if file is not None:
                out.append(file)
        return out

    def _glb_uris(self, me: ConfinedFile) -> list[bytes]:
        """GLB: a 12-byte header, then chunks; the first is the JSON. Only that chunk is read."""
        fd = self._open(me, "model file")
        try:
            size = os.fstat(fd).st_size
            head = os.pread(fd, 20, 0)
            if len(head) < 20:
                return []
            length, kind = struct.unpack_from("<II", head, 12)
            if kind != 0x4E4F534A or 20 + length > size:  # "JSON"
                return []
            if length > self._max_read_bytes:
                raise FarmInputError(f"{me.named}: the glTF JSON chunk is over {self._max_read_bytes} bytes")
            text = bytearray()
            while len(text) < length:
                chunk = os.pread(fd, min(_READ_BYTES, length - len(text)), 20 + len(text))
                if not chunk:
                    return []  # shorter than it said: the loader reports it
                text += chunk
        except OSError as err:
            raise FarmInputError(f"{me.named}: cannot read the model file: {err.strerror}") from None
        finally:
            os.close(fd)
        return _gltf_json_uris(bytes(text))

    def _scan_obj(self, model: str, me: ConfinedFile) -> list[ConfinedFile]:
        out = []
        for name in _obj_material_libraries(self._lines(me, "model file")):
            library = self._reference(model, model, name)
            if library is not None:
                out.append(library)
        libraries = list(out)
        for library in libraries:
            out += self._material_library_maps(model, library)
        return out

    def _material_library_maps(self, model: str, library: ConfinedFile) -> list[ConfinedFile]:
        # Kept apart from the models: a library is read as MTL whatever its extension.
        if library.named in self._libraries:
            return self._libraries[library.named]
        maps = []
        for name in _mtl_maps(self._lines(library, "material library")):
            found = self._reference(model, library.named, name)
            if found is not None:
                maps.append(found)
        self._libraries[library.named] = maps
        return maps
