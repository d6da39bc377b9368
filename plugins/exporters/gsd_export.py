"""GSD export: one HOOMD-blue frame for HOOMD-blue, freud and OVITO, of a 2D or 3D packing.

The frame holds the placed particles in draw order. Every particle has its
own random shape, so every particle has its own **type**, named
``<mineral>_<index>`` (``index``: the particle's draw index in the packing
file), whose entry of ``particles/type_shapes`` is its shape in the GSD
shape schema. Lengths are in the scene's ``length_unit`` in 2D and in a
power of ten of it in 3D (see *Lengths of a 3D frame* below; GSD has no unit
field); the log entry ``regopack/length_unit_m`` holds the file's unit in
metres (``1e-6`` for micrometres).

**2D packings.** A shape is ``{"type": "Polygon", "rounding_radius": rho,
"vertices": [...]}``, the form in which HOOMD-blue writes the shapes of its
``ConvexPolygon`` (``rho = 0``) and ``ConvexSpheropolygon`` (``rho > 0``; a
disk is the single vertex ``(0, 0)`` rounded by its radius) integrators.

- **Position**: the particle's centroid (centre of mass), in a box centred on
  the origin: ``position = centroid - origin``, with ``origin`` the centre of
  the domain's bounding box, stored as the log entry ``regopack/origin``.
  Periodic domains are wrapped into ``[-L/2, L/2)``, with the periods removed
  in ``particles/image``.
- **Orientation**: the packing's ``orientation`` angle as the quaternion
  ``(cos(t/2), 0, 0, sin(t/2))``; the type's vertices are the outline around
  the centroid rotated by ``-t`` (the particle's body frame).
- **Vertices**: counter-clockwise, distinct, without collinear vertices
  (:func:`convex_outline`), as HOOMD-blue requires.
- **Mass** = area x ``density``; ``moment_inertia`` = ``[0, 0, Izz]`` about
  the centroid (:func:`shape_moments`).

**3D packings.** A shape is ``{"type": "ConvexPolyhedron", "rounding_radius":
0, "vertices": [[x, y, z], ...]}``, the form in which HOOMD-blue writes the
shapes of its ``ConvexPolyhedron`` integrator.

- **Position**: the polyhedron's centroid minus the box's centre ``origin``
  (logged as ``regopack/origin``); periodic boxes are wrapped as in 2D.
- **Orientation and body frame**: the principal axes of the particle's
  inertia, as the unit quaternion ``(w, x, y, z)`` that turns the body frame
  into the box frame; the type's vertices are the polyhedron around its
  centroid in that body frame, and ``moment_inertia`` holds the principal
  moments, as HOOMD-blue's rigid-body integrators expect. The packing's own
  rotation quaternion is logged as ``particles/regopack/rotation``.
- **Mass** = volume x ``density``.

A sphere (of a scene of spheres) is ``{"type": "Sphere", "diameter": d}``
at its centre, with the identity quaternion and the moments ``m d² / 10``.

- **Lengths of a 3D frame**: in a power of ten of the scene's unit,
  :func:`shape_scale`, the smallest at least as large as the largest
  particle's circumradius (100 µm for grains up to 200 µm across): every
  shape is then at most 1 across its centre. OVITO builds the mesh of a
  ``ConvexPolyhedron`` type as a convex hull whose tolerances do not follow
  the shape's size, and draws a shape some units across (or thousands, or
  thousandths) as a sphere. Positions, the box, ``regopack/origin``,
  diameters and shapes are in that unit and moments in mass × its square;
  masses stay volume × ``density`` of the scene's unit. The log entries
  ``regopack/length_scale`` (the unit in the scene's unit: multiply a length
  of the file by it) and ``regopack/length_unit_m`` (the unit in metres)
  say which. A 2D frame is written in the scene's unit and has no
  ``regopack/length_scale``.

``gsd`` is an optional dependency (``pip install gsd``, or ``pip install '.[gsd]'``
in regopack's source folder).
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack._compat import renamed_names
from regopack.base.errors import ExportError
from regopack.base.messages import install_hint
from regopack.base.units import METRES, length_unit
from regopack.geometry.domain import Box, PeriodicRectangle
from regopack.packing.core import Packing, _remove_stale_temporaries
from regopack.plugins.exporters.export_common import Analyses, AnyPacking, both_dimensions
from regopack.plugins.exporters.rounded_bodies import rounded_moments
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Exporter
from regopack.registry.plugin_types import ExporterSpec

__all__ = [
    "OUTLINE_TOL",
    "GsdConfig",
    "GsdExporter",
    "convex_outline",
    "principal_frame",
    "quaternion_from_matrix",
    "shape_moments",
    "shape_scale",
]

FloatArray = NDArray[np.float64]

OUTLINE_TOL = 1e-9
"""Relative tolerance of :func:`convex_outline`.

