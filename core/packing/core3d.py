"""The result of a 3D run: every drawn solid, where it went, and how the run was set up.

A :class:`Packing3D` is the 3D counterpart of :class:`regopack.packing.core.Packing`.
It is saved as an NPZ file in packing format version 3 (see
``docs/reference/packing-format.md``) by :func:`save3d`; :func:`load_packing`
reads a 2D or a 3D packing file, whichever it is. Writes are atomic.
"""

from __future__ import annotations

import json
import math
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import GeometryError, PackingError, PackingFileError
from regopack.geometry.domain import Box, domain_from_dict
from regopack.geometry.solids import SolidBatch
from regopack.packing.core import (
    FILE_MAGIC,
    FORMAT_VERSION_3D,
    MIN_RADIUS,
    REACH,
    Packing,
    PlacedParticles,
    _as_array,
    _atomic_file,
    _first,
    _invalid,
    _json_default,
    _read_meta,
    _read_meta_keys,
    _short,
    check_array_types,
    check_equivalent_radius,
    check_file_scene,
    check_particles,
    load,
    open_archive,
    read_arrays,
    save,
)

if TYPE_CHECKING:
    from regopack.geometry.population import Population
    from regopack.registry.interfaces import InsertionResult

__all__ = ["Packing3D", "load_packing", "save3d", "save_packing"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

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

_COLUMNS = {"vertices": 3, "normals": 3, "rotation": 4, "centre": 3}
_FINITE3D = ("radius", "vertices", "normals", "support", "rotation")
PLANE_TOLERANCE = 1e-9
"""Largest distance of a face vertex from the face's plane, relative to its face's size."""
UNIT_TOLERANCE = 1e-9
"""Largest departure from length 1 of a face normal or a rotation quaternion."""


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


@dataclass(frozen=True, eq=False)
class Packing3D(PlacedParticles):
    """All drawn solids of a 3D run, in draw order, and where each was placed.

    Attributes
    ----------
    radius
        ``(n,)`` equivalent radius (volume = 4/3 pi r^3).
    mineral, mineral_names
        Phase index of each particle and the phase names, as in 2D.
    vertices, offsets, face_vertices, face_vertex_offsets, face_offsets, normals, support, rotation
        The solids, relative to their centres, as in :class:`regopack.geometry.solids.SolidBatch`.
    centre
        ``(n, 3)`` position of each particle's centre; NaN where not placed.
    insertion_index
        ``(n,)`` order of placement, ``-1`` where not placed.
    domain
        The container (a walled or periodic box).
    scene, seed, version, stats
        As in 2D.
    rounding
        ``(n,)`` rounding radius of each solid (a sphere is one vertex rounded
        by its radius), or ``None`` when every solid is a sharp polyhedron.
    """

    radius: FloatArray
    mineral: IntArray
    mineral_names: tuple[str, ...]
    vertices: FloatArray
    offsets: IntArray
    face_vertices: IntArray
    face_vertex_offsets: IntArray
    face_offsets: IntArray
    normals: FloatArray
    support: FloatArray
    rotation: FloatArray
    centre: FloatArray
    insertion_index: IntArray
    domain: Box
    scene: dict[str, Any] = field(default_factory=dict)
    seed: int = 0
    version: str = "0.0.0"
    stats: dict[str, float] = field(default_factory=dict)
    rounding: FloatArray | None = None

    dimension = 3
    """Spatial dimension of the packing."""

    def __post_init__(self) -> None:
        """Convert the arrays to their dtypes (where no value changes) and :meth:`validate`."""
        for name, (dtype, _) in _ARRAYS3D.items():
            object.__setattr__(self, name, _as_array(name, getattr(self, name), dtype))
        if self.rounding is not None:
            object.__setattr__(self, "rounding", _as_array("rounding", self.rounding, np.float64))
        if isinstance(self.mineral_names, list | tuple):
            object.__setattr__(self, "mineral_names", tuple(self.mineral_names))
        self.validate()

    def validate(self) -> None:
        """Check the packing against packing format version 3; raise if it breaks it.

        As :meth:`regopack.packing.core.Packing.validate`, with the solids' arrays:
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
        check_array_types(self, _ARRAYS3D)
        for name, cols in _COLUMNS.items():
            shape = getattr(self, name).shape
            if shape[1] != cols:
                raise PackingError(
                    f"array {name!r} has shape {shape}, expected ({shape[0]}, {cols})"
                )
        n = self.radius.shape[0]
        for name in ("mineral", "rotation", "centre", "insertion_index"):
            rows = getattr(self, name).shape[0]
            if rows != n:
                raise PackingError(
                    f"array {name!r} has {rows} rows, expected one per particle "
                    f"({n}, the length of 'radius')"
                )
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
        for name in _FINITE3D:
            arr = getattr(self, name)
            finite = np.isfinite(arr)
            if not finite.all():
                row = _first(~finite.reshape(arr.shape[0], -1).all(axis=1))
                raise PackingError(
                    f"array {name!r} has the non-finite value {arr[row]} at row {row}"
                )
        for name in ("normals", "rotation"):
            arr = getattr(self, name)
            off = np.abs(np.sqrt(np.einsum("ij,ij->i", arr, arr)) - 1.0) > UNIT_TOLERANCE
            if off.any():
                row = _first(off)
                raise PackingError(f"array {name!r} has the non-unit row {arr[row]} at row {row}")
        self._check_geometry()
        check_particles(
            self.radius,
            self.mineral,
            self.mineral_names,
            self.insertion_index,
            self.centre,
            self.rounding,
            self.stats,
        )
        if not isinstance(self.domain, Box):
            raise PackingError(f"'domain' is a {type(self.domain).__name__}, not a 3D box")
        volume = self.domain.volume
        if not (math.isfinite(volume) and volume > 0):
            raise PackingError(f"'domain' {self.domain.to_dict()} has no positive finite volume")

    def _check_geometry(self) -> None:
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
        domain: Box,
        scene_dict: Mapping[str, Any],
        seed: int,
        stats: Mapping[str, float] | None = None,
    ) -> Packing3D:
        """Combine a 3D population and an insertion result into a packing."""
        from regopack._version import __version__

        shapes = population.shapes
        if not isinstance(shapes, SolidBatch):
            raise PackingError("a 3D packing needs a population of solids")
        n = len(population)
        return cls(
            radius=np.asarray(population.radius, dtype=np.float64),
            mineral=np.asarray(population.mineral, dtype=np.int64),
            mineral_names=tuple(population.mineral_names),
            vertices=shapes.vertices,
            offsets=shapes.offsets,
            face_vertices=shapes.face_vertices,
            face_vertex_offsets=shapes.face_vertex_offsets,
            face_offsets=shapes.face_offsets,
            normals=shapes.normals,
            support=shapes.support,
            rotation=shapes.rotation,
            centre=np.asarray(result.centre, dtype=np.float64).reshape(n, 3),
            insertion_index=np.asarray(result.insertion_index, dtype=np.int64).reshape(n),
            domain=domain,
            scene=dict(scene_dict),
            seed=int(seed),
            version=__version__,
            stats=dict(result.stats if stats is None else stats),
            rounding=shapes.rounding,
        )

    # -- counts and masks ---------------------------------------------------

    # -- geometry ---------------------------------------------------------------

    @property
    def solids(self) -> SolidBatch:
        """The particles' solids, relative to their centres."""
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

    @property
    def rounded(self) -> bool:
        """True when some particle is rounded (a sphere or a rounded polyhedron)."""
        return self.rounding is not None and bool(np.any(self.rounding > 0))

    def world_vertices(self, j: int) -> FloatArray:
        """Vertices of particle ``j`` in the packing's frame (NaN when not placed)."""
        out: FloatArray = self.vertices[self.offsets[j] : self.offsets[j + 1]] + self.centre[j]
        return out

    @property
    def phi(self) -> float:
        """Volume fraction of the box filled by the placed particles.

        In a walled box every placed solid lies inside; in a periodic box
        every part of a solid lies in the box once, in some image.
        """
        volume = self.solids.volume[self.placed].sum()
        return float(volume / self.domain.volume)

    def __repr__(self) -> str:
        sx, sy, sz = self.domain.size
        return (
            f"<Packing3D: {self.n_placed} of {self.n_particles} placed in a "
            f"{sx:g} × {sy:g} × {sz:g} {self.domain.kind}, phi {self.phi:.4f}>"
        )


def _meta3d(packing: Packing3D) -> dict[str, Any]:
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


def save3d(packing: Packing3D, path: str | Path) -> None:
    """Write ``packing`` to ``path`` (NPZ, format version 3), atomically.

    Raises
    ------
    PackingError
        When the packing breaks the format; nothing is written then.
    """
    packing.validate()
    arrays: dict[str, Any] = {name: getattr(packing, name) for name in _ARRAYS3D}
    if packing.rounding is not None:
        arrays["rounding"] = packing.rounding
    meta = json.dumps(_meta3d(packing), default=_json_default)
    savez: Callable[..., None] = np.savez
    with _atomic_file(Path(path)) as fh:
        savez(fh, meta=np.array(meta), **arrays)


def save_packing(packing: Packing | Packing3D, path: str | Path) -> None:
    """Write a 2D or 3D packing to ``path``, atomically, in the format of its dimension.

    Raises
    ------
    PackingError
        When the packing breaks its format; nothing is written then.
    """
    if isinstance(packing, Packing3D):
        save3d(packing, path)
    elif isinstance(packing, Packing):
        save(packing, path)
    else:
        raise PackingError(f"{type(packing).__name__} is not a packing")


def _read_box(path: Path, data: Any) -> Box:
    if not isinstance(data, dict):
        raise _invalid(path, f"meta 'domain' is {_short(data)}, not an object")
    try:
        return domain_from_dict(data, 3)
    except (KeyError, TypeError, ValueError, GeometryError) as err:
        why = f"no {err}" if isinstance(err, KeyError) else str(err)
        raise _invalid(path, f"meta 'domain' (kind {_short(data.get('kind'))}): {why}") from err


def check_file_values3d(packing: Packing3D) -> None:
    """Check what a 3D file's numbers mean, beyond :meth:`Packing3D.validate`.

    Every radius is the volume-equivalent radius of its solid within
    :data:`~regopack.packing.core.RADIUS_RTOL` (the volume as the cones from the
    centre over the faces, plus a sphere's; a flat or empty solid has none);
    every placed particle lies within :data:`~regopack.packing.core.REACH` box
    sizes of the box and its radius is at least
    :data:`~regopack.packing.core.MIN_RADIUS` of the box's largest side; in a
    periodic box every centre lies in the cell. Relative tolerances only;
    vectorised.

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
    b = packing.domain.bounds()
    low, high = b[0::2], b[1::2]
    size = float(np.max(high - low))
    small = placed & (packing.radius < MIN_RADIUS * size)
    if small.any():
        j = _first(small)
        raise PackingError(
            f"array 'radius' has the value {packing.radius[j]} at placed particle {j}, less "
            f"than {MIN_RADIUS:g} of the box's largest side {size:g}"
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
            f"{reach[j]:.6g} from it), more than the box's largest side ({size:g}) beyond "
            f"its bounds {b.tolist()}"
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


def load_packing(path: str | Path) -> Packing | Packing3D:
    """Read a 2D or 3D packing file, checking it against its format.

    A 2D file (format versions 1 and 2) gives a :class:`~regopack.packing.core.Packing`
    (see :func:`regopack.packing.core.load`), a 3D file (version 3) a
    :class:`Packing3D`, checked as thoroughly. Nothing is unpickled.

    Raises
    ------
    PackingFileError
        One line naming the file and what is wrong with it.
    """
    try:
        with open_archive(path) as npz:
            path = npz.path
            meta = _read_meta(path, npz)
            if meta["format_version"] != FORMAT_VERSION_3D:
                return load(path)
            if meta.get("dimension") != 3:
                raise _invalid(path, f"meta 'dimension' is {_short(meta.get('dimension'))}, not 3")
            arrays = read_arrays(path, npz, _ARRAYS3D)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        raise PackingFileError(
            f"{path}: not a regopack packing file ({' '.join(str(err).split())})"
        ) from err
    keys = _read_meta_keys(path, meta, _read_box)
    try:
        packing = Packing3D(**arrays, **keys)
        check_file_values3d(packing)
    except PackingError as err:
        raise _invalid(path, str(err)) from err
    check_file_scene(path, packing)
    return packing
