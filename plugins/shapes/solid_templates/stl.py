"""A strict reader of STL meshes, binary and ASCII, for untrusted files.

Only the triangles' vertices are read: the facet normals of the file are
checked for syntax (ASCII) but not used, and the attribute bytes of binary
facets are ignored. The mesh need not be closed, oriented or convex.

Which format a file is in follows from its size: a file of exactly
``84 + 50 n`` bytes, where ``n`` is the little-endian count at byte 80, is
binary (even when its header starts with ``solid``, as some writers make
it); otherwise a file that starts with ``solid`` is ASCII; anything else is a
binary file of the wrong size. Every problem is a one-line
:class:`~regopack.plugins.shapes.polygons.TemplateError` naming the file.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np
from numpy.typing import NDArray

from regopack.plugins.shapes.polygons import TemplateError

__all__ = ["ASCII_BYTES_PER_TRIANGLE", "MAX_TRIANGLES", "StlMesh", "read_stl"]

FloatArray = NDArray[np.float64]

MAX_TRIANGLES = 1_000_000
"""Most triangles an STL file may hold.

A template is only used through its convex hull, whose vertices are a small
part of a fine mesh's (a micro-CT grain of 10⁵ triangles has a hull of a few
thousand); 10⁶ triangles are 50 MB of binary STL, 72 MB of float64
coordinates and about 4 s of reading and hull computation (measured; an ASCII
file of as many triangles about 10 s), per file and process. A larger mesh
is refused rather than read: decimate it first.
"""

ASCII_BYTES_PER_TRIANGLE = 512
"""Largest mean size of an ASCII facet (a facet written with 17 digits is about 400 bytes);
an ASCII file larger than ``MAX_TRIANGLES`` such facets is refused before it is read."""

HEADER = 80
"""Bytes of a binary STL's free header, before the triangle count."""

FACET_DTYPE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
"""One binary facet: 50 bytes, little-endian."""

ASCII_CHUNK = 1 << 22
"""Bytes of ASCII text parsed at a time (bounds the memory of the token lists)."""

FACET_TOKENS = 21
"""Tokens of one ASCII facet: ``facet normal a b c outer loop`` 3 x ``vertex x y z``
``endloop endfacet``."""

_KEYWORDS = {
    0: b"facet",
    1: b"normal",
    5: b"outer",
    6: b"loop",
    7: b"vertex",
    11: b"vertex",
    15: b"vertex",
    19: b"endloop",
    20: b"endfacet",
}
"""Keyword of each keyword position of an ASCII facet's tokens."""

_NUMBERS = (2, 3, 4, 8, 9, 10, 12, 13, 14, 16, 17, 18)
"""Positions of the numbers of an ASCII facet's tokens (the normal, then 3 vertices)."""

_VERTEX_NUMBERS = list(_NUMBERS[3:])


@dataclass(frozen=True, eq=False)
class StlMesh:
    """The triangles of an STL file.

    Attributes
    ----------
    triangles
        ``(t, 3, 3)`` float64 coordinates: triangle, corner, axis.
    binary
        Whether the file was binary; its coordinates were then float32
        numbers (kept exactly), which sets how precise they are.
    """

    triangles: FloatArray
    binary: bool

    @property
    def stored_as(self) -> type[np.floating]:
        """The float type the file stored the coordinates in."""
        return np.float32 if self.binary else np.float64


def _show(token: bytes) -> str:
    """Show a token as it may appear in a one-line message (printable, at most 20 characters)."""
    text = token.decode("ascii", errors="replace")
    text = "".join(c if c.isprintable() else "?" for c in text)
    return repr(text if len(text) <= 20 else text[:17] + "...")