Two consecutive vertices closer than this times the outline's largest
distance from its reference point are one vertex; a vertex whose two edges
turn by less than this (the sine of the angle) is collinear.
"""

INSTALL_HINT = f"the gsd export needs the gsd package: {install_hint('gsd')}"
"""Message of the error raised when ``gsd`` is not installed."""


class GsdConfig(BaseModel):
    """Parameters of the GSD exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    density: float = Field(
        1.0,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Mass per unit area (2D) or volume (3D); the mass of a particle is its area "
            "or volume times this."
        ),
    )


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    out: FloatArray = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def convex_outline(v: FloatArray, rel_tol: float = OUTLINE_TOL) -> FloatArray:
    """Return a convex outline without repeated and collinear vertices.

    Parameters
    ----------
    v
        ``(k, 2)`` counter-clockwise vertices of a convex outline.
    rel_tol
        Relative tolerance (see :data:`OUTLINE_TOL`).

    Returns
    -------
    numpy.ndarray
        The remaining vertices, in their order: one vertex when all coincide,
        the two ends when all lie on a line.

    Raises
    ------
    ValueError
        When the outline turns clockwise somewhere (not convex and
        counter-clockwise).

    Examples
    --------
    >>> sq = np.array([[0, 0], [1, 0], [1, 0], [2, 0], [2, 2], [0, 2]], dtype=float)
    >>> convex_outline(sq).tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]
    """
    v = np.asarray(v, dtype=np.float64).reshape(-1, 2)
    if v.shape[0] == 0:
        return v
    tol = rel_tol * float(np.abs(v).max())
    while v.shape[0] > 1:  # repeated vertices (edges of zero length)
        keep = np.hypot(*(v - np.roll(v, 1, axis=0)).T) > tol
        if keep.all():
            break
        if not keep.any():
            return v[:1].copy()
        v = v[keep]
    while v.shape[0] >= 3:  # collinear vertices
        e_in = v - np.roll(v, 1, axis=0)
        e_out = np.roll(v, -1, axis=0) - v
        cross = _cross(e_in, e_out)
        limit = rel_tol * np.hypot(*e_in.T) * np.hypot(*e_out.T)
        if np.any(cross < -limit):
            raise ValueError("the outline is not convex and counter-clockwise")
        flat = cross <= limit
        if not flat.any():
            break
        if flat.all():  # every vertex on one line: keep its two ends
            d = np.hypot(*(v[:, None, :] - v[None, :, :]).transpose(2, 0, 1))
            i, j = np.unravel_index(int(np.argmax(d)), d.shape)
            return v[[min(i, j), max(i, j)]].copy()
        v = v[~flat]
    return v


def shape_moments(core: FloatArray, rho: float) -> tuple[float, FloatArray, float]:
    """Area, centroid and polar second moment of a convex outline grown by ``rho``.

    The shape is the Minkowski sum of the convex ``core`` (``(k, 2)``,
    counter-clockwise, distinct, not collinear; one vertex or two are allowed
    when ``rho > 0``) and the disk of radius ``rho``: the core, a rectangle
    on every edge and a circular sector at every vertex
    (:func:`regopack.plugins.exporters.rounded_bodies.rounded_moments`).

    Returns
    -------
    tuple
        ``(area, centroid, j)`` with ``j = ∫ |x - centroid|² dA``.

    Examples
    --------
    >>> a, c, j = shape_moments(np.zeros((1, 2)), 2.0)
    >>> round(a / math.pi, 12), c.tolist(), round(j / (8 * math.pi), 12)
    (4.0, [0.0, 0.0], 1.0)
    """
    core = np.asarray(core, dtype=np.float64).reshape(-1, 2)
    if core.shape[0] < 3 and rho <= 0:
        raise ValueError("a sharp outline needs at least three vertices")
    area, centroid, ixx, iyy, _ = rounded_moments(core, rho)
    return float(area), centroid, float(ixx + iyy)


