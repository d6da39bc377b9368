"""The result of a run: every drawn particle, where it went, and how the run was set up.

One :class:`Packing` holds a packing of either dimension: polygons in a plane
domain or solids in a box (:attr:`Packing.dimension`, the domain's). It is
saved as an NPZ file (see ``docs/reference/packing-format.md``) with
:func:`save`, in format version 1 or 2 in 2D and 3 in 3D, and read back with
:func:`load`. Writes are atomic: a file is either the previous one or the
complete new one, never a partial write.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat as _stat
import tempfile
import zipfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Generic, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray
from typing_extensions import TypeVar

from regopack._compat import renamed_names
from regopack.base.errors import GeometryError, PackingError, PackingFileError
from regopack.geometry.domain import (
    Box,
    Cylinder,
    Domain,
    PlaneDomain,
    Rectangle,
    domain_from_dict,
)
from regopack.geometry.solids import SolidBatch

if TYPE_CHECKING:
    from regopack.geometry.population import Population
    from regopack.packing.drawing import PackingArtists
    from regopack.registry.interfaces import InsertionResult

__all__ = [
    "FILE_MAGIC",
    "FORMAT_VERSION",
    "Packing",
    "load",
    "save",
    "write_json_atomic",
]

FORMAT_VERSION = 2
"""Newest packing file format version; :func:`save` writes it for domains other than rectangles.