def read_stl(path: str | Path, name: str | None = None) -> StlMesh:
    r"""Read the triangles of a binary or ASCII STL file.

    Parameters
    ----------
    path
        The file.
    name
        How to name the file in messages (default: ``path`` as given).

    Returns
    -------
    StlMesh
        The triangles, as float64 (binary files store float32, kept exactly).

    Raises
    ------
    TemplateError
        One line naming the file: it is missing or unreadable, larger than
        :data:`MAX_TRIANGLES` triangles allow, a binary file whose size does
        not match its triangle count (truncated), an ASCII file with a syntax
        error (naming the facet and the token), or a vertex coordinate that
        is not finite.

    Examples
    --------
    >>> import os, struct, tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = os.path.join(d, "one.stl")
    ...     with open(p, "wb") as f:
    ...         _ = f.write(bytes(80) + struct.pack("<I12fH", 1, *[0.0] * 12, 0))
    ...     mesh = read_stl(p)
    >>> mesh.triangles.shape, mesh.binary
    ((1, 3, 3), True)
    """
    label = str(path) if name is None else name
    file = Path(path)
    try:
        with file.open("rb") as stream:
            size = _size(stream)
            if size > HEADER + 4 + 50 * MAX_TRIANGLES and size > ASCII_BYTES_PER_TRIANGLE * (
                MAX_TRIANGLES
            ):
                raise TemplateError(
                    f"{label}: {size:,} bytes is more than an STL of at most "
                    f"{MAX_TRIANGLES:,} triangles takes (the limit); decimate the mesh first"
                )
            head = stream.read(HEADER + 4)
            count = int.from_bytes(head[HEADER:], "little") if len(head) == HEADER + 4 else -1
            if count >= 0 and size == HEADER + 4 + 50 * count:
                triangles, binary = _read_binary(stream, count, label), True
            elif _looks_like_text(stream) and head.lstrip()[:5].lower() == b"solid":
                stream.seek(0)
                triangles, binary = _read_ascii(stream, label), False
            elif count < 0:
                raise TemplateError(
                    f"{label}: not an STL file: {size} bytes is shorter than the 84-byte header "
                    "of a binary STL, and an ASCII STL starts with 'solid'"
                )
            else:
                raise TemplateError(
                    f"{label}: truncated or damaged binary STL: its header declares "
                    f"{count:,} triangles, which take 84 + 50 x {count:,} = "
                    f"{HEADER + 4 + 50 * count:,} bytes, but the file has {size:,} bytes "
                    "(an ASCII STL would start with 'solid')"
                )
    except OSError as err:
        what = "no such STL file" if not file.exists() else "cannot read the STL file"
        raise TemplateError(f"{label}: {what}: {err.strerror or err}") from err
    bad = ~np.isfinite(triangles).all(axis=(1, 2))
    if bad.any():
        t = int(np.argmax(bad))
        raise TemplateError(
            f"{label}: triangle {t} has a coordinate that is not a finite number "
            f"({', '.join(f'{c:g}' for c in triangles[t].ravel() if not np.isfinite(c))}); "
            "every vertex coordinate must be finite"
        )
    return StlMesh(triangles=triangles, binary=binary)


_TEXT_BYTES = bytes(range(32, 127)) + b"\t\n\r\f\v" + bytes(range(128, 256))


def _looks_like_text(stream: BinaryIO) -> bool:
    """Whether the first 4 kB of the file hold no control bytes (as text, UTF-8 too, does).

    Binary facets almost always hold NUL bytes (the zero coordinates and
    normals, the attribute count), so a truncated binary file whose header
    starts with ``solid`` is still told from an ASCII one.
    """
    stream.seek(0)
    sample = stream.read(4096)
    stream.seek(0)
    return not sample.translate(None, _TEXT_BYTES)


def _size(stream: BinaryIO) -> int:
    stream.seek(0, io.SEEK_END)
    size = stream.tell()
    stream.seek(0)
    return size