def _gsd_hoomd() -> Any:
    """Return the ``gsd.hoomd`` module, or raise the one-line install hint."""
    try:
        import gsd.hoomd
    except ImportError as err:
        raise ExportError(INSTALL_HINT) from err
    return gsd.hoomd


def _write_frame(path: Path, frame: Any, hoomd: Any) -> None:
    """Write ``frame`` to a temporary file beside ``path`` and rename it over ``path``."""
    from regopack.base.outdir import fsync_directory

    directory = path.parent if str(path.parent) else Path(".")
    try:
        _remove_stale_temporaries(directory, path.name)
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
        os.close(fd)
        try:
            with hoomd.open(tmp, "w") as traj:
                traj.append(frame)
            with open(tmp, "rb") as fh:
                os.fsync(fh.fileno())
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
            os.replace(tmp, path)
        except BaseException:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
            raise
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err
    fsync_directory(directory)


def quaternion_from_matrix(m: FloatArray) -> FloatArray:
    """Return the unit quaternion ``(w, x, y, z)``, ``w >= 0``, of the proper rotation matrix ``m``.

    Examples
    --------
    >>> quaternion_from_matrix(np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])).round(6).tolist()
    [0.707107, 0.0, 0.0, 0.707107]
    """
    t = float(np.trace(m))
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (m[k, j] - m[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j, i] + m[i, j]) / s
        q[1 + k] = (m[k, i] + m[i, k]) / s
    out = np.asarray(q, dtype=np.float64)
    out /= np.linalg.norm(out)
    return -out if out[0] < 0 else out