Version 2 adds the domain kinds ``polygon``, ``circle`` and ``periodic`` and
the optional array ``rounding`` (disks, rounded polygons). Packings of sharp
polygons in a walled rectangle are written as version 1, which they fully
fit, so that older readers keep reading them.
"""

ROUNDED_SEGMENTS = 128
"""Segments per full turn when a rounded outline is drawn as a polygon (shapely, figures)."""

FILE_MAGIC = "regopack-packing"
"""Value of ``meta["format"]`` identifying a regopack packing file."""

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_ARRAYS: dict[str, tuple[type[np.generic], int]] = {
    "radius": (np.float64, 1),
    "mineral": (np.int64, 1),
    "vertices": (np.float64, 2),
    "offsets": (np.int64, 1),
    "orientation": (np.float64, 1),
    "centre": (np.float64, 2),
    "insertion_index": (np.int64, 1),
}
"""Arrays of every packing (and of its file): dtype and number of dimensions."""

_FINITE = ("radius", "vertices", "orientation")
"""Arrays whose every value must be finite (``centre`` is NaN where not placed)."""

_ARRAYS3D: dict[str, tuple[type[np.generic], int]] = {
    "radius": (np.float64, 1),
    "mineral": (np.int64, 1),
    "vertices": (np.float64, 2),
    "offsets": (np.int64, 1),
    "face_vertices": (np.int64, 1),
    "face_vertex_offsets": (np.int64, 1),
    "face_offsets": (np.int64, 1),
    "normals": (np.float64, 2),
    "support": (np.float64, 1),
    "rotation": (np.float64, 2),
    "centre": (np.float64, 2),
    "insertion_index": (np.int64, 1),
}
"""Arrays of every 3D packing (and of its file): dtype and number of dimensions."""

_ONLY = {2: ("orientation",), 3: tuple(k for k in _ARRAYS3D if k not in _ARRAYS)}
"""Arrays of one dimension only, by that dimension: empty in a packing of the other."""

_COLUMNS = {"vertices": 3, "normals": 3, "rotation": 4, "centre": 3}
_FINITE3D = ("radius", "vertices", "normals", "support", "rotation")
PLANE_TOLERANCE = 1e-9
"""Largest distance of a face vertex from the face's plane, relative to its face's size."""
UNIT_TOLERANCE = 1e-9
"""Largest departure from length 1 of a face normal or a rotation quaternion."""

D = TypeVar("D", bound=Domain, default=Any)
"""The domain type of a :class:`Packing` (``Packing[Box]`` in 3D); a bare ``Packing`` has any."""


def _as_array(name: str, value: Any, dtype: type[np.generic]) -> NDArray[Any]:
    """Return ``value`` as an array of ``dtype``, converting only where no value can change.

    Raises
    ------
    PackingError
        When ``value`` is not a numeric array (an object array, strings, a
        ragged list) or its dtype does not convert safely to ``dtype``
        (floats for an index array, booleans, complex numbers).
    """
    try:
        arr = value if isinstance(value, np.ndarray) else np.asarray(value)
    except (TypeError, ValueError) as err:
        raise PackingError(f"array {name!r} is not a numeric array ({err})") from None
    if arr.dtype == dtype:
        return arr
    convertible = arr.dtype.kind in "iuf" and np.can_cast(arr.dtype, dtype, casting="safe")
    if not convertible and not (arr.size == 0 and arr.dtype.kind in "iuf"):
        raise PackingError(f"array {name!r} has dtype {arr.dtype}, expected {np.dtype(dtype)}")
    return arr.astype(dtype)


def _first(mask: NDArray[np.bool_]) -> int:
    return int(np.flatnonzero(mask)[0])


def _segment_reduce(
    ufunc: np.ufunc, values: FloatArray, offsets: IntArray, empty: float = 0.0
) -> FloatArray:
    n = offsets.shape[0] - 1
    out = np.full(n, empty, dtype=np.float64)
    nonempty = np.diff(offsets) > 0
    if values.shape[0] and nonempty.any():
        out[nonempty] = ufunc.reduceat(values, offsets[:-1][nonempty])
    return out


def check_particles(
    radius: FloatArray,
    mineral: IntArray,
    mineral_names: Any,
    index: IntArray,
    centre: FloatArray,
    rounding: FloatArray | None,
    stats: Any,
) -> None:
    """Check what 2D and 3D packings share, once their arrays' shapes and values are checked.

    Radii positive; minerals index the names; the order of placement numbers
    the placed particles ``0 .. n_placed - 1``; centres finite exactly where
    placed; rounding radii finite and ``>= 0``; distinct non-empty mineral
    names; numeric stats.

    Raises
    ------
    PackingError
        One line naming the array (or attribute) and what is wrong with it.
    """
    n = radius.shape[0]
    if n and radius.min() <= 0:
        j = _first(radius <= 0)
        raise PackingError(
            f"array 'radius' has the value {radius[j]} at particle {j}; radii are > 0"
        )
    n_phases = len(mineral_names)
    if n and (mineral.min() < 0 or mineral.max() >= n_phases):
        j = _first((mineral < 0) | (mineral >= n_phases))
        raise PackingError(
            f"array 'mineral' has the value {mineral[j]} at particle {j}, which is not a "
            f"phase index in [0, {n_phases}) ({n_phases} mineral names)"
        )
    if n and (index.min() < -1 or index.max() >= n):
        j = _first((index < -1) | (index >= n))
        raise PackingError(
            f"array 'insertion_index' has the value {index[j]} at particle {j}, outside [-1, {n})"
        )
    placed = index >= 0
    finite_centre = np.isfinite(centre).all(axis=1)
    if not np.array_equal(finite_centre, placed):
        j = _first(finite_centre != placed)
        state = "placed" if placed[j] else "not placed"
        raise PackingError(
            f"array 'centre' is {centre[j]} at particle {j}, which is {state} "
            f"(insertion_index {index[j]}): a centre is finite exactly where the particle "
            "is placed"
        )
    if not np.isnan(centre[~placed]).all():
        j = _first(~placed & ~np.isnan(centre).all(axis=1))
        raise PackingError(f"array 'centre' is {centre[j]} at particle {j}, not placed: not NaN")
    n_placed = int(np.count_nonzero(placed))
    uses = np.bincount(index[placed], minlength=n)
    if n_placed and uses.max() > 1:
        value = _first(uses > 1)
        a, b = np.flatnonzero(index == value)[:2]
        raise PackingError(
            f"array 'insertion_index' gives the value {value} to particles {a} and {b}; "
            "every placed particle has its own"
        )
    if n_placed and not uses[:n_placed].all():
        raise PackingError(
            f"array 'insertion_index' skips {_first(uses[:n_placed] == 0)}: the "
            f"{n_placed} placed particles are numbered 0 to {n_placed - 1}"
        )
    if rounding is not None:
        rho = rounding
        if not isinstance(rho, np.ndarray) or rho.dtype != np.float64 or rho.shape != (n,):
            what = f"shape {rho.shape}" if isinstance(rho, np.ndarray) else type(rho).__name__
            raise PackingError(
                f"array 'rounding' has {what}, expected float64 of shape ({n},) "
                "(one radius per particle)"
            )
        bad = ~(np.isfinite(rho) & (rho >= 0))
        if bad.any():
            j = _first(bad)
            raise PackingError(
                f"array 'rounding' has the value {rho[j]} at particle {j}; a rounding "
                "radius is finite and >= 0"
            )
    names = mineral_names
    if not isinstance(names, tuple) or not all(isinstance(m, str) for m in names):
        raise PackingError(f"'mineral_names' must be a list of strings, not {names!r}")
    for k, m in enumerate(names):
        if not m.strip():
            raise PackingError(f"'mineral_names' has an empty name (phase {k})")
    if len(set(names)) != len(names):
        repeated = sorted({m for m in names if names.count(m) > 1})
        raise PackingError(f"'mineral_names' repeats {', '.join(map(repr, repeated))}")
    if not isinstance(stats, dict):
        raise PackingError(f"'stats' is a {type(stats).__name__}, not a dict")
    for key, stat in stats.items():
        if not isinstance(stat, int | float | np.integer | np.floating) or isinstance(
            stat, bool | np.bool_
        ):
            raise PackingError(f"'stats' has {key!r} = {_short(stat)}, not a number")


class PlacedParticles:
    """Counts and masks of the placed particles, shared by 2D and 3D packings."""

    radius: FloatArray
    insertion_index: IntArray

    @property
    def n_particles(self) -> int:
        """Number of drawn particles (placed or not)."""
        return int(self.radius.shape[0])

    @property
    def placed(self) -> NDArray[np.bool_]:
        """Mask of the placed particles."""
        return self.insertion_index >= 0

    @property
    def n_placed(self) -> int:
        """Number of placed particles."""
        return int(np.count_nonzero(self.placed))

    def placed_in_order(self) -> IntArray:
        """Return the indices of the placed particles, in the order they were placed."""
        idx = np.flatnonzero(self.placed)
        return idx[np.argsort(self.insertion_index[idx], kind="stable")].astype(np.int64)


def check_array_types(obj: object, arrays: Mapping[str, tuple[type[np.generic], int]]) -> None:
    """Check that every array named in ``arrays`` has its dtype and number of dimensions."""
    for name, (dtype, ndim) in arrays.items():
        arr = getattr(obj, name)
        if not isinstance(arr, np.ndarray) or arr.dtype != dtype:
            got = arr.dtype if isinstance(arr, np.ndarray) else type(arr).__name__
            raise PackingError(f"array {name!r} has dtype {got}, expected {np.dtype(dtype)}")
        if arr.ndim != ndim:
            raise PackingError(f"array {name!r} has shape {arr.shape}, expected a {ndim}-D array")


def _check_offsets(name: str, offsets: IntArray, rows: int, total: int, least: int) -> None:
    """``offsets`` has ``rows + 1`` entries from 0 to ``total``, each step at least ``least``."""
    if offsets.shape[0] != rows + 1:
        raise PackingError(f"array {name!r} has {offsets.shape[0]} entries, expected {rows + 1}")
    if offsets[0] != 0:
        raise PackingError(f"array {name!r} starts at {offsets[0]}, not 0")
    if rows and (offsets.min() < 0 or offsets.max() > total):
        j = _first((offsets < 0) | (offsets > total))
        raise PackingError(
            f"array {name!r} has the value {offsets[j]} at entry {j}, outside [0, {total}]"
        )
    steps = np.diff(offsets)
    if rows and steps.min() < least:
        j = _first(steps < least)
        raise PackingError(
            f"array {name!r} gives entry {j} {steps[j]} items "
            f"({offsets[j]} to {offsets[j + 1]}); at least {least}"
        )
    if offsets[-1] != total:
        raise PackingError(f"array {name!r} ends at {offsets[-1]}, expected {total}")


def _no_ints() -> IntArray:
    return np.zeros(0, dtype=np.int64)


def _no_floats() -> FloatArray:
    return np.zeros(0, dtype=np.float64)


def _no_rows(columns: int) -> Callable[[], FloatArray]:
    return lambda: np.zeros((0, columns), dtype=np.float64)


def _solid_fields(shapes: SolidBatch) -> dict[str, Any]:
    """Return the fields of a 3D packing that its solids give (all but their rounding)."""
    return {
        "vertices": shapes.vertices,
        "offsets": shapes.offsets,
        "face_vertices": shapes.face_vertices,
        "face_vertex_offsets": shapes.face_vertex_offsets,
        "face_offsets": shapes.face_offsets,
        "normals": shapes.normals,
        "support": shapes.support,
        "rotation": shapes.rotation,
    }


@dataclass(frozen=True, eq=False)
class Packing(PlacedParticles, Generic[D]):
    """All drawn particles of a run, in draw order, and where each was placed.

    A packing of polygons in a plane domain (2D) or of solids in a box (3D):
    :attr:`dimension` is its domain's. The arrays of the other dimension are
    empty (``orientation`` in 3D; the faces, ``normals``, ``support`` and
    ``rotation`` in 2D), and they are keyword-only.

    Attributes
    ----------
    radius
        ``(n,)`` equivalent radius of each particle (area = pi r^2 in 2D,
        volume = 4/3 pi r^3 in 3D).
    mineral
        ``(n,)`` int64 index into :attr:`mineral_names`.
    mineral_names
        Phase names in scene order.
    vertices
        ``(M, d)`` vertices relative to each particle's centre: in 2D the
        counter-clockwise outlines, in 3D the solids' corners.
    offsets
        ``(n + 1,)`` int64; particle ``j``'s vertices are ``vertices[offsets[j]:offsets[j+1]]``.
    orientation
        ``(n,)`` orientation angle of each particle in radians (2D only).
    centre
        ``(n, d)`` position of each particle's centre (reference point); NaN where not placed.
    insertion_index
        ``(n,)`` int64 order of placement, ``-1`` where not placed.
    domain
        The container: a :class:`~regopack.geometry.domain.PlaneDomain` or a
        :class:`~regopack.geometry.domain.Box`.
    scene
        The fully resolved scene.
    seed
        Seed of the run.
    version
        regopack version that produced the packing.
    stats
        Counters and timings of the run.
    rounding
        ``(n,)`` radius that rounds each particle (a disk or a sphere is one
        vertex at its centre rounded by its radius), or ``None`` when every
        particle is a sharp polygon or polyhedron.
    face_vertices, face_vertex_offsets, face_offsets, normals, support, rotation
        The solids' faces and rotations (3D only), as in
        :class:`regopack.geometry.solids.SolidBatch`.
    """

    radius: FloatArray
    mineral: IntArray
    mineral_names: tuple[str, ...]
    vertices: FloatArray
    offsets: IntArray
    orientation: FloatArray = field(default_factory=_no_floats, kw_only=True)
    centre: FloatArray
    insertion_index: IntArray
    domain: D
    scene: dict[str, Any] = field(default_factory=dict)
    seed: int = 0
    version: str = "0.0.0"
    stats: dict[str, float] = field(default_factory=dict)
    rounding: FloatArray | None = None
    face_vertices: IntArray = field(default_factory=_no_ints, kw_only=True)
    face_vertex_offsets: IntArray = field(default_factory=_no_ints, kw_only=True)
    face_offsets: IntArray = field(default_factory=_no_ints, kw_only=True)
    normals: FloatArray = field(default_factory=_no_rows(3), kw_only=True)
    support: FloatArray = field(default_factory=_no_floats, kw_only=True)
    rotation: FloatArray = field(default_factory=_no_rows(4), kw_only=True)

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Restore a pickled packing; one pickled before a field existed gets its default."""
        for f in fields(self):
            if f.name not in state and f.default_factory is not MISSING:
                state[f.name] = f.default_factory()
            elif f.name not in state and f.default is not MISSING:
                state[f.name] = f.default
        self.__dict__.update(state)

    def __post_init__(self) -> None:
        """Convert the arrays to their dtypes (where no value changes) and :meth:`validate`."""
        for name, (dtype, _) in (_ARRAYS | _ARRAYS3D).items():
            object.__setattr__(self, name, _as_array(name, getattr(self, name), dtype))
        if self.rounding is not None:
            object.__setattr__(self, "rounding", _as_array("rounding", self.rounding, np.float64))
        names = self.mineral_names
        if isinstance(names, list | tuple):
            object.__setattr__(self, "mineral_names", tuple(names))
        self.validate()

    @property
    def dimension(self) -> int:
        """Spatial dimension of the packing: 2 or 3, its domain's."""
        return int(self.domain.dimension)

    def _checked_dimension(self) -> int:
        """Return the domain's dimension; for a domain that is none, the vertices' (to name it)."""
        if isinstance(self.domain, Domain):
            return int(self.domain.dimension)
        v = self.vertices
        return 3 if isinstance(v, np.ndarray) and v.ndim == 2 and v.shape[1] == 3 else 2

    def validate(self) -> None:
        """Check the packing against the packing format; raise if it breaks it.

        Every packing is checked when it is built, and :func:`load` and the
        analyses check again (the arrays can be changed in place), so that no
        compiled kernel sees an index out of range. The arrays of the other
        dimension must be empty. Checked in 2D, in this order:

        - the arrays have their dtypes (``float64``, ``int64``), dimensions and
          lengths (``n`` rows; ``offsets`` ``n + 1``; ``centre`` and
          ``vertices`` two columns);
        - ``offsets`` starts at 0, rises strictly (every particle has a
          vertex) and ends at the number of vertices;
        - ``radius``, ``vertices`` and ``orientation`` are finite, and every
          radius is positive;
        - every ``mineral`` is an index into ``mineral_names``, ``[0, n_phases)``;
        - every ``insertion_index`` lies in ``[-1, n)``, and the placed
          particles (index ``>= 0``) are numbered ``0 .. n_placed - 1``, each
          number once;
        - ``centre`` is finite exactly for the placed particles and NaN for the others;
        - ``rounding``, when present, is one finite radius ``>= 0`` per particle;
        - the mineral names are non-empty, distinct strings, and every
          value of ``stats`` is a number;
        - the domain is a :class:`~regopack.geometry.domain.PlaneDomain` with finite bounds
          and a positive area.

        In 3D (format version 3) the same, with the solids' arrays:
        ``offsets`` gives every particle a vertex; ``face_offsets`` rises
        (a sphere has no face) and ``face_vertex_offsets`` gives every face at
        least three vertices; every face vertex indexes its own particle's
        vertices; face normals and rotations are unit vectors; every face
        vertex lies in its face's plane (within 1e-9 of the face's size), every
        loop runs counter-clockwise seen from outside, every support value is
        positive; a polyhedron is sharp with at least 4 faces and a solid
        without faces is a sphere; the domain is a box of positive finite volume.

        Raises
        ------
        PackingError
            One line naming the array (or attribute) and what is wrong with it.
        """
        dimension = self._checked_dimension()
        for name in _ONLY[5 - dimension]:
            arr = getattr(self, name)
            if not isinstance(arr, np.ndarray) or arr.size:
                what = f"shape {arr.shape}" if isinstance(arr, np.ndarray) else repr(arr)
                kind = getattr(self.domain, "kind", type(self.domain).__name__)
                raise PackingError(
                    f"array {name!r} is set ({what}), but a {dimension}D packing (domain "
                    f"{kind!r}) has none: it belongs to {5 - dimension}D packings"
                )
        if dimension == 3:
            self._validate_solids()
        else:
            self._validate_outlines()

    def _check_rows(self, names: tuple[str, ...]) -> None:
        """Each array of ``names`` has one row per particle (as many as ``radius``)."""
        n = self.radius.shape[0]
        for name in names:
            rows = getattr(self, name).shape[0]
            if rows != n:
                raise PackingError(
                    f"array {name!r} has {rows} rows, expected one per particle "
                    f"({n}, the length of 'radius')"
                )

    def _check_finite(self, names: tuple[str, ...], where: Callable[[str, int], str]) -> None:
        """Every value of the arrays ``names`` is finite; ``where`` names a bad array's row."""
        for name in names:
            arr = getattr(self, name)
            finite = np.isfinite(arr)
            if not finite.all():
                row = _first(~finite.reshape(arr.shape[0], -1).all(axis=1))
                raise PackingError(
                    f"array {name!r} has the non-finite value {arr[row]} at {where(name, row)}"
                )

    def _validate_outlines(self) -> None:
        """Check a 2D packing (see :meth:`validate`)."""
        check_array_types(self, _ARRAYS)
        radius, mineral, vertices, offsets = self.radius, self.mineral, self.vertices, self.offsets
        centre, index = self.centre, self.insertion_index
        n = radius.shape[0]
        self._check_rows(("mineral", "orientation", "centre", "insertion_index"))
        for name in ("centre", "vertices"):
            shape = getattr(self, name).shape
            if shape[1] != 2:
                raise PackingError(f"array {name!r} has shape {shape}, expected ({shape[0]}, 2)")
        if offsets.shape[0] != n + 1:
            raise PackingError(
                f"array 'offsets' has {offsets.shape[0]} entries, expected n + 1 = {n + 1}"
            )
        if offsets[0] != 0:
            raise PackingError(f"array 'offsets' starts at {offsets[0]}, not 0")
        inner, last = offsets[:-1], offsets[-1]
        if n and (inner.min() < 0 or inner.max() > last):
            # checked before the differences, which wrap around in int64
            j = _first((inner < 0) | (inner > last))
            raise PackingError(
                f"array 'offsets' has the value {offsets[j]} at entry {j}, outside "
                f"[0, {last}] (its last entry)"
            )
        counts = np.diff(offsets)
        if n and counts.min() < 1:
            j = _first(counts < 1)
            raise PackingError(
                f"array 'offsets' does not rise strictly: offsets[{j}] = {offsets[j]} and "
                f"offsets[{j + 1}] = {offsets[j + 1]} give particle {j} {counts[j]} vertices"
            )
        if offsets[-1] != vertices.shape[0]:
            raise PackingError(
                f"array 'offsets' ends at {offsets[-1]}, but 'vertices' has "
                f"{vertices.shape[0]} rows"
            )
        self._check_finite(
            _FINITE,
            lambda name, row: (
                f"row {row} (particle {int(np.searchsorted(offsets, row, side='right')) - 1})"
                if name == "vertices"
                else f"particle {row}"
            ),
        )
        check_particles(
            radius, mineral, self.mineral_names, index, centre, self.rounding, self.stats
        )
        if not isinstance(self.domain, PlaneDomain):
            raise PackingError(f"'domain' is a {type(self.domain).__name__}, not a PlaneDomain")
        area = self.domain.area
        if not (np.isfinite(self.domain.bounds()).all() and math.isfinite(area) and area > 0):
            raise PackingError(f"'domain' {self.domain.to_dict()} has no positive finite area")

    def _validate_solids(self) -> None:
        """Check a 3D packing (see :meth:`validate`)."""
        check_array_types(self, _ARRAYS3D)
        for name, cols in _COLUMNS.items():
            shape = getattr(self, name).shape
            if shape[1] != cols:
                raise PackingError(
                    f"array {name!r} has shape {shape}, expected ({shape[0]}, {cols})"
                )
        n = self.radius.shape[0]
        self._check_rows(("mineral", "rotation", "centre", "insertion_index"))
        faces = self.normals.shape[0]
        if self.support.shape[0] != faces:
            raise PackingError(
                f"array 'support' has {self.support.shape[0]} entries, expected one per face "
                f"({faces}, the rows of 'normals')"
            )
        _check_offsets("offsets", self.offsets, n, self.vertices.shape[0], 1)
        _check_offsets("face_offsets", self.face_offsets, n, faces, 0)
        _check_offsets(
            "face_vertex_offsets", self.face_vertex_offsets, faces, self.face_vertices.shape[0], 3
        )
        if faces:
            owner = np.repeat(np.arange(n), np.diff(self.face_offsets))
            loop_owner = np.repeat(owner, np.diff(self.face_vertex_offsets))
            count = np.diff(self.offsets)[loop_owner]
            bad = (self.face_vertices < 0) | (self.face_vertices >= count)
            if bad.any():
                k = _first(bad)
                raise PackingError(
                    f"array 'face_vertices' has the value {self.face_vertices[k]} at entry {k} "
                    f"(particle {loop_owner[k]}, which has {count[k]} vertices)"
                )
        self._check_finite(_FINITE3D, lambda name, row: f"row {row}")
        for name in ("normals", "rotation"):
            arr = getattr(self, name)
            off = np.abs(np.sqrt(np.einsum("ij,ij->i", arr, arr)) - 1.0) > UNIT_TOLERANCE
            if off.any():
                row = _first(off)
                raise PackingError(f"array {name!r} has the non-unit row {arr[row]} at row {row}")
        self._check_faces()
        check_particles(
            self.radius,
            self.mineral,
            self.mineral_names,
            self.insertion_index,
            self.centre,
            self.rounding,
            self.stats,
        )
        if not isinstance(self.domain, Box | Cylinder):
            raise PackingError(
                f"'domain' is a {type(self.domain).__name__}, not a 3D box or cylinder"
            )
        volume = self.domain.volume
        if not (math.isfinite(volume) and volume > 0):
            raise PackingError(f"'domain' {self.domain.to_dict()} has no positive finite volume")

    def _check_faces(self) -> None:
        """Check that faces lie in their planes, run counter-clockwise, enclose the centre.

        A solid without faces must be a sphere: one vertex at its centre, rounded.
        """
        n = self.radius.shape[0]
        nfaces = np.diff(self.face_offsets)
        nverts = np.diff(self.offsets)
        rho = (
            np.zeros(n)
            if self.rounding is None
            else np.asarray(self.rounding, dtype=np.float64).reshape(-1)
        )
        if rho.shape != (n,):
            return  # check_particles names the shape of 'rounding'
        first = self.vertices[self.offsets[:-1]] if n else np.zeros((0, 3))
        sphere_ok = (nverts == 1) & (rho > 0) & np.all(first == 0.0, axis=1)
        bad = (nfaces == 0) & ~sphere_ok
        if bad.any():
            j = _first(bad)
            raise PackingError(
                f"particle {j} has no faces but is not a sphere (a single vertex (0, 0, 0) "
                "with a rounding radius > 0)"
            )
        bad = (nfaces > 0) & ((nfaces < 4) | (rho > 0))
        if bad.any():
            j = _first(bad)
            what = "rounded" if rho[j] > 0 else f"has {nfaces[j]} faces"
            raise PackingError(
                f"particle {j} is a polyhedron that {what}: polyhedra are sharp and have "
                "at least 4 faces"
            )
        faces = self.normals.shape[0]
        if not faces:
            return
        sizes = np.diff(self.face_vertex_offsets)
        face_of = np.repeat(np.arange(faces), sizes)
        owner = np.repeat(np.repeat(np.arange(n), nfaces), sizes)
        v = self.vertices[self.offsets[owner] + self.face_vertices]
        scale = np.maximum(np.sqrt(np.einsum("ij,ij->i", v, v)), np.finfo(float).tiny)
        size = np.maximum.reduceat(scale, self.face_vertex_offsets[:-1])[face_of]
        off = np.abs(np.einsum("ij,ij->i", v, self.normals[face_of]) - self.support[face_of])
        bad = off > PLANE_TOLERANCE * size
        if bad.any():
            k = _first(bad)
            raise PackingError(
                f"face {face_of[k]} (particle {owner[k]}) has a vertex {off[k]:.3g} off its "
                "plane normals . x = support"
            )
        if np.any(self.support <= 0):
            f = _first(self.support <= 0)
            raise PackingError(
                f"face {f} has the support value {self.support[f]}: every face plane lies "
                "beyond the particle's centre (support > 0)"
            )
        nxt = np.arange(v.shape[0]) + 1
        ends = self.face_vertex_offsets[1:] - 1
        nxt[ends] = self.face_vertex_offsets[:-1]
        twice_area = np.add.reduceat(np.cross(v, v[nxt]), self.face_vertex_offsets[:-1])
        turn = np.einsum("ij,ij->i", twice_area, self.normals)
        if np.any(turn <= 0):
            f = _first(turn <= 0)
            raise PackingError(
                f"face {f} is not counter-clockwise seen from outside (or has no area)"
            )

    @classmethod
    def from_parts(
        cls,
        population: Population,
        result: InsertionResult,
        domain: D,
        scene_dict: Mapping[str, Any],
        seed: int,
        stats: Mapping[str, float] | None = None,
    ) -> Packing[D]:
        """Combine a population and an insertion result into a packing of the domain's dimension.

        ``stats`` defaults to ``result.stats``.
        """
        from regopack._version import __version__

        n = len(population)
        insertion_index = np.asarray(result.insertion_index, dtype=np.int64).reshape(n)
        common: dict[str, Any] = {
            "radius": np.asarray(population.radius, dtype=np.float64),
            "mineral": np.asarray(population.mineral, dtype=np.int64),
            "mineral_names": tuple(population.mineral_names),
            "insertion_index": insertion_index,
            "domain": domain,
            "scene": dict(scene_dict),
            "seed": int(seed),
            "version": __version__,
            "stats": dict(result.stats if stats is None else stats),
            "rounding": population.shapes.rounding,
        }
        if domain.dimension == 3:
            shapes = population.shapes
            if not isinstance(shapes, SolidBatch):
                raise PackingError("a 3D packing needs a population of solids")
            return cls(
                **_solid_fields(shapes),
                centre=np.asarray(result.centre, dtype=np.float64).reshape(n, 3),
                **common,
            )
        shapes2 = cast(Any, population.shapes)
        return cls(
            vertices=np.asarray(shapes2.vertices, dtype=np.float64).reshape(-1, 2),
            offsets=np.asarray(shapes2.offsets, dtype=np.int64),
            orientation=np.asarray(shapes2.orientation, dtype=np.float64),
            centre=np.asarray(result.centre, dtype=np.float64).reshape(n, 2),
            **common,
        )

    @classmethod
    def of_spheres(
        cls,
        centre: ArrayLike,
        radius: ArrayLike,
        domain: Box | Cylinder,
        mineral: ArrayLike | None = None,
        mineral_names: Sequence[str] = ("sphere",),
    ) -> Packing[Box | Cylinder]:
        """Return a packing of spheres, every one placed, in the order given.

        For spheres that come from elsewhere (a DEM code's final state, a
        lattice, another generator), so that every analysis, the oracle and
        the exporters take them as they take a regopack packing.

        Parameters
        ----------
        centre
            ``(n, 3)`` centres.
        radius
            ``(n,)`` radii.
        domain
            The box or cylinder.
        mineral
            ``(n,)`` indices into ``mineral_names``; all 0 by default.
        mineral_names
            The phases' names.

        Examples
        --------
        >>> from regopack.geometry.domain import Box
        >>> box = Box(0.0, 4.0, 0.0, 2.0, 0.0, 2.0)
        >>> p = Packing.of_spheres([[1, 1, 1], [3, 1, 1]], [1, 1], box)
        >>> p.n_placed, p.dimension
        (2, 3)
        """
        c = np.array(centre, dtype=np.float64).reshape(-1, 3)
        n = c.shape[0]
        shapes = SolidBatch.of_spheres(np.array(radius, dtype=np.float64).reshape(n))
        kinds = (
            np.zeros(n, dtype=np.int64)
            if mineral is None
            else np.array(mineral, dtype=np.int64).reshape(n)
        )
        return Packing(
            radius=np.array(shapes.rounding),
            mineral=kinds,
            mineral_names=tuple(mineral_names),
            **_solid_fields(shapes),
            rounding=shapes.rounding,
            centre=c,
            insertion_index=np.arange(n, dtype=np.int64),
            domain=domain,
        )

    def _plane_only(self, what: str, instead: str) -> None:
        """Refuse a 3D packing in ``what``, which draws or measures polygons; name ``instead``."""
        if self.dimension != 2:
            raise PackingError(
                f"Packing.{what} works on 2D packings (polygons); for this 3D packing use {instead}"
            )

    # -- counts and masks ---------------------------------------------------

    @property
    def not_placed(self) -> IntArray:
        """Indices of the particles that were not placed."""
        return np.flatnonzero(~self.placed).astype(np.int64)

    # -- geometry ---------------------------------------------------------------

    @property
    def rounding_radius(self) -> FloatArray:
        """Rounding radius of every particle (zeros for sharp polygons and polyhedra)."""
        if self.rounding is None:
            return np.zeros(self.n_particles, dtype=np.float64)
        return np.asarray(self.rounding, dtype=np.float64)

    @property
    def rounded(self) -> bool:
        """True when some particle is rounded (a disk, a sphere, a rounded polygon)."""
        return self.rounding is not None and bool(np.any(self.rounding > 0))

    @property
    def solids(self) -> SolidBatch:
        """The particles' solids, relative to their centres (3D).

        Raises
        ------
        PackingError
            For a 2D packing, whose outlines :meth:`polygons` and :meth:`to_shapely` give.
        """
        if self.dimension != 3:
            raise PackingError(
                "Packing.solids works on 3D packings; for this 2D packing use polygons() "
                "or to_shapely()"
            )
        return SolidBatch(
            vertices=self.vertices,
            offsets=self.offsets,
            face_vertices=self.face_vertices,
            face_vertex_offsets=self.face_vertex_offsets,
            face_offsets=self.face_offsets,
            normals=self.normals,
            support=self.support,
            rotation=self.rotation,
            rounding=self.rounding,
        )

    def world_vertices(self, j: int) -> FloatArray:
        """Vertices of particle ``j`` in the packing's frame (NaN when not placed)."""
        out: FloatArray = self.vertices[self.offsets[j] : self.offsets[j + 1]] + self.centre[j]
        return out

    def _select(self, indices: ArrayLike | None) -> IntArray:
        if indices is None:
            return np.flatnonzero(self.placed).astype(np.int64)
        return np.atleast_1d(np.asarray(indices, dtype=np.int64))

    def polygon(self, j: int) -> FloatArray:
        """Absolute vertices ``(k, 2)`` of particle ``j`` (NaN if not placed); 2D."""
        self._plane_only("polygon", "world_vertices(j)")
        return self.world_vertices(j)

    def _absolute(self, idx: IntArray) -> tuple[FloatArray, IntArray]:
        """Absolute vertices of the particles ``idx`` (flat) and their counts."""
        counts = (self.offsets[idx + 1] - self.offsets[idx]).astype(np.int64)
        starts = np.repeat(self.offsets[idx], counts)
        within = np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(
            np.cumsum(counts) - counts, counts
        )
        rows = starts + within
        coords = self.vertices[rows] + np.repeat(self.centre[idx], counts, axis=0)
        return coords, counts

    def polygons(self, indices: ArrayLike | None = None) -> list[FloatArray]:
        """Absolute vertices of several particles (2D).

        Parameters
        ----------
        indices
            Particle indices; by default the placed particles in draw order
            (``np.flatnonzero(packing.placed)``).
        """
        self._plane_only("polygons", "world_vertices(j) or solids")
        idx = self._select(indices)
        if self.rounded:
            geoms = self.to_shapely(idx)
            return [np.asarray(g.exterior.coords)[:-1] for g in geoms]
        coords, counts = self._absolute(idx)
        return np.split(coords, np.cumsum(counts)[:-1]) if len(idx) else []

    def to_shapely(self, indices: ArrayLike | None = None) -> NDArray[np.object_]:
        """Shapely polygons of several particles (default: the placed ones, in draw order); 2D.

        Examples
        --------
        >>> from regopack.testing import packing_from_polygons
        >>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
        >>> float(p.to_shapely()[0].area)
        1.0
        """
        import shapely

        self._plane_only("to_shapely", "solids")
        idx = self._select(indices)
        if len(idx) == 0:
            return np.empty(0, dtype=object)
        coords, counts = self._absolute(idx)
        ring_of_vertex = np.repeat(np.arange(len(idx)), counts)
        if not self.rounded:
            rings = shapely.linearrings(coords, indices=ring_of_vertex)
            return np.asarray(shapely.polygons(rings), dtype=object)
        # rounded outlines: the core (point, segment or polygon) grown by its radius,
        # drawn with ROUNDED_SEGMENTS segments per full turn
        cores = shapely.convex_hull(shapely.multipoints(coords, indices=ring_of_vertex))
        rho = self.rounding_radius[idx]
        out = np.asarray(cores, dtype=object)
        grow = rho > 0
        out[grow] = shapely.buffer(cores[grow], rho[grow], quad_segs=ROUNDED_SEGMENTS // 4)
        return out

    def area(self) -> FloatArray:
        """Area of every particle, exactly (shoelace; plus the rounding's strips and disk); 2D."""
        self._plane_only("area", "measure() (the volume of every solid)")
        v = self.vertices
        if v.shape[0] == 0:
            return np.zeros(self.n_particles, dtype=np.float64)
        nxt = np.arange(1, v.shape[0] + 1, dtype=np.int64)
        counts = np.diff(self.offsets)
        ends = self.offsets[1:][counts > 0] - 1
        nxt[ends] = self.offsets[:-1][counts > 0]
        cross = v[:, 0] * v[nxt, 1] - v[nxt, 0] * v[:, 1]
        area = 0.5 * _segment_reduce(np.add, cross, self.offsets)
        if self.rounded:
            rho = self.rounding_radius
            edge = np.hypot(v[nxt, 0] - v[:, 0], v[nxt, 1] - v[:, 1])
            perimeter = _segment_reduce(np.add, edge, self.offsets)
            area = area + perimeter * rho + np.pi * rho * rho
        return area

    def measure(self) -> FloatArray:
        """Area (2D, :meth:`area`) or volume (3D) of every particle."""
        return self.solids.volume if self.dimension == 3 else self.area()

    @property
    def circumradius(self) -> FloatArray:
        """Largest distance from each particle's centre to its outline or surface."""
        v = self.vertices
        if self.dimension == 3:
            d = np.sqrt(np.einsum("ij,ij->i", v, v))
        else:
            d = np.hypot(v[:, 0], v[:, 1])
        out = _segment_reduce(np.maximum, d, self.offsets)
        return out + self.rounding_radius if self.rounded else out

    def __repr__(self) -> str:
        if self.dimension == 3:
            sx, sy, sz = cast(Box | Cylinder, self.domain).size
            return (
                f"<Packing: {self.n_placed} of {self.n_particles} placed in a "
                f"{sx:g} × {sy:g} × {sz:g} {self.domain.kind}, phi {self.phi:.4f}>"
            )
        return (
            f"Packing({self.n_placed}/{self.n_particles} placed, "
            f"scene={self.scene.get('name', '?')!r}, seed={self.seed})"
        )

    # -- display ------------------------------------------------------------------

    @property
    def phi(self) -> float:
        """Area (2D) or volume (3D) fraction of the placed particles over the whole domain.

        In a periodic domain every part of a particle lies in the domain once,
        in some image.
        """
        if self.dimension == 3:
            volume = self.solids.volume[self.placed].sum()
            return float(volume / self.domain.measure)
        area = float(self.area()[self.placed].sum())
        whole = self.domain.measure
        return area / whole if whole > 0 else float("nan")

    def plot(
        self,
        ax: Any = None,
        color_by: str | ArrayLike = "mineral",
        **kwargs: Any,
    ) -> PackingArtists:
        """Draw the placed particles with matplotlib (a 3D packing by a section).

        Parameters
        ----------
        ax
            Axes to draw into (default: a new figure's).
        color_by
            ``"mineral"`` (a fixed colour per mineral name, with a legend),
            ``"diameter"``, ``"radius"``, ``"order"`` (insertion order), ``"Z"``
            (contacts per particle, computed here), or one value per drawn or
            per placed particle (with a colour bar).
        **kwargs
            ``cmap``, ``edgecolor``, ``linewidth``, ``legend``, ``colorbar``
            and ``label`` (of the colour bar); for a 3D packing ``axis`` (0, 1
            or 2, the normal of the section's plane; default 1) and ``at``
            (the plane's position; default the box's centre).

        Notes
        -----
        The mineral legend sits to the right of the axes: make the figure
        with ``layout="constrained"``, or save it with ``bbox_inches="tight"``
        (as notebooks do), to keep it inside the picture. In a periodic
        domain the particles that reach past a side are drawn on both sides.
        A 3D packing is drawn by the section of its solids with an
        axis-aligned plane (:func:`regopack.packing.drawing.section_polygons`);
        :func:`regopack.packing.drawing.draw_view` renders it in 3D axes.

        Returns
        -------
        regopack.packing.drawing.PackingArtists
            The axes, the particles' ``PolyCollection``, the domain outline,
            and the legend or colour bar.
        """
        from regopack.packing.drawing import draw_packing

        return draw_packing(self, ax, color_by, **kwargs)

    def _repr_png_(self) -> bytes | None:
        from regopack.packing.drawing import packing_png

        return packing_png(self)

    def _repr_html_(self) -> str | None:
        import base64
        import html

        from regopack.packing.drawing import packing_png, summary_line

        png = base64.b64encode(packing_png(self)).decode("ascii")
        return (
            f"<div><p>{html.escape(summary_line(self))}</p>"
            f'<img src="data:image/png;base64,{png}" alt="packing coloured by mineral"/></div>'
        )


# ---------------------------------------------------------------------------
# what a file's numbers must mean: checked on loading


RADIUS_RTOL = 1e-6
"""Largest relative difference between a radius and the equivalent radius of its outline.

Every shape has the area pi r^2 of its radius to rounding error (about 1e-15);
the tolerance leaves room for a file rewritten in single precision.
"""

CONVEX_TOL = 1e-9
"""Largest clockwise turn at an outline's corner, as the sine of the angle (scale-free)."""

REACH = 1.0
"""How far a placed particle may reach beyond the domain's bounding box, in domain sizes."""

MIN_RADIUS = 1e-12
"""Smallest radius of a placed particle, as a fraction of the domain's larger side."""


class _OutlineTerms:
    """Per-vertex terms of outlines, each vertex with the next of its particle (cyclically).

    ``about`` is the cross product of a vertex and the next (twice the area of
    the triangle they make with the centre), ``ex, ey`` the edge to the next
    vertex, ``turn`` the cross product of the edge into a vertex and the edge
    out of it, ``up`` whether the edge crosses the centre's ray to +x upwards,
    ``repeated`` whether the next vertex is the same. The shifted neighbours
    are slices, fixed at each particle's last vertex, so no shifted copy of
    the coordinates is made (the arrays of a million particles are large).
    """

    def __init__(self, x: FloatArray, y: FloatArray, offsets: IntArray) -> None:
        first, last = offsets[:-1], offsets[1:] - 1
        self.x, self.y = x, y
        tmp = np.empty_like(x)
        about = np.empty_like(x)
        np.multiply(x[:-1], y[1:], out=about[:-1])
        np.multiply(x[1:], y[:-1], out=tmp[:-1])
        about[:-1] -= tmp[:-1]
        about[last] = x[last] * y[first] - x[first] * y[last]
        ex, ey = np.empty_like(x), np.empty_like(x)
        np.subtract(x[1:], x[:-1], out=ex[:-1])
        np.subtract(y[1:], y[:-1], out=ey[:-1])
        ex[last], ey[last] = x[first] - x[last], y[first] - y[last]
        turn = np.empty_like(x)
        np.multiply(ex[:-1], ey[1:], out=turn[1:])
        np.multiply(ey[:-1], ex[1:], out=tmp[1:])
        turn[1:] -= tmp[1:]
        turn[first] = ex[last] * ey[first] - ey[last] * ex[first]
        up = np.empty(x.shape[0], dtype=np.bool_)
        np.less(y[:-1], 0.0, out=up[:-1])
        up[:-1] &= y[1:] >= 0.0
        up[last] = (y[last] < 0.0) & (y[first] >= 0.0)
        repeated = ex == 0.0
        repeated &= ey == 0.0
        self.about, self.ex, self.ey, self.turn, self.up = about, ex, ey, turn, up
        self.repeated = repeated


def _half_sums(cross: FloatArray, offsets: IntArray) -> FloatArray:
    """Shoelace areas from the cross products of each particle (as :meth:`Packing.area`).

    Every particle has a vertex (:meth:`Packing.validate` checks it).
    """
    out: FloatArray = 0.5 * np.add.reduceat(cross, offsets[:-1])
    return out


MERGE_RTOL = 1e-9
"""Consecutive vertices closer than this fraction of an outline's extent are merged on loading.

regopack's own outlines of many vertices (octagons of ``m = 256``, or ``a = 1``
and a small ``psi``) hold pairs of vertices about 1e-10 of the outline apart
whose edge, by rounding, runs slightly backwards.
"""

_CHUNK = 2**16
"""Vertices checked at a time by :func:`check_file_values` (whole particles)."""


_MEASURE_WORDS = {
    2: ("outline", "area", "sqrt(area / pi)"),
    3: ("solid", "volume", "(3 volume / 4 pi)^(1/3)"),
}
"""How the radius check names a particle's measure in each dimension."""


def check_equivalent_radius(radius: FloatArray, measure: FloatArray, dimension: int) -> None:
    """Refuse a radius that is not the equivalent radius of its particle's area or volume.

    The equivalent radius is that of the disk (2D) or ball (3D) of the same
    ``measure``, within a relative :data:`RADIUS_RTOL`.

    Raises
    ------
    PackingError
        Naming the first particle whose radius disagrees.
    """
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused below
        m = np.maximum(measure, 0.0)
        eq = np.sqrt(m / np.pi) if dimension == 2 else np.cbrt(m * 3.0 / (4.0 * np.pi))
    bad = ~(np.abs(eq - radius) <= RADIUS_RTOL * radius)
    if bad.any():
        j = _first(bad)
        body, what, rule = _MEASURE_WORDS[dimension]
        raise PackingError(
            f"array 'radius' has the value {radius[j]} at particle {j}, but its {body}'s "
            f"{what} {measure[j]:.17g} has the equivalent radius {eq[j]:.17g}; a radius is "
            f"{rule} within a relative {RADIUS_RTOL:g}"
        )


def _check_outlines(
    v: FloatArray, offsets: IntArray, rho: FloatArray, base: int
) -> tuple[FloatArray, FloatArray]:
    """Check the outlines of some particles; return their areas and their reach.

    ``offsets`` start at 0; ``base`` is the index of the first particle (for
    the messages). The reach is the largest coordinate of an outline, relative
    to its centre, plus the rounding.

    Raises
    ------
    PackingError
        One line naming the particle and what is wrong with its outline.
    """
    n = offsets.shape[0] - 1
    m = _OutlineTerms(np.ascontiguousarray(v[:, 0]), np.ascontiguousarray(v[:, 1]), offsets)
    # vertices closer to the next than MERGE_RTOL of the outline's extent are one
    # vertex (exact repeats, and the pairs a rounding error puts a hair apart)
    far = np.maximum(np.abs(m.x), np.abs(m.y))
    tol = MERGE_RTOL * np.maximum.reduceat(far, offsets[:-1])
    tol_v = np.repeat(tol, np.diff(offsets))
    near = (np.abs(m.ex) <= tol_v) & (np.abs(m.ey) <= tol_v)
    near |= m.repeated
    if near.any():  # drop them (rare: whole arrays copied, or outlines of many vertices)
        owner = np.repeat(np.arange(n), np.diff(offsets))
        keep = ~near
        counts = np.bincount(owner[keep], minlength=n)
        single = counts == 0  # every vertex the same point
        keep[offsets[:-1][single]] = True
        counts[single] = 1
        woff = np.concatenate([[0], np.cumsum(counts)])
        m = _OutlineTerms(v[keep, 0], v[keep, 1], woff)
    else:
        counts, woff = np.diff(offsets), offsets
    x, y = m.x, m.y
    core = counts >= 3
    sharp_flat = ~core & ~(rho > 0)
    if sharp_flat.any():
        j = _first(sharp_flat)
        raise PackingError(
            f"array 'vertices' gives particle {base + j} {counts[j]} distinct vertices and no "
            "rounding: its outline has no area (a sharp outline is a polygon of 3 vertices or more)"
        )
    poly = None if core.all() else np.repeat(core, counts)

    def first_bad(ok: NDArray[np.bool_]) -> int | None:
        """First vertex of a polygon where ``ok`` fails, or None."""
        bad = ~ok if poly is None else poly & ~ok
        return _first(bad) if bad.any() else None

    def owner_of(k: int) -> int:
        return int(np.searchsorted(woff, k, side="right")) - 1

    # the reference point strictly inside: every edge turns counter-clockwise about it
    k = first_bad(m.about > 0)
    if k is not None:
        xn, yn = x[k] + m.ex[k], y[k] + m.ey[k]
        raise PackingError(
            f"array 'vertices' gives particle {base + owner_of(k)} an outline whose edge "
            f"({x[k]:.17g}, {y[k]:.17g}) -> ({xn:.17g}, {yn:.17g}) does not pass "
            "counter-clockwise around its centre (zero or negative area, collinear "
            "vertices, or the centre outside); outlines are counter-clockwise around a "
            "centre strictly inside"
        )
    # convex: every corner turns left (the sine of the turn, >= -CONVEX_TOL)
    k = first_bad(m.turn >= 0)
    if k is not None:  # a slight right turn (rounding) is allowed: measured where there is one
        right = np.flatnonzero(m.turn < 0)
        prev = np.where(
            np.isin(right, woff[:-1]),
            woff[1:][np.searchsorted(woff, right, side="right") - 1] - 1,
            right - 1,
        )
        px, py = m.ex[prev], m.ey[prev]
        sine = m.turn[right] / (np.hypot(px, py) * np.hypot(m.ex[right], m.ey[right]))
        ok = np.ones(m.turn.shape[0], dtype=np.bool_)
        ok[right] = sine >= -CONVEX_TOL
        k = first_bad(ok)
    if k is not None:
        raise PackingError(
            f"array 'vertices' gives particle {base + owner_of(k)} an outline that turns clockwise "
            f"at its vertex ({x[k]:.17g}, {y[k]:.17g}); outlines are convex"
        )
    # once around: the edges cross the centre's ray to +x once (the angle rises throughout)
    laps = np.add.reduceat(m.up, woff[:-1], dtype=np.int64)
    bad = core & (laps != 1)
    if bad.any():
        j = _first(bad)
        raise PackingError(
            f"array 'vertices' gives particle {base + j} an outline that winds {laps[j]} times "
            "around its centre (it crosses itself); outlines are simple polygons"
        )
    area = _half_sums(m.about, woff)
    if rho.any():  # the rounding's strips along the edges and its disk
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused later
            perimeter = np.add.reduceat(np.hypot(m.ex, m.ey), woff[:-1])
            area += perimeter * rho + np.pi * rho * rho
    far = np.abs(m.x, out=m.ex)  # the edges are no longer needed: their buffers are reused
    np.maximum(far, np.abs(m.y, out=m.ey), out=far)
    reach = np.maximum.reduceat(far, woff[:-1]) + rho
    return area, reach


def check_file_values(packing: Packing, version: int | None = None) -> None:
    """Check what a file's numbers mean, beyond :meth:`Packing.validate`, as :func:`load` does.

    In 3D, as :func:`check_solid_values`. In 2D, every outline is a simple
    convex polygon, counter-clockwise around its reference point (strictly
    inside; edges of zero length are allowed), or,
    when rounded, a point or a segment; every radius is the equivalent radius
    of its outline's area within :data:`RADIUS_RTOL`; every placed particle
    lies within :data:`REACH` domain sizes of the domain's bounding box and its
    radius is at least :data:`MIN_RADIUS` of it; in a periodic domain every
    centre lies in the cell; and a version-1 file holds a walled rectangle of
    sharp polygons. All tolerances are relative, so a packing scaled by any
    factor passes or fails alike. Vectorised: about a tenth of a second per
    million particles.

    Raises
    ------
    PackingError
        One line naming the particle, the array and the value, and what is allowed.
    """
    if packing.dimension == 3:
        check_solid_values(packing)
        return
    with np.errstate(all="ignore"):  # outlines of 1e200 overflow: refused, without warnings
        _check_values(packing, version)


def check_solid_values(packing: Packing[Box | Cylinder]) -> None:
    """Check what a 3D file's numbers mean, beyond :meth:`Packing.validate`.

    Every radius is the volume-equivalent radius of its solid within
    :data:`RADIUS_RTOL` (the volume as the cones from the centre over the
    faces, plus a sphere's; a flat or empty solid has none); every placed
    particle lies within :data:`REACH` box sizes of the box (a cylinder: of its
    bounding box, and of its side wall) and its radius is at least
    :data:`MIN_RADIUS` of the box's largest side; in a periodic box
    every centre lies in the cell. Relative tolerances only; vectorised.

    Raises
    ------
    PackingError
        One line naming the particle, the array and the value, and what is allowed.
    """
    n = packing.n_particles
    if n == 0:
        return
    rho = (
        np.zeros(n) if packing.rounding is None else np.asarray(packing.rounding, dtype=np.float64)
    )
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused below
        volume = (4.0 / 3.0) * np.pi * rho**3
    faces = packing.normals.shape[0]
    if faces:
        sizes = np.diff(packing.face_vertex_offsets)
        owner = np.repeat(np.repeat(np.arange(n), np.diff(packing.face_offsets)), sizes)
        v = packing.vertices[packing.offsets[owner] + packing.face_vertices]
        nxt = np.arange(v.shape[0]) + 1
        nxt[packing.face_vertex_offsets[1:] - 1] = packing.face_vertex_offsets[:-1]
        twice_area = np.add.reduceat(np.cross(v, v[nxt]), packing.face_vertex_offsets[:-1])
        cone = np.einsum("ij,ij->i", twice_area, packing.normals) * packing.support / 6.0
        face_owner = np.repeat(np.arange(n), np.diff(packing.face_offsets))
        volume = volume + np.bincount(face_owner, weights=cone, minlength=n)
    check_equivalent_radius(packing.radius, volume, 3)
    placed = packing.placed
    b = packing.domain.bounds()  # a cylinder's bounding box
    low, high = b[0::2], b[1::2]
    size = float(np.max(high - low))
    box = "box" if isinstance(packing.domain, Box) else packing.domain.kind
    small = placed & (packing.radius < MIN_RADIUS * size)
    if small.any():
        j = _first(small)
        raise PackingError(
            f"array 'radius' has the value {packing.radius[j]} at placed particle {j}, less "
            f"than {MIN_RADIUS:g} of the {box}'s largest side {size:g}"
        )
    offsets = packing.offsets
    far = np.abs(packing.vertices[:, 0])
    for axis in (1, 2):
        far = np.maximum(far, np.abs(packing.vertices[:, axis]))
    reach = np.maximum.reduceat(far, offsets[:-1]) + rho
    centre = np.where(placed[:, None], packing.centre, 0.5 * (low + high))
    bad = placed & ~np.all(
        (centre - reach[:, None] >= low - REACH * size)
        & (centre + reach[:, None] <= high + REACH * size),
        axis=1,
    )
    if bad.any():
        j = _first(bad)
        raise PackingError(
            f"array 'centre' places particle {j} at {packing.centre[j]} (reaching "
            f"{reach[j]:.6g} from it), more than the {box}'s largest side ({size:g}) beyond "
            f"its bounds {b.tolist()}"
        )
    dom = packing.domain
    if isinstance(dom, Cylinder):
        # beyond the side wall too, by the same measure
        radial = np.hypot(centre[:, 0] - dom.cx, centre[:, 1] - dom.cy) - reach
        bad = placed & (radial > dom.radius + REACH * size)
        if bad.any():
            j = _first(bad)
            raise PackingError(
                f"array 'centre' places particle {j} at {packing.centre[j]} (reaching "
                f"{reach[j]:.6g} from it), more than the cylinder's largest side ({size:g}) "
                f"beyond its side wall (axis ({dom.cx:g}, {dom.cy:g}), radius {dom.radius:g})"
            )
    if packing.domain.periodic:
        c = packing.centre
        top = np.maximum(high, low + (high - low))
        bad = placed & ~np.all((c >= low) & (c < top), axis=1)
        if bad.any():
            j = _first(bad)
            raise PackingError(
                f"array 'centre' places particle {j} at {c[j]}, outside the periodic cell "
                f"{b.tolist()} (each centre lies in [min, max) along every axis)"
            )


def _check_values(packing: Packing, version: int | None) -> None:
    dom = packing.domain
    if version == 1 and (type(dom) is not Rectangle or packing.rounded):
        what = f"a {dom.kind} domain" if type(dom) is not Rectangle else "rounded particles"
        raise PackingError(
            f"meta 'format_version' is 1 with {what}; version 1 holds sharp polygons in a "
            "walled rectangle only (domain kinds 'periodic', 'polygon', 'circle' and the "
            "array 'rounding' came with version 2)"
        )
    n = packing.n_particles
    if n == 0:
        return
    v, offsets = packing.vertices, packing.offsets
    rho = packing.rounding_radius
    # in runs of about _CHUNK vertices, whole particles each, so that the
    # temporaries stay in the processor's cache
    starts = np.searchsorted(offsets, np.arange(0, v.shape[0], _CHUNK))
    bounds = np.unique(np.concatenate([starts, [0, n]]))
    area = np.empty(n)
    reach = np.empty(n)
    for p0, p1 in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True):
        a0, a1 = int(offsets[p0]), int(offsets[p1])
        area[p0:p1], reach[p0:p1] = _check_outlines(
            v[a0:a1], offsets[p0 : p1 + 1] - a0, rho[p0:p1], p0
        )
    check_equivalent_radius(packing.radius, area, 2)
    placed = packing.placed
    b = dom.bounds()
    size = max(float(b[1] - b[0]), float(b[3] - b[2]))
    small = placed & (packing.radius < MIN_RADIUS * size)
    if small.any():
        j = _first(small)
        raise PackingError(
            f"array 'radius' has the value {packing.radius[j]} at placed particle {j}, less "
            f"than {MIN_RADIUS:g} of the domain's larger side {size:g}"
        )
    centre = np.where(placed[:, None], packing.centre, 0.5 * (b[[0, 2]] + b[[1, 3]]))
    lo = b[[0, 2]] - REACH * size
    hi = b[[1, 3]] + REACH * size
    bad = placed & ~np.all(
        (centre - reach[:, None] >= lo) & (centre + reach[:, None] <= hi), axis=1
    )
    if bad.any():
        j = _first(bad)
        raise PackingError(
            f"array 'centre' places particle {j} at {packing.centre[j]} (reaching "
            f"{reach[j]:.6g} from it), more than the domain's larger side ({size:g}) beyond "
            f"the domain's bounds {b.tolist()}"
        )
    if dom.periodic:
        c = packing.centre
        low = b[[0, 2]]
        high = np.maximum(b[[1, 3]], low + (b[[1, 3]] - low))  # as PeriodicRectangle.wrap
        bad = placed & ~np.all((c >= low) & (c < high), axis=1)
        if bad.any():
            j = _first(bad)
            raise PackingError(
                f"array 'centre' places particle {j} at {c[j]}, outside the periodic cell "
                f"[{b[0]:g}, {b[1]:g}) x [{b[2]:g}, {b[3]:g}); a periodic centre lies in the cell"
            )