def _read_binary(stream: BinaryIO, count: int, label: str) -> FloatArray:
    if count > MAX_TRIANGLES:
        raise TemplateError(
            f"{label}: {count:,} triangles; at most {MAX_TRIANGLES:,} are allowed "
            "(only the convex hull is used): decimate the mesh first"
        )
    data = stream.read(50 * count)
    facets = np.frombuffer(data, dtype=FACET_DTYPE, count=count)
    return facets["vertices"].astype(np.float64)


def _read_ascii(stream: BinaryIO, label: str) -> FloatArray:
    """Triangles of an ASCII STL: ``solid [name]``, facets, ``endsolid [name]``.

    Keywords are read in any letter case. The text is parsed in chunks that
    end after an ``endfacet``, so memory stays bounded for large files.
    """
    while not stream.readline().strip():  # 'solid' and the name, already checked
        pass
    parts: list[FloatArray] = []
    done = 0  # facets parsed so far
    rest = b""
    while chunk := stream.read(ASCII_CHUNK):
        text = rest + chunk.lower()
        cut = text.rfind(b"endfacet")
        if cut < 0:
            if len(text) > 2 * ASCII_CHUNK:
                raise TemplateError(
                    f"{label}: ASCII STL: facet {done}: no 'endfacet' in the next "
                    f"{len(text):,} bytes"
                )
            rest = text
            continue
        cut += len(b"endfacet")
        rest = text[cut:]
        parts.append(_facets(text[:cut].split(), done, label))
        done += len(parts[-1])
        if done > MAX_TRIANGLES:
            raise TemplateError(
                f"{label}: more than {MAX_TRIANGLES:,} triangles; at most {MAX_TRIANGLES:,} "
                "are allowed (only the convex hull is used): decimate the mesh first"
            )
    tail = rest.split()
    if not tail:
        raise TemplateError(f"{label}: ASCII STL: the file ends without 'endsolid'")
    if tail[0] != b"endsolid":
        _syntax_error(tail, done, label)
    return np.concatenate(parts) if parts else np.zeros((0, 3, 3))


def _facets(tokens: list[bytes], first: int, label: str) -> FloatArray:
    """``(k, 3, 3)`` vertices of ``tokens``, whole facets; facets are numbered from ``first``."""
    k, extra = divmod(len(tokens), FACET_TOKENS)
    if extra:
        _syntax_error(tokens, first, label)
    if k == 0:
        return np.zeros((0, 3, 3))
    table = np.array(tokens, dtype=object).reshape(k, FACET_TOKENS)
    for col, word in _KEYWORDS.items():
        if not np.all(table[:, col] == word):
            _syntax_error(tokens, first, label)
    try:
        np.array(table[:, list(_NUMBERS)].astype(bytes), dtype=np.float64)
        values = table[:, _VERTEX_NUMBERS].astype(bytes).astype(np.float64)
    except ValueError:
        _syntax_error(tokens, first, label)
    return np.asarray(values, dtype=np.float64).reshape(k, 3, 3)


def _syntax_error(tokens: list[bytes], first: int, label: str) -> None:
    """Raise the message of the first token that breaks the facet grammar."""
    for i, token in enumerate(tokens):
        facet, pos = divmod(i, FACET_TOKENS)
        where = f"{label}: ASCII STL: facet {first + facet}"
        word = _KEYWORDS.get(pos)
        if pos == 0 and token == b"endsolid":
            raise TemplateError(
                f"{where}: 'endsolid' before the end of the file (one solid per file is read)"
            )
        if word is not None and token != word:
            wanted = "'facet' or 'endsolid'" if pos == 0 else repr(word.decode())
            raise TemplateError(f"{where}: expected {wanted}, found {_show(token)}")
        if word is None:
            try:
                float(token)
            except ValueError:
                raise TemplateError(
                    f"{where}: {_show(token)} is not a number (a coordinate was expected)"
                ) from None
    facet = first + len(tokens) // FACET_TOKENS
    raise TemplateError(f"{label}: ASCII STL: facet {facet}: the file ends inside the facet")
