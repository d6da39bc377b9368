"""Solid templates of a scene: which STL files a path names, read and hulled once each.

A template path is one ``.stl`` file, a folder (its ``.stl`` files, not its
subfolders'), or a glob pattern such as ``grains/*.stl`` (the ``.stl`` files it
matches). Files are taken in sorted order of their paths, the order of
``choice = "cycle"``. Each file is read
(:func:`~regopack.plugins.shapes.solid_templates.stl.read_stl`)
and hulled (:func:`~regopack.plugins.shapes.solid_templates.hull.normalised_hull`)
once per process while its size and modification time stay the same: the
scene's validation and the run that follows share the result.
"""

from __future__ import annotations

import functools
import glob
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from regopack.base.toml import not_a_file
from regopack.plugins.shapes.polygons import TemplateError
from regopack.plugins.shapes.solid_templates.hull import ConvexSolid, normalised_hull
from regopack.plugins.shapes.solid_templates.stl import read_stl

__all__ = ["MAX_FILES", "SolidTemplates", "read_solid_templates", "template_files"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

MAX_FILES = 10_000
"""Most STL files one template path may name (each is read and hulled before the run)."""

SUFFIX = ".stl"


def _relative_note(path: Path) -> str:
    return "" if path.is_absolute() else f" (relative to the current directory {Path.cwd()})"


def template_files(path: str) -> list[Path]:
    """List the STL files that ``path`` names, sorted.

    Raises
    ------
    TemplateError
        When ``path`` names no ``.stl`` file: a missing path, an empty
        folder, a pattern that matches none, a file of another type, or more
        than :data:`MAX_FILES` files.
    """
    given = Path(path)
    if given.is_file():
        if given.suffix.lower() != SUFFIX:
            raise TemplateError(
                f"{path}: unsupported solid template file type (use .stl files, binary or "
                "ASCII; 2D outlines in .csv or .json belong to the 'template' shape)"
            )
        return [given]
    if given.is_dir():
        files = sorted(f for f in given.iterdir() if f.suffix.lower() == SUFFIX and f.is_file())
        if not files:
            raise TemplateError(f"{path}: the folder holds no .stl file{_relative_note(given)}")
    elif given.exists():  # a named pipe, a device or a socket: never opened
        raise TemplateError(f"{path}: {not_a_file(given, 'STL')}")
    elif any(c in path for c in "*?["):  # a glob pattern
        files = sorted(
            Path(f) for f in glob.glob(path) if f.lower().endswith(SUFFIX) and os.path.isfile(f)
        )
        if not files:
            raise TemplateError(f"{path}: the pattern matches no .stl file{_relative_note(given)}")
    else:
        raise TemplateError(f"{path}: no such STL file or folder{_relative_note(given)}")
    if len(files) > MAX_FILES:
        raise TemplateError(
            f"{path}: {len(files):,} STL files; at most {MAX_FILES:,} are read for one shape"
        )
    return files


@functools.lru_cache(maxsize=1024)
def _hull_of_file(resolved: str, size: int, mtime_ns: int, label: str) -> ConvexSolid:
    """Read and hull one file; the key's size and time make a changed file be read again."""
    mesh = read_stl(resolved, name=label)
    solid = normalised_hull(mesh.triangles.reshape(-1, 3), label, mesh.stored_as)
    for array in (solid.vertices, solid.face_vertices, solid.face_vertex_offsets):
        array.flags.writeable = False
    for array in (solid.normals, solid.support):
        array.flags.writeable = False
    return solid


def hull_of_file(file: Path) -> ConvexSolid:
    """Read and hull one STL file (cached while the file is unchanged)."""
    try:
        stat = file.stat()
    except OSError as err:
        raise TemplateError(f"{file}: cannot read the STL file: {err.strerror or err}") from err
    return _hull_of_file(str(file.resolve()), stat.st_size, stat.st_mtime_ns, str(file))


@dataclass(frozen=True, eq=False)
class SolidTemplates:
    """The normalised hulls of a template path, in flat arrays (template ``j`` after ``j - 1``).

    Attributes
    ----------
    names
        The file of each template, as named by the path.
    vertices
        ``(V, 3)`` vertices of all templates (volume 1, centroid at the origin).
    vertex_offsets
        ``(k + 1,)``: template ``j``'s vertices are ``vertex_offsets[j]:vertex_offsets[j + 1]``.
    face_vertices
        Vertex loops of all faces, indices local to their template.
    face_vertex_offsets
        ``(F + 1,)`` start of each face's loop.
    face_offsets
        ``(k + 1,)``: template ``j``'s faces are ``face_offsets[j]:face_offsets[j + 1]``.
    normals
        ``(F, 3)`` unit outward normals.
    support
        ``(F,)`` support values (of the volume-1 template).
    """

    names: tuple[str, ...]
    vertices: FloatArray
    vertex_offsets: IntArray
    face_vertices: IntArray
    face_vertex_offsets: IntArray
    face_offsets: IntArray
    normals: FloatArray
    support: FloatArray

    def __len__(self) -> int:
        return len(self.names)

    @classmethod
    def of(cls, names: list[str], solids: list[ConvexSolid]) -> SolidTemplates:
        """Concatenate the solids (local face indices stay local)."""

        def offsets(counts: list[int]) -> IntArray:
            out = np.zeros(len(counts) + 1, dtype=np.int64)
            np.cumsum(counts, out=out[1:])
            return out

        loops = [np.diff(s.face_vertex_offsets) for s in solids]
        return cls(
            names=tuple(names),
            vertices=np.concatenate([s.vertices for s in solids]),
            vertex_offsets=offsets([s.vertices.shape[0] for s in solids]),
            face_vertices=np.concatenate([s.face_vertices for s in solids]),
            face_vertex_offsets=offsets([int(n) for sizes in loops for n in sizes]),
            face_offsets=offsets([s.n_faces for s in solids]),
            normals=np.concatenate([s.normals for s in solids]),
            support=np.concatenate([s.support for s in solids]),
        )


def read_solid_templates(path: str) -> SolidTemplates:
    r"""Read and hull every STL file that ``path`` names (see the module docstring).

    Raises
    ------
    TemplateError
        One line naming the path or the file at fault and what is wrong.

    Examples
    --------
    >>> import os, tempfile
    >>> corners = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    >>> facets = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    >>> text = "solid t\n" + "".join(
    ...     "facet normal 0 0 0\nouter loop\n"
    ...     + "".join("vertex %g %g %g\n" % corners[i] for i in f)
    ...     + "endloop\nendfacet\n"
    ...     for f in facets
    ... ) + "endsolid t\n"
    >>> with tempfile.TemporaryDirectory() as d:
    ...     with open(os.path.join(d, "tet.stl"), "w") as f:
    ...         _ = f.write(text)
    ...     tpl = read_solid_templates(d)
    >>> len(tpl), tpl.vertices.shape, len(tpl.normals)
    (1, (4, 3), 4)
    """
    files = template_files(path)
    return SolidTemplates.of([str(f) for f in files], [hull_of_file(f) for f in files])