SIZE_RTOL = 1e-9
"""Relative tolerance of the radii against the size range of a file's scene."""

RUN_SECTIONS = ("size", "domain")
"""Sections every run writes to its scene: a file's scene with all of them is checked.

A scene with fewer (a name only, or a name and a domain, as packings built in
Python carry) is not a run's scene and is left as it is.
"""


def _scene_size_range(path: Path, size: Any) -> tuple[float, float] | None:
    """Return the range ``(d_min / 2, d_max / 2)`` given by the numbers of a scene's ``size``.

    Read from the numbers alone: no plugin is resolved and no file the scene
    names is read, so a packing loads wherever it was made and whatever it
    names. None when ``d_min`` or ``d_max`` is absent, zero, or above the
    other (a size plugin of other parameters). A given ``d_min`` or ``d_max``
    that is not a number, not finite or negative is refused: the analyses
    take their margins from it.
    """
    if not isinstance(size, dict):
        return None
    values: dict[str, float] = {}
    for key in ("d_min", "d_max"):
        if key not in size:
            continue
        value = size[key]
        shown = json.dumps(value, default=str)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise _invalid(
                path, f"meta 'scene': size.{key} = {shown}: Input should be a valid number"
            )
        if not math.isfinite(value):
            raise _invalid(
                path, f"meta 'scene': size.{key} = {shown}: Input should be a finite number"
            )
        if value < 0:
            raise _invalid(
                path, f"meta 'scene': size.{key} = {shown}: Input should be greater than 0"
            )
        values[key] = float(value)
    if len(values) < 2 or not 0 < values["d_min"] <= values["d_max"]:
        return None
    return values["d_min"] / 2, values["d_max"] / 2


