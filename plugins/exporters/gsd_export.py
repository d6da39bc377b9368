"""GSD export: one HOOMD-blue frame for HOOMD-blue, freud and OVITO.

The frame holds the placed particles in draw order. Every particle has its
own random outline, so every particle has its own **type**, named
``<mineral>_<index>`` (``index``: the particle's draw index in the packing
file), whose entry of ``particles/type_shapes`` is its outline in the GSD
shape schema: ``{"type": "Polygon", "rounding_radius": rho, "vertices": [...]}``,
the form in which HOOMD-blue writes the shapes of its ``ConvexPolygon``
(``rho = 0``) and ``ConvexSpheropolygon`` (``rho > 0``; a disk is the single
vertex ``(0, 0)`` rounded by its radius) integrators.

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
- **Units**: lengths in the scene's ``length_unit`` (GSD has no unit field);
  the log entry ``regopack/length_unit_m`` holds that unit in metres
  (``1e-6`` for micrometres).
- **Mass** = area x ``density``; ``moment_inertia`` = ``[0, 0, Izz]`` about
  the centroid (:func:`shape_moments`).

``gsd`` is an optional dependency (``pip install gsd``, or ``pip install '.[gsd]'``
in regopack's source folder).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ExportError
from regopack.base.messages import install_hint
from regopack.base.units import METRES, length_unit
from regopack.geometry.domain import PeriodicRectangle
from regopack.packing.core import Packing, _remove_stale_temporaries
from regopack.plugins.exporters.rounded_bodies import rounded_moments
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Analyzer, Exporter
from regopack.registry.plugin_types import ExporterSpec

__all__ = [
    "OUTLINE_TOL",
    "GsdConfig",
    "GsdExporter",
    "convex_outline",
    "shape_moments",
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
        description="Mass per unit area; the mass of a particle is its area times this.",
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


class GsdExporter(Exporter):
    """One HOOMD-blue GSD frame (2D) with a type and a polygon shape per placed particle.

    See the module's documentation for the layout. Besides the standard
    chunks the frame logs ``particles/regopack/mineral`` (mineral index),
    ``particles/regopack/index`` (draw index), ``particles/regopack/insertion_index``,
    and ``regopack/origin`` (``[x, y, 0]``: add it to a position to get the
    domain's coordinates), ``regopack/density`` and ``regopack/periodic``.

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

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the frame; return ``path``."""
        hoomd = _gsd_hoomd()
        path = Path(path)
        rho_all = packing.rounding_radius
        density = self.config.density
        xmin, xmax, ymin, ymax = (float(v) for v in packing.domain.bounds())
        length = np.array([xmax - xmin, ymax - ymin])
        origin = np.array([0.5 * (xmin + xmax), 0.5 * (ymin + ymax)])
        idx = np.flatnonzero(packing.placed)
        n = len(idx)
        pos = np.zeros((n, 2))
        theta = packing.orientation[idx]
        mass = np.zeros(n)
        izz = np.zeros(n)
        diameter = np.zeros(n)
        shapes: list[dict[str, Any]] = []
        types: list[str] = []
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
            pos[i] = packing.centre[j] + c - origin
            mass[i] = area * density
            izz[i] = polar * density
            diameter[i] = 2.0 * (float(np.hypot(*rel.T).max()) + rho)
            types.append(f"{packing.mineral_names[packing.mineral[j]]}_{j}")
            shapes.append({"type": "Polygon", "rounding_radius": rho, "vertices": body.tolist()})
        image = np.zeros((n, 3), dtype=np.int32)
        box = np.array([length[0], length[1], 0.0, 0.0, 0.0, 0.0], dtype=np.float32)
        periodic = isinstance(packing.domain, PeriodicRectangle)
        if periodic:
            shift = np.floor((pos + 0.5 * length) / length)
            pos -= shift * length
            image[:, :2] = shift.astype(np.int32)
        position = np.zeros((n, 3), dtype=np.float32)
        position[:, :2] = pos
        if periodic:  # rounding to single precision may land on +L/2
            for axis in range(2):
                big = box[axis]
                hi = position[:, axis] >= big / 2
                position[hi, axis] -= big
                image[hi, axis] += 1
                lo = position[:, axis] < -big / 2
                position[lo, axis] += big
                image[lo, axis] -= 1
        orientation = np.zeros((n, 4), dtype=np.float32)
        orientation[:, 0] = np.cos(0.5 * theta)
        orientation[:, 3] = np.sin(0.5 * theta)
        frame = hoomd.Frame()
        frame.configuration.step = 0
        frame.configuration.dimensions = 2
        frame.configuration.box = box
        frame.particles.N = n
        if n:
            frame.particles.types = types
            frame.particles.type_shapes = shapes
        frame.particles.typeid = np.arange(n, dtype=np.uint32)
        frame.particles.position = position
        frame.particles.orientation = orientation
        frame.particles.mass = mass.astype(np.float32)
        frame.particles.moment_inertia = np.column_stack([np.zeros(n), np.zeros(n), izz]).astype(
            np.float32
        )
        frame.particles.diameter = diameter.astype(np.float32)
        frame.particles.image = image
        frame.log["particles/regopack/mineral"] = packing.mineral[idx].astype(np.int32)
        frame.log["particles/regopack/index"] = idx.astype(np.int64)
        frame.log["particles/regopack/insertion_index"] = packing.insertion_index[idx].astype(
            np.int64
        )
        frame.log["regopack/origin"] = np.array([origin[0], origin[1], 0.0])
        frame.log["regopack/density"] = np.array([density])
        frame.log["regopack/length_unit_m"] = np.array([METRES[length_unit(packing)]])
        frame.log["regopack/periodic"] = np.array([int(periodic)], dtype=np.uint8)
        _write_frame(path, frame, hoomd)
        return path


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the GSD exporter."""
    return [
        ExporterSpec(
            "gsd",
            GsdConfig,
            GsdExporter,
            "GSD frame for HOOMD-blue, freud and OVITO (one polygon type per particle).",
        )
    ]
