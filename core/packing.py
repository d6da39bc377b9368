"""The result of a run: every drawn particle, where it went, and how the run was set up.

A :class:`Packing` is saved as an NPZ file (see ``docs/reference/packing-format.md``)
with :func:`save` and read back with :func:`load`. Writes are atomic: a file
is either the previous one or the complete new one, never a partial write.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import zipfile
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.domain import Domain, Rectangle, domain_from_dict
from regopack.errors import GeometryError, PackingFileError

if TYPE_CHECKING:
    from regopack.interfaces import InsertionResult
    from regopack.population import Population

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


def _segment_reduce(
    ufunc: np.ufunc, values: FloatArray, offsets: IntArray, empty: float = 0.0
) -> FloatArray:
    n = offsets.shape[0] - 1
    out = np.full(n, empty, dtype=np.float64)
    nonempty = np.diff(offsets) > 0
    if values.shape[0] and nonempty.any():
        out[nonempty] = ufunc.reduceat(values, offsets[:-1][nonempty])
    return out


@dataclass(frozen=True, eq=False)
class Packing:
    """All drawn particles of a run, in draw order, and where each was placed.

    Attributes
    ----------
    radius
        ``(n,)`` equivalent radius of each particle (area = pi r^2).
    mineral
        ``(n,)`` int64 index into :attr:`mineral_names`.
    mineral_names
        Phase names in scene order.
    vertices
        ``(M, 2)`` counter-clockwise outline vertices relative to each particle's centre.
    offsets
        ``(n + 1,)`` int64; particle ``j``'s vertices are ``vertices[offsets[j]:offsets[j+1]]``.
    orientation
        ``(n,)`` orientation angle of each particle in radians.
    centre
        ``(n, 2)`` position of each particle's centre (reference point); NaN where not placed.
    insertion_index
        ``(n,)`` int64 order of placement, ``-1`` where not placed.
    domain
        The container.
    scene
        The fully resolved scene.
    seed
        Seed of the run.
    version
        regopack version that produced the packing.
    stats
        Counters and timings of the run.
    rounding
        ``(n,)`` radius of the disk that rounds each outline (a disk is one
        vertex at its centre rounded by its radius), or ``None`` when every
        particle is a sharp polygon.
    """

    radius: FloatArray
    mineral: IntArray
    mineral_names: tuple[str, ...]
    vertices: FloatArray
    offsets: IntArray
    orientation: FloatArray
    centre: FloatArray
    insertion_index: IntArray
    domain: Domain
    scene: dict[str, Any] = field(default_factory=dict)
    seed: int = 0
    version: str = "0.0.0"
    stats: dict[str, float] = field(default_factory=dict)
    rounding: FloatArray | None = None

    @classmethod
    def from_parts(
        cls,
        population: Population,
        result: InsertionResult,
        domain: Domain,
        scene_dict: Mapping[str, Any],
        seed: int,
        stats: Mapping[str, float] | None = None,
    ) -> Packing:
        """Combine a population and an insertion result into a packing.

        ``stats`` defaults to ``result.stats``.
        """
        from regopack import __version__

        n = len(population)
        centre = np.asarray(result.centre, dtype=np.float64).reshape(n, 2)
        insertion_index = np.asarray(result.insertion_index, dtype=np.int64).reshape(n)
        return cls(
            radius=np.asarray(population.radius, dtype=np.float64),
            mineral=np.asarray(population.mineral, dtype=np.int64),
            mineral_names=tuple(population.mineral_names),
            vertices=np.asarray(population.shapes.vertices, dtype=np.float64).reshape(-1, 2),
            offsets=np.asarray(population.shapes.offsets, dtype=np.int64),
            orientation=np.asarray(population.shapes.orientation, dtype=np.float64),
            centre=centre,
            insertion_index=insertion_index,
            domain=domain,
            scene=dict(scene_dict),
            seed=int(seed),
            version=__version__,
            stats=dict(result.stats if stats is None else stats),
            rounding=population.shapes.rounding,
        )

    # -- counts and masks ---------------------------------------------------

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

    @property
    def not_placed(self) -> IntArray:
        """Indices of the particles that were not placed."""
        return np.flatnonzero(~self.placed).astype(np.int64)

    def placed_in_order(self) -> IntArray:
        """Return the indices of the placed particles, in the order they were placed."""
        idx = np.flatnonzero(self.placed)
        return idx[np.argsort(self.insertion_index[idx], kind="stable")].astype(np.int64)

    # -- geometry ---------------------------------------------------------------

    @property
    def rounding_radius(self) -> FloatArray:
        """Rounding radius of every particle (zeros for sharp polygons)."""
        if self.rounding is None:
            return np.zeros(self.n_particles, dtype=np.float64)
        return np.asarray(self.rounding, dtype=np.float64)

    @property
    def rounded(self) -> bool:
        """True when some particle is rounded (a disk or a rounded polygon)."""
        return self.rounding is not None and bool(np.any(self.rounding > 0))

    def _select(self, indices: ArrayLike | None) -> IntArray:
        if indices is None:
            return np.flatnonzero(self.placed).astype(np.int64)
        return np.atleast_1d(np.asarray(indices, dtype=np.int64))

    def polygon(self, j: int) -> FloatArray:
        """Absolute vertices ``(k, 2)`` of particle ``j`` (NaN if not placed)."""
        out: FloatArray = self.vertices[self.offsets[j] : self.offsets[j + 1]] + self.centre[j]
        return out

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
        """Absolute vertices of several particles.

        Parameters
        ----------
        indices
            Particle indices; by default the placed particles in draw order
            (``np.flatnonzero(packing.placed)``).
        """
        idx = self._select(indices)
        if self.rounded:
            geoms = self.to_shapely(idx)
            return [np.asarray(g.exterior.coords)[:-1] for g in geoms]
        coords, counts = self._absolute(idx)
        return np.split(coords, np.cumsum(counts)[:-1]) if len(idx) else []

    def to_shapely(self, indices: ArrayLike | None = None) -> NDArray[np.object_]:
        """Shapely polygons of several particles (default: the placed ones, in draw order).

        Examples
        --------
        >>> from regopack.testing import packing_from_polygons
        >>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
        >>> float(p.to_shapely()[0].area)
        1.0
        """
        import shapely

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
        """Area of every particle, exactly (shoelace; plus the rounding's strips and disk)."""
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

    @property
    def circumradius(self) -> FloatArray:
        """Largest distance from each particle's centre to its outline."""
        d = np.hypot(self.vertices[:, 0], self.vertices[:, 1])
        out = _segment_reduce(np.maximum, d, self.offsets)
        return out + self.rounding_radius if self.rounded else out

    def __repr__(self) -> str:
        return (
            f"Packing({self.n_placed}/{self.n_particles} placed, "
            f"scene={self.scene.get('name', '?')!r}, seed={self.seed})"
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


@contextmanager
def _atomic_file(path: Path) -> Iterator[IO[bytes]]:
    """Open a temporary file beside ``path``; move it over ``path`` on success."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
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
    _fsync_directory(directory)


def _fsync_directory(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


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


def save(packing: Packing, path: str | Path) -> None:
    """Write ``packing`` to ``path`` (NPZ), atomically.

    The file is written under a temporary name in the same directory, flushed
    to disk, then renamed over ``path``; an interrupted save leaves any
    previous file untouched. The name is used as given (no ``.npz`` is added).
    """
    arrays: dict[str, Any] = {name: getattr(packing, name) for name in _ARRAYS}
    if packing.rounded:
        arrays["rounding"] = packing.rounding_radius
    meta = json.dumps(_meta(packing), default=_json_default)
    savez: Callable[..., None] = np.savez
    with _atomic_file(Path(path)) as fh:
        savez(fh, meta=np.array(meta), **arrays)


def _bad(path: Path, why: str) -> PackingFileError:
    return PackingFileError(f"{path}: not a regopack packing file ({why})")


def load(path: str | Path) -> Packing:
    """Read a packing written by :func:`save`.

    Raises
    ------
    PackingFileError
        One line, if the file is missing, is not a regopack packing file, or
        was written in a newer format version.
    """
    path = Path(path)
    if not path.exists():
        raise PackingFileError(f"{path}: no such file")
    if path.is_dir():
        raise PackingFileError(f"{path}: is a directory, not a packing file")
    if not zipfile.is_zipfile(path):
        raise _bad(path, "not an NPZ archive (a packing file is written by 'regopack run')")
    try:
        with np.load(path, allow_pickle=False) as npz:
            contents = {name: npz[name] for name in npz.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        raise _bad(path, " ".join(str(err).split()) or type(err).__name__) from err
    if "meta" not in contents:
        raise _bad(path, "no 'meta' entry")
    try:
        meta = json.loads(str(contents["meta"]))
    except json.JSONDecodeError as err:
        raise _bad(path, "unreadable 'meta' entry") from err
    if not isinstance(meta, dict) or meta.get("format") != FILE_MAGIC:
        raise _bad(path, "'meta' does not identify a regopack packing")
    version = meta.get("format_version")
    if not isinstance(version, int):
        raise _bad(path, "no format version")
    if version > FORMAT_VERSION:
        raise PackingFileError(
            f"{path}: written in packing format version {version}, but this regopack "
            f"reads versions up to {FORMAT_VERSION}; upgrade regopack"
        )
    arrays: dict[str, Any] = {}
    for name, (dtype, ndim) in _ARRAYS.items():
        if name not in contents:
            raise _bad(path, f"missing array {name!r}")
        arr = contents[name]
        if arr.ndim != ndim or not np.can_cast(arr.dtype, dtype, casting="same_kind"):
            raise _bad(path, f"array {name!r} has dtype {arr.dtype} and {arr.ndim} dimensions")
        arrays[name] = arr.astype(dtype, copy=False)
    n = arrays["radius"].shape[0]
    offsets = arrays["offsets"]
    consistent = (
        all(arrays[k].shape[0] == n for k in ("mineral", "orientation", "centre"))
        and arrays["insertion_index"].shape[0] == n
        and arrays["centre"].shape[1:] == (2,)
        and arrays["vertices"].shape[1:] == (2,)
        and offsets.shape == (n + 1,)
        and offsets[0] == 0
        and offsets[-1] == arrays["vertices"].shape[0]
        and bool(np.all(np.diff(offsets) >= 0))
    )
    if not consistent:
        raise _bad(path, "array shapes are inconsistent")
    try:
        domain = domain_from_dict(meta["domain"])
        mineral_names = tuple(str(m) for m in meta["mineral_names"])
    except (KeyError, TypeError, ValueError, GeometryError) as err:
        raise _bad(path, "incomplete 'meta' entry") from err
    stats = {str(k): (math.nan if v is None else v) for k, v in dict(meta.get("stats", {})).items()}
    rounding = None
    if "rounding" in contents:
        rounding = np.asarray(contents["rounding"], dtype=np.float64)
        if rounding.shape != (n,) or not np.all(np.isfinite(rounding) & (rounding >= 0)):
            raise _bad(path, "array 'rounding' is not one finite radius >= 0 per particle")
    return Packing(
        **arrays,
        mineral_names=mineral_names,
        domain=domain,
        scene=dict(meta.get("scene") or {}),
        seed=int(meta.get("seed", 0)),
        version=str(meta.get("version", "unknown")),
        stats=stats,
        rounding=rounding,
    )