def principal_frame(moments: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Principal moments of inertia and the rotation whose columns are the principal axes.

    Parameters
    ----------
    moments
        ``∫ (x - c)(x - c)ᵀ dm`` about the centre of mass.

    Returns
    -------
    inertia, axes
        The three principal moments (ascending) and a proper rotation matrix
        (determinant +1) from the body frame to the box frame.
    """
    inertia_tensor = np.trace(moments) * np.eye(3) - moments
    values, axes = np.linalg.eigh(inertia_tensor)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return values, axes


@dataclass
class _Particles:
    """What the frame holds of the placed particles, before a periodic box wraps them.

    ``position`` is the centre of mass minus the box's centre, ``orientation``
    the quaternion ``(w, x, y, z)`` of the body frame, ``inertia`` the
    principal moments (``[0, 0, Izz]`` in 2D), ``logs`` the dimension's own
    per-particle log entries.
    """

    index: NDArray[np.int64]
    types: list[str]
    shapes: list[dict[str, Any]]
    position: FloatArray
    orientation: FloatArray
    mass: FloatArray
    inertia: FloatArray
    diameter: FloatArray
    logs: dict[str, NDArray[Any]]

    @classmethod
    def empty(cls, index: NDArray[np.int64], dim: int, logs: dict[str, NDArray[Any]]) -> _Particles:
        """Return zeros for ``len(index)`` particles of dimension ``dim``, to be filled in."""
        n = len(index)
        z = np.zeros
        return cls(index, [], [], z((n, dim)), z((n, 4)), z(n), z((n, 3)), z(n), logs)


def _type_name(packing: AnyPacking, j: int) -> str:
    return f"{packing.mineral_names[packing.mineral[j]]}_{j}"


def _polygons(packing: Packing, origin: FloatArray, density: float) -> _Particles:
    """Return the placed polygons: centroids, orientations, areas and polar moments."""
    rho_all = packing.rounding_radius
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    theta = packing.orientation[idx]
    out = _Particles.empty(idx, 2, {})
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    for i, j in enumerate(idx.tolist()):
        rho = float(rho_all[j])
        local = packing.vertices[packing.offsets[j] : packing.offsets[j + 1]]
        try:
            core = convex_outline(local)
            area, c, polar = shape_moments(core, rho)
        except ValueError as err:
            raise ExportError(f"particle {j}: {err}; GSD polygon shapes are convex") from err
        rel = core - c
        # body frame: the outline rotated back by the orientation angle
        body = np.column_stack(
            [
                cos_t[i] * rel[:, 0] + sin_t[i] * rel[:, 1],
                cos_t[i] * rel[:, 1] - sin_t[i] * rel[:, 0],
            ]
        )
        out.position[i] = packing.centre[j] + c - origin
        out.mass[i] = area * density
        out.inertia[i, 2] = polar * density
        out.diameter[i] = 2.0 * (float(np.hypot(*rel.T).max()) + rho)
        out.types.append(_type_name(packing, j))
        out.shapes.append({"type": "Polygon", "rounding_radius": rho, "vertices": body.tolist()})
    out.orientation[:, 0] = np.cos(0.5 * theta)
    out.orientation[:, 3] = np.sin(0.5 * theta)
    return out


def _solids(packing: Packing[Box], origin: FloatArray, density: float) -> _Particles:
    """Return the placed polyhedra and spheres: centroids, principal frames, volumes, moments."""
    solids = placed_solids(packing, "gsd", spheres=True)
    n = len(solids)
    idx = np.array([s.index for s in solids], dtype=np.int64)
    rotation = {"particles/regopack/rotation": packing.rotation[idx].reshape(n, 4)}
    out = _Particles.empty(idx, 3, rotation)
    for i, s in enumerate(solids):
        out.types.append(_type_name(packing, s.index))
        if s.rounding > 0:  # a sphere: the GSD shape of a sphere, turned by nothing
            rho = s.rounding
            out.position[i] = s.centre - origin
            out.orientation[i] = (1.0, 0.0, 0.0, 0.0)
            out.mass[i] = 4.0 / 3.0 * np.pi * rho**3 * density
            out.inertia[i] = 0.4 * out.mass[i] * rho * rho
            out.diameter[i] = 2.0 * rho
            out.shapes.append({"type": "Sphere", "diameter": 2.0 * rho})
            continue
        volume, c, moments = mass_properties(s.local, s.loops)
        values, axes = principal_frame(moments * density)
        body = (s.local - c) @ axes  # box frame -> body frame: axesᵀ (x - c)
        out.position[i] = s.centre + c - origin
        out.orientation[i] = quaternion_from_matrix(axes)
        out.mass[i] = volume * density
        out.inertia[i] = values
        out.diameter[i] = 2.0 * float(np.linalg.norm(body, axis=1).max())
        out.shapes.append(
            {"type": "ConvexPolyhedron", "rounding_radius": 0.0, "vertices": body.tolist()}
        )
    return out


def shape_scale(diameter: FloatArray) -> float:
    """Return the power of ten that the lengths of a 3D frame are written in (packing lengths).

    The smallest power of ten at least the largest circumradius, so that
    every shape is at most 1 across its centre: OVITO builds the mesh of a
    ``ConvexPolyhedron`` with a convex hull whose tolerances are absolute, and
    it draws as a sphere a shape that lies well outside about 0.01 to 2.

    Examples
    --------
    >>> [shape_scale(np.array(d)) for d in ([4.0, 25.8], [0.004], [])]
    [100.0, 0.01, 1.0]
    """
    if not diameter.size or not np.max(diameter) > 0:
        return 1.0
    return float(10.0 ** math.ceil(math.log10(0.5 * float(np.max(diameter)))))


def _rescaled(p: _Particles, scale: float) -> _Particles:
    """Return ``p`` with lengths divided by ``scale`` (masses kept, moments in the new length)."""
    if scale == 1.0:
        return p
    shapes = [
        {**sh, "diameter": sh["diameter"] / scale}
        if sh["type"] == "Sphere"
        else {**sh, "vertices": (np.asarray(sh["vertices"]) / scale).tolist()}
        for sh in p.shapes
    ]
    return _Particles(
        p.index,
        p.types,
        shapes,
        p.position / scale,
        p.orientation,
        p.mass,
        p.inertia / scale**2,
        p.diameter / scale,
        p.logs,
    )


def _wrap(
    pos: FloatArray, length: FloatArray, box: NDArray[np.float32], periodic: bool
) -> tuple[NDArray[np.float32], NDArray[np.int32]]:
    """Single-precision positions (z = 0 in 2D), in ``[-L/2, L/2)`` when periodic, and images."""
    n, dim = pos.shape
    image = np.zeros((n, 3), dtype=np.int32)
    if periodic:
        shift = np.floor((pos + 0.5 * length) / length)
        pos = pos - shift * length
        image[:, :dim] = shift.astype(np.int32)
    position = np.zeros((n, 3), dtype=np.float32)
    position[:, :dim] = pos
    if periodic:  # rounding to single precision may land on +L/2
        for axis in range(dim):
            big = box[axis]
            hi = position[:, axis] >= big / 2
            position[hi, axis] -= big
            image[hi, axis] += 1
            lo = position[:, axis] < -big / 2
            position[lo, axis] += big
            image[lo, axis] -= 1
    return position, image


class GsdExporter(Exporter[AnyPacking]):
    """One HOOMD-blue GSD frame with a type and a shape per placed particle, 2D or 3D.

    See the module's documentation for the layout. Besides the standard
    chunks the frame logs ``particles/regopack/mineral`` (mineral index),
    ``particles/regopack/index`` (draw index), ``particles/regopack/insertion_index``,
    in 3D ``particles/regopack/rotation`` (the packing's quaternion ``(w, x,
    y, z)``), and ``regopack/origin`` (add it to a position to get the
    domain's coordinates; z = 0 in 2D), ``regopack/density`` and
    ``regopack/periodic``.

    Raises
    ------
    ExportError
        When ``gsd`` is not installed (on construction), a particle's outline
        is not convex, or the file cannot be written.
    """

    suffix = ".gsd"

    def __init__(self, config: GsdConfig | None = None) -> None:
        self.config = config or GsdConfig()
        _gsd_hoomd()

    def export(self, packing: AnyPacking, path: Path, *, analyses: Analyses = None) -> Path:
        """Write the frame; return ``path``."""
        hoomd = _gsd_hoomd()
        path = Path(path)
        density = self.config.density
        dim = packing.domain.dimension
        lo, hi = np.asarray(packing.domain.bounds(), dtype=np.float64).reshape(dim, 2).T
        length = hi - lo
        origin = 0.5 * (lo + hi)
        scale = 1.0
        if packing.dimension == 3:
            periodic = bool(packing.domain.periodic)
            particles = _solids(packing, origin, density)
            scale = shape_scale(particles.diameter)
            particles = _rescaled(particles, scale)
            length, origin = length / scale, origin / scale
        else:
            periodic = isinstance(packing.domain, PeriodicRectangle)
            particles = _polygons(packing, origin, density)
        box = np.zeros(6, dtype=np.float32)
        box[:dim] = length
        position, image = _wrap(particles.position, length, box, periodic)
        n = len(particles.index)
        frame = hoomd.Frame()
        frame.configuration.step = 0
        frame.configuration.dimensions = dim
        frame.configuration.box = box
        frame.particles.N = n
        if n:
            frame.particles.types = particles.types
            frame.particles.type_shapes = particles.shapes
        frame.particles.typeid = np.arange(n, dtype=np.uint32)
        frame.particles.position = position
        frame.particles.orientation = particles.orientation.astype(np.float32)
        frame.particles.mass = particles.mass.astype(np.float32)
        frame.particles.moment_inertia = particles.inertia.astype(np.float32)
        frame.particles.diameter = particles.diameter.astype(np.float32)
        frame.particles.image = image
        idx = particles.index
        frame.log["particles/regopack/mineral"] = packing.mineral[idx].astype(np.int32)
        frame.log["particles/regopack/index"] = idx
        frame.log["particles/regopack/insertion_index"] = packing.insertion_index[idx].astype(
            np.int64
        )
        frame.log.update(particles.logs)
        frame.log["regopack/origin"] = np.concatenate([origin, np.zeros(3 - dim)])
        frame.log["regopack/density"] = np.array([density])
        frame.log["regopack/length_unit_m"] = np.array([METRES[length_unit(packing)] * scale])
        if dim == 3:  # a 2D frame is in the scene's unit
            frame.log["regopack/length_scale"] = np.array([scale])
        frame.log["regopack/periodic"] = np.array([int(periodic)], dtype=np.uint8)
        _write_frame(path, frame, hoomd)
        return path


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the GSD exporter."""
    return [
        both_dimensions(
            "gsd",
            GsdConfig,
            GsdExporter,
            "GSD frame for HOOMD-blue, freud and OVITO (a polygon or polyhedron type per "
            "particle).",
        )
    ]


__getattr__ = renamed_names(
    __name__,
    {
        "Gsd3dConfig": "GsdConfig",
        "Gsd3dExporter": "GsdExporter",
    },
)
"""The names of the 3D exporter this module's exporter took over, for one release."""