def check_file_scene(path: Path, packing: Packing) -> None:
    """Check the scene a packing file holds against the file, without resolving a plugin.

    A run's scene (one with every section of :data:`RUN_SECTIONS`) is
    validated by :func:`regopack.scenes.model.scene_from_dict` (its structure
    and the domain's values); its domain kind and (when it gives them) its
    phase names must be the file's, and every radius must lie in the size
    range ``[d_min / 2, d_max / 2]`` (within :data:`SIZE_RTOL`) that the
    plain numbers ``size.d_min`` and ``size.d_max`` give, since the analyses
    take their margins from it. The plugins the scene names are not resolved
    and no file it names is read (a sieve table moved, a FIFO, a plugin not
    installed here): loading reads the packing file only. A scene without
    every run section (a name only, as packings built in Python carry) and
    the scene of a 2D section of a 3D packing (with a ``slice`` table, see
    the ``slice`` exporter) are left as they are; the analyses then take
    their margins from the stats or the radii. A stat ``interior_margin``,
    which the analyses prefer to the scene's ``d_max``, must be finite and
    ``>= 0``.

    Raises
    ------
    PackingFileError
        One line naming the file, the field, the value and what is allowed.
    """
    margin = packing.stats.get("interior_margin")
    if margin is not None and not (math.isfinite(margin) and margin >= 0):
        raise _invalid(
            path, f"meta 'stats' has 'interior_margin' = {margin!r}; it is finite and >= 0"
        )
    scene = packing.scene
    if "slice" in scene or not all(key in scene for key in RUN_SECTIONS):
        return
    from regopack.base.errors import ConfigError
    from regopack.scenes.model import scene_from_dict

    try:
        structural = scene_from_dict(scene, source="meta 'scene'")
    except ConfigError as err:
        raise _invalid(
            path, f"{err} (the scene of a packing file is checked as 'regopack run' checks one)"
        ) from None
    kind = structural.domain.kind
    if kind != packing.domain.kind:
        raise _invalid(
            path,
            f"meta 'scene' has domain.kind = {kind!r}, but meta 'domain' is a "
            f"{packing.domain.kind!r}; they are the same",
        )
    if "phases" in scene:
        phases = tuple(phase.name for phase in structural.phases)
        if phases != packing.mineral_names:
            raise _invalid(
                path,
                f"meta 'scene' names the phases {list(phases)}, but meta 'mineral_names' is "
                f"{list(packing.mineral_names)}; they are the same, in the same order",
            )
    limits = _scene_size_range(path, scene.get("size"))
    if limits is None:
        return
    r_min, r_max = limits
    radius = packing.radius
    bad = ~((radius >= r_min * (1 - SIZE_RTOL)) & (radius <= r_max * (1 + SIZE_RTOL)))
    if bad.any():
        j = _first(bad)
        raise _invalid(
            path,
            f"array 'radius' has the value {radius[j]} at particle {j}, outside the range "
            f"[{r_min:.17g}, {r_max:.17g}] of meta 'scene' size (d_min / 2 to d_max / 2)",
        )


# ---------------------------------------------------------------------------
# files


def _json_default(obj: object) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot write a {type(obj).__name__} as JSON")


def _finite_or_none(obj: Any) -> Any:
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {str(k): _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite_or_none(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _finite_or_none(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


_CLEANED: set[tuple[str, str]] = set()
"""Files whose stale temporaries this process has already looked for."""


def _remove_stale_temporaries(directory: Path, name: str) -> None:
    """Remove ``.<name>.<random>.tmp`` files that a killed write left in ``directory``.

    Done once per file and process, so that rewriting a file often (a sweep's
    ``results.csv``) does not list its directory every time.
    """
    key = (os.path.abspath(directory), name)
    if key in _CLEANED:
        return
    _CLEANED.add(key)
    pattern = re.compile(re.escape(f".{name}.") + r"[A-Za-z0-9_]{8}\.tmp")
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return
    for entry in entries:
        if pattern.fullmatch(entry.name) and entry.is_file(follow_symlinks=False):
            try:
                os.unlink(entry.path)
            except OSError:
                pass


@contextmanager
def _atomic_file(path: Path) -> Iterator[IO[bytes]]:
    """Open a temporary file beside ``path``; move it over ``path`` on success.

    Temporaries of an earlier write of ``path`` that was killed (SIGKILL, a
    power cut) are removed first.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    _remove_stale_temporaries(directory, path.name)
    fd, tmp_name = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp creates the file readable by its owner only; give it the usual mode
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_name, 0o666 & ~umask)
        os.replace(tmp_name, path)
    except BaseException:
        try:
            os.unlink(tmp_name)
        except FileNotFoundError:
            pass
        raise
    from regopack.base.outdir import fsync_directory

    fsync_directory(directory)


def write_json_atomic(path: str | Path, obj: Any) -> None:
    """Write ``obj`` as indented JSON, atomically.

    Non-finite floats (NaN, infinity) are written as ``null`` so the file is
    standard JSON; numpy scalars and arrays are converted to plain values.
    """
    text = json.dumps(_finite_or_none(obj), indent=2, default=_json_default, allow_nan=False)
    with _atomic_file(Path(path)) as fh:
        fh.write((text + "\n").encode("utf-8"))


def _meta(packing: Packing) -> dict[str, Any]:
    d = packing.domain
    return {
        "format": FILE_MAGIC,
        "format_version": 1 if type(d) is Rectangle and not packing.rounded else FORMAT_VERSION,
        "version": packing.version,
        "mineral_names": list(packing.mineral_names),
        "domain": d.to_dict(),
        "scene": packing.scene,
        "seed": packing.seed,
        "stats": packing.stats,
    }


def _meta3d(packing: Packing) -> dict[str, Any]:
    return {
        "format": FILE_MAGIC,
        "format_version": FORMAT_VERSION_3D,
        "dimension": 3,
        "version": packing.version,
        "mineral_names": list(packing.mineral_names),
        "domain": packing.domain.to_dict(),
        "scene": packing.scene,
        "seed": packing.seed,
        "stats": packing.stats,
    }


def save(packing: Packing, path: str | Path) -> None:
    """Write ``packing`` to ``path`` (NPZ) in the format of its dimension, atomically.

    A 2D packing is written in format version 1 or 2, a 3D one in version 3.
    The file is written under a temporary name in the same directory, flushed
    to disk, then renamed over ``path``; an interrupted save leaves any
    previous file untouched. The name is used as given (no ``.npz`` is added).

    Raises
    ------
    PackingError
        When the packing breaks the packing format (its arrays may have been
        changed in place since it was built), or is no packing; nothing is
        written then.
    """
    if not isinstance(packing, Packing):
        raise PackingError(f"{type(packing).__name__} is not a packing")
    packing.validate()
    arrays: dict[str, Any]
    if packing.dimension == 3:
        arrays = {name: getattr(packing, name) for name in _ARRAYS3D}
        if packing.rounding is not None:
            arrays["rounding"] = packing.rounding
        meta = json.dumps(_meta3d(packing), default=_json_default)
    else:
        arrays = {name: getattr(packing, name) for name in _ARRAYS}
        if packing.rounded:
            arrays["rounding"] = packing.rounding_radius
        meta = json.dumps(_meta(packing), default=_json_default)
    savez: Callable[..., None] = np.savez
    with _atomic_file(Path(path)) as fh:
        savez(fh, meta=np.array(meta), **arrays)


def _bad(path: Path, why: str) -> PackingFileError:
    """Error for a file that is not a regopack packing file at all."""
    return PackingFileError(f"{path}: not a regopack packing file ({why})")


def _invalid(path: Path, why: str) -> PackingFileError:
    """Error for a regopack packing file that breaks the format."""
    return PackingFileError(f"{path}: invalid packing file: {' '.join(why.split())}")


KNOWN_FORMAT_VERSIONS = (1, 2)
"""Packing format versions of 2D packing files, which :func:`load` reads."""

FORMAT_VERSION_3D = 3
"""Format version of 3D packing files."""


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _read_meta(path: Path, npz: PackingArchive) -> dict[str, Any]:
    """Read the ``meta`` entry and check that it names a packing of a known version."""
    if "meta" not in npz.files:
        raise _bad(path, "no 'meta' entry")
    try:
        shape, dtype = npz.header("meta")
    except PackingFileError as err:
        raise _bad(path, f"unreadable 'meta' entry: {str(err).split(': ', 1)[-1]}") from None
    if dtype.kind != "U" or shape != ():
        raise _bad(path, f"'meta' is a {dtype} array of shape {shape}, not a string")
    if dtype.itemsize // 4 > MAX_META_CHARS:
        raise _invalid(
            path,
            f"meta is {dtype.itemsize // 4} characters long; at most {MAX_META_CHARS} are "
            "allowed (a resolved scene and its stats take a few thousand)",
        )
    text = str(npz["meta"])
    depth = _json_depth(text)
    if depth > MAX_META_DEPTH:
        raise _invalid(
            path, f"meta nests objects and lists {depth} deep; at most {MAX_META_DEPTH} is allowed"
        )
    try:
        meta = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as err:
        raise _bad(path, "unreadable 'meta' entry") from err
    if not isinstance(meta, dict) or meta.get("format") != FILE_MAGIC:
        raise _bad(path, "'meta' does not identify a regopack packing")
    version = meta.get("format_version")
    if version is None:
        raise _invalid(path, "meta 'format_version' is missing")
    if not _is_int(version):
        raise _invalid(
            path,
            f"meta 'format_version' is {_short(version)}, a {type(version).__name__}, "
            "not an integer",
        )
    if version > FORMAT_VERSION_3D:
        raise PackingFileError(
            f"{path}: written in packing format version {version}, but this regopack "
            f"reads versions up to {FORMAT_VERSION_3D}; upgrade regopack"
        )
    if version not in (*KNOWN_FORMAT_VERSIONS, FORMAT_VERSION_3D):
        raise _invalid(
            path,
            f"meta 'format_version' is {version}, not a known version "
            f"({', '.join(map(str, (*KNOWN_FORMAT_VERSIONS, FORMAT_VERSION_3D)))})",
        )
    return meta


def _read_array(
    path: Path,
    npz: PackingArchive,
    name: str,
    dtype: type[np.generic],
    ndim: int,
    rows: int | None = None,
) -> Any:
    """Read one array, check its dimensions and convert it to ``dtype`` (where no value changes).

    Its header is checked first (:meth:`PackingArchive.read`): at most ``rows``
    rows, when given, and the declared size of its member.
    """
    try:
        arr = npz.read(name, ndim, rows)
    except ValueError as err:  # e.g. data that ends before its header's shape
        raise _invalid(path, f"array {name!r} cannot be read ({err})") from err
    try:
        return _as_array(name, arr, dtype)
    except PackingError as err:
        raise _invalid(path, str(err)) from err


def row_limits(n: int, arrays: Mapping[str, tuple[type[np.generic], int]]) -> dict[str, int]:
    """Most rows each array of a file may declare, given its ``n`` particles.

    One row per particle (``offsets``, ``face_offsets``: ``n + 1``); vertices
    and faces at most :data:`MAX_VERTICES_PER_PARTICLE` per particle on average
    (face loops six times that, the vertex uses of a polyhedron's faces).
    """
    many = n * MAX_VERTICES_PER_PARTICLE
    per_item = {
        "offsets": n + 1,
        "face_offsets": n + 1,
        "vertices": many,
        "normals": many,
        "support": many,
        "face_vertex_offsets": many + 1,
        "face_vertices": 6 * many,
    }
    return {name: per_item.get(name, n) for name in (*arrays, "rounding")}


def _read_domain(path: Path, data: Any, dimension: int) -> Domain:
    """Rebuild the ``domain`` record of a packing of ``dimension`` (2D: rectangle by default)."""
    if not isinstance(data, dict):
        raise _invalid(path, f"meta 'domain' is {_short(data)}, not an object")
    try:
        return domain_from_dict(data, dimension)
    except (KeyError, TypeError, ValueError, GeometryError) as err:
        why = f"no {err}" if isinstance(err, KeyError) else str(err)
        kind = _short(data.get("kind", "rectangle" if dimension == 2 else None))
        raise _invalid(path, f"meta 'domain' (kind {kind}): {why}") from err


def _read_meta_keys(
    path: Path,
    meta: Mapping[str, Any],
    dimension: int = 2,
) -> dict[str, Any]:
    """Return the keyword arguments of :class:`Packing` that ``meta`` holds, types checked.

    The ``domain`` record is read as a domain of ``dimension``.
    """
    for key in ("domain", "mineral_names"):
        if key not in meta:
            raise _invalid(path, f"meta {key!r} is missing")
    names = meta["mineral_names"]
    if not isinstance(names, list) or not all(isinstance(m, str) for m in names):
        raise _invalid(path, f"meta 'mineral_names' is {_short(names)}, not a list of strings")
    scene = meta.get("scene") or {}
    if not isinstance(scene, dict):
        raise _invalid(path, f"meta 'scene' is {_short(scene)}, not an object")
    seed = meta.get("seed", 0)
    if not _is_int(seed):
        raise _invalid(path, f"meta 'seed' is {_short(seed)}, not an integer")
    version = meta.get("version", "unknown")
    if not isinstance(version, str):
        raise _invalid(path, f"meta 'version' is {_short(version)}, not a string")
    stats = meta.get("stats") or {}
    if not isinstance(stats, dict):
        raise _invalid(path, f"meta 'stats' is {_short(stats)}, not an object")
    for key, value in stats.items():
        if value is not None and not _is_number(value):
            raise _invalid(path, f"meta 'stats' has {key!r} = {_short(value)}, not a number")
    return {
        "mineral_names": tuple(names),
        "domain": _read_domain(path, meta["domain"], dimension),
        "scene": scene,
        "seed": seed,
        "version": version,
        "stats": {str(k): (math.nan if v is None else v) for k, v in stats.items()},
    }


def open_packing_file(path: str | Path) -> Path:
    """Check that ``path`` names a regular file; return it as a path.

    Only a regular file (or a link to one) is accepted, decided by
    :func:`os.stat` before the file is opened: a directory, a FIFO (which
    would block until a writer comes) or a device (``/dev/zero`` reads without
    end) is refused.

    Raises
    ------
    PackingFileError
        When it is missing or not a regular file.
    """
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise PackingFileError(f"{path}: no such file") from None
    except OSError as err:
        raise PackingFileError(f"{path}: cannot be read ({err.strerror})") from None
    if not _stat.S_ISREG(st.st_mode):
        kind = next(
            (
                what
                for test, what in (
                    (_stat.S_ISDIR, "a directory"),
                    (_stat.S_ISFIFO, "a FIFO (named pipe)"),
                    (_stat.S_ISCHR, "a character device"),
                    (_stat.S_ISBLK, "a block device"),
                    (_stat.S_ISSOCK, "a socket"),
                )
                if test(st.st_mode)
            ),
            "something other than a regular file",
        )
        raise PackingFileError(f"{path}: is {kind}, not a packing file (a regular file)")
    return path


# ---------------------------------------------------------------------------
# the archive: members read only after their declared sizes are checked

MAX_META_CHARS = 4 * 2**20
"""Longest ``meta`` document read, in characters (a resolved scene and stats take a few KiB)."""

MAX_META_DEPTH = 32
"""Deepest nesting of objects and lists in ``meta`` (a resolved scene nests about 6 deep)."""

MAX_EXPANSION = 100
"""Largest ratio of a member's declared size to its compressed size, above 1 MiB.

regopack stores the members uncompressed (ratio 1); numbers compressed by
``numpy.savez_compressed`` expand a few times. A member that declares more is
a zip bomb, refused before it is decompressed. Only the members that bound
the others are held to it (:data:`EXPANSION_CAPPED`): a per-particle array
(``mineral`` of a one-phase packing, all zeros, deflates a thousand times)
has at most one row per particle and :data:`MAX_ROW_ENTRIES` entries a row.
"""

EXPANSION_CAPPED = frozenset(
    {
        "radius",
        "vertices",
        "meta",
        "face_vertices",
        "face_vertex_offsets",
        "face_offsets",
        "normals",
        "support",
    }
)
"""Members held to :data:`MAX_EXPANSION`: ``meta``, the particle count, vertices and faces."""

MAX_ROW_ENTRIES = 16
"""Most entries a row of a per-particle array may declare (a rotation matrix has 9)."""

MAX_VERTICES_PER_PARTICLE = 2**16
"""Most vertices (2D) or faces and face vertices (3D) a file may give one particle on average."""

_EXPANSION_FLOOR = 2**20
_NPY_HEADER_LIMIT = 10_000
_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"')


def _json_depth(text: str) -> int:
    """Deepest nesting of ``[`` and ``{`` in the JSON ``text`` (strings left out), vectorised."""
    skeleton = _JSON_STRING.sub("", text).encode("utf-8", "replace")
    codes = np.frombuffer(skeleton, dtype=np.uint8)
    if codes.size == 0:
        return 0
    step = np.isin(codes, (ord("["), ord("{"))).astype(np.int64)
    step -= np.isin(codes, (ord("]"), ord("}")))
    return int(np.cumsum(step).max(initial=0))


class PackingArchive:
    """The ``.npy`` members of a packing file, each read only after its header is checked.

    Before a member's data is read, its NPY header (shape, dtype) is read and
    checked: no pickled objects, at most ``rows`` rows when the caller gives
    them, a declared size in the zip directory equal to what the header
    implies, and no more than :data:`MAX_EXPANSION` times its compressed
    size (above 1 MiB). So a file cannot make :func:`load` read, decompress
    or allocate more than its own size allows, whatever it declares.
    """

    def __init__(self, path: Path, zf: zipfile.ZipFile, disk_size: int) -> None:
        self.path = path
        self._zip = zf
        self._disk_size = disk_size
        members: dict[str, zipfile.ZipInfo] = {}
        for info in zf.infolist():
            if info.filename.endswith(".npy"):
                name = info.filename[:-4]
                if name in members:  # zipfile reads one copy, numpy.load the other
                    raise _bad(path, f"member {info.filename!r} appears more than once")
                members[name] = info
        self._members = members
        self.files = list(members)

    def _unreadable(self, name: str, err: Exception) -> PackingFileError:
        """Return the error for a member zipfile cannot open: encrypted, or of an unknown method."""
        if isinstance(err, NotImplementedError):  # a RuntimeError too
            why = " ".join(str(err).split())
        else:
            why = "it is encrypted; regopack writes members in the clear"
        return _bad(self.path, f"member {name!r} cannot be read ({why})")

    def _info(self, name: str, capped: bool = True) -> zipfile.ZipInfo:
        info = self._members[name]
        size, packed = info.file_size, info.compress_size
        if packed > self._disk_size:
            raise _bad(
                self.path,
                f"member {name!r} declares {packed} compressed bytes in a file of "
                f"{self._disk_size} bytes",
            )
        if capped and size > _EXPANSION_FLOOR and size > MAX_EXPANSION * max(packed, 1):
            raise _bad(
                self.path,
                f"member {name!r} declares {size} bytes compressed into {packed}, more than "
                f"{MAX_EXPANSION} times (regopack stores members uncompressed)",
            )
        return info

    def header(self, name: str, capped: bool = True) -> tuple[tuple[int, ...], np.dtype[Any]]:
        """Shape and dtype that member ``name`` declares, checked against its size.

        Raises
        ------
        PackingFileError
            When the member has no valid NPY header, declares a pickled
            (object) dtype, or a size other than its zip entry's.
        """
        info = self._info(name, capped)
        try:
            with self._zip.open(info) as fh:
                version = np.lib.format.read_magic(fh)
                if version == (1, 0):
                    header = np.lib.format.read_array_header_1_0(
                        fh, max_header_size=_NPY_HEADER_LIMIT
                    )
                elif version == (2, 0):
                    header = np.lib.format.read_array_header_2_0(
                        fh, max_header_size=_NPY_HEADER_LIMIT
                    )
                else:
                    raise ValueError(f"NPY format version {version[0]}.{version[1]}")
                start = fh.tell()
        except (NotImplementedError, RuntimeError) as err:  # compression method, encryption
            raise self._unreadable(name, err) from None
        except (ValueError, OSError, EOFError, zipfile.BadZipFile) as err:
            raise _invalid(
                self.path, f"member {name!r} has no valid NPY header ({' '.join(str(err).split())})"
            ) from None
        shape, _, dtype = header
        if dtype.hasobject:
            raise _invalid(
                self.path,
                f"array {name!r} cannot be read (Object arrays need pickle, which is not allowed)",
            )
        entries = math.prod(shape)
        if start + entries * dtype.itemsize != info.file_size:
            raise _invalid(
                self.path,
                f"array {name!r} declares shape {shape} of {dtype} ({entries * dtype.itemsize} "
                f"bytes), but its member holds {info.file_size - start} bytes after the header",
            )
        return shape, dtype

    def read(self, name: str, ndim: int | None = None, rows: int | None = None) -> NDArray[Any]:
        """Read member ``name`` after checking its header (and its rows, if ``rows`` is given).

        Raises
        ------
        PackingFileError
            One line naming the file, the array, what it declares and what is allowed.
        """
        # a per-particle array, its rows bounded by the particle count, is not held
        # to the expansion cap; its rows' width is bounded below, before it is read
        capped = rows is None or name in EXPANSION_CAPPED
        shape, _ = self.header(name, capped)
        if ndim is not None and len(shape) != ndim:
            raise _invalid(
                self.path, f"array {name!r} has shape {shape}, expected a {ndim}-D array"
            )
        if rows is not None and shape and shape[0] > rows:
            raise _invalid(
                self.path, f"array {name!r} declares {shape[0]} rows; at most {rows} are allowed"
            )
        if not capped and math.prod(shape[1:]) > MAX_ROW_ENTRIES:
            raise _invalid(
                self.path,
                f"array {name!r} has shape {shape}; at most {MAX_ROW_ENTRIES} entries a row "
                "are allowed",
            )
        try:
            with self._zip.open(self._members[name]) as fh:
                arr: NDArray[Any] = np.lib.format.read_array(
                    fh, allow_pickle=False, max_header_size=_NPY_HEADER_LIMIT
                )
        except (NotImplementedError, RuntimeError) as err:  # compression method, encryption
            raise self._unreadable(name, err) from None
        return arr

    def __getitem__(self, name: str) -> NDArray[Any]:
        return self.read(name)


@contextmanager
def open_archive(path: str | Path) -> Iterator[PackingArchive]:
    """Open a packing file (a regular file only) as a :class:`PackingArchive`.

    Raises
    ------
    PackingFileError
        When the file is missing, not a regular file (a directory, a FIFO,
        a device), or not a zip archive.
    """
    path = open_packing_file(path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as err:
        raise PackingFileError(f"{path}: cannot be read ({err.strerror})") from None
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not _stat.S_ISREG(st.st_mode):  # replaced since it was looked at
            raise PackingFileError(f"{path}: not a regular file, not a packing file")
        if not zipfile.is_zipfile(fh):
            raise _bad(path, "not an NPZ archive (a packing file is written by 'regopack run')")
        try:
            zf = zipfile.ZipFile(fh)
        except (zipfile.BadZipFile, OSError, ValueError, EOFError) as err:
            raise _bad(path, " ".join(str(err).split()) or type(err).__name__) from None
        with zf:
            yield PackingArchive(path, zf, st.st_size)


def read_arrays(
    path: Path, npz: PackingArchive, arrays: Mapping[str, tuple[type[np.generic], int]]
) -> dict[str, Any]:
    """Read ``arrays`` (and ``rounding``, if present), each header checked before its data.

    ``radius`` is read first; its length ``n`` bounds the rows of the others
    (:func:`row_limits`), so no member is read that ``n`` particles cannot fill.
    """
    for name in arrays:
        if name not in npz.files:
            raise _invalid(path, f"missing array {name!r}")
    dtype, ndim = arrays["radius"]
    out: dict[str, Any] = {"radius": _read_array(path, npz, "radius", dtype, ndim)}
    limits = row_limits(int(out["radius"].shape[0]), arrays)
    for name, (dtype, ndim) in arrays.items():
        if name != "radius":
            out[name] = _read_array(path, npz, name, dtype, ndim, limits[name])
    if "rounding" in npz.files:
        out["rounding"] = _read_array(path, npz, "rounding", np.float64, 1, limits["rounding"])
    return out


def load(path: str | Path) -> Packing:
    """Read a 2D or 3D packing written by :func:`save`, checking it against its format.

    A file of format version 1 or 2 holds a 2D packing, one of version 3 a 3D
    packing. Every array is checked (dtype, shape, finite values, index
    ranges, the order of placement; see :meth:`Packing.validate`), and so is
    every ``meta`` key (types, the domain's geometry), so that a damaged or
    crafted file never reaches a compiled kernel. Nothing is unpickled.

    Raises
    ------
    PackingFileError
        One line naming the file: if it is missing, is not a regopack packing
        file, was written in a newer format version, or breaks the format
        (``invalid packing file: array 'mineral' has the value 7 at particle
        3, ...``, naming the array or ``meta`` key and what is wrong).
    """
    try:
        with open_archive(path) as npz:
            path = npz.path
            meta = _read_meta(path, npz)
            solid = meta["format_version"] == FORMAT_VERSION_3D
            if solid and meta.get("dimension") != 3:
                raise _invalid(path, f"meta 'dimension' is {_short(meta.get('dimension'))}, not 3")
            if not solid and meta.get("dimension", 2) != 2:
                raise _invalid(
                    path,
                    f"meta 'dimension' is {_short(meta.get('dimension'))} in a format "
                    f"version {meta['format_version']} file, which holds 2D packings",
                )
            arrays = read_arrays(path, npz, _ARRAYS3D if solid else _ARRAYS)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        raise _bad(Path(path), " ".join(str(err).split()) or type(err).__name__) from err
    keys = _read_meta_keys(path, meta, 3 if solid else 2)
    try:
        packing: Packing = Packing(**arrays, **keys)
        check_file_values(packing, meta["format_version"])
    except PackingError as err:
        raise _invalid(path, str(err)) from err
    check_file_scene(path, packing)
    return packing


_DEPRECATED = {
    "Packing3D": "Packing",
    "save3d": "save",
    "save_packing": "save",
    "load_packing": "load",
    "check_file_values3d": "check_file_values",
}
"""Former names (of ``regopack.packing.core3d``), deprecated, and the names that replaced them."""


__getattr__ = renamed_names(__name__, _DEPRECATED)
"""Give the former 3D names (deprecated) the names that replaced them (PEP 562)."""
