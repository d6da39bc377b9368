"""The ``gsd3d`` exporter: one 3D HOOMD-blue frame of convex polyhedra (GSD).

As the 2D ``gsd`` export, every placed particle has its own type,
``<mineral>_<index>``, whose entry of ``particles/type_shapes`` is its
polyhedron in the GSD shape schema: ``{"type": "ConvexPolyhedron",
"rounding_radius": 0, "vertices": [[x, y, z], ...]}``, the form in which
HOOMD-blue writes the shapes of its ``ConvexPolyhedron`` integrator.

- **Position**: the polyhedron's centroid (its centre of mass) minus the
  box's centre ``origin`` (GSD boxes are centred on the origin), which is
  logged as ``regopack/origin``.
- **Orientation and body frame**: the principal axes of the particle's
  inertia, as the unit quaternion ``(w, x, y, z)`` that turns the body frame
  into the box frame; the type's vertices are the polyhedron around its
  centroid in that body frame, and ``moment_inertia`` holds the principal
  moments, as HOOMD-blue's rigid-body integrators expect. The packing's own
  rotation quaternion is logged as ``particles/regopack/rotation``.
- **Units**: lengths in the scene's ``length_unit`` (GSD has no unit field);
  the log entry ``regopack/length_unit_m`` holds that unit in metres
  (``1e-6`` for micrometres).
- **Mass** = volume × ``density``.

A sphere (of a scene of spheres) is ``{"type": "Sphere", "diameter": d}``
at its centre, with the identity quaternion and the moments ``m d² / 10``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.units import METRES, length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.gsd_export import _gsd_hoomd, _write_frame
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.interfaces import Analyzer, SolidExporter

__all__ = ["Gsd3dConfig", "Gsd3dExporter", "principal_frame", "quaternion_from_matrix"]

FloatArray = NDArray[np.float64]


class Gsd3dConfig(BaseModel):
    """Parameters of the ``gsd3d`` exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    density: float = Field(
        1.0,
        gt=0,
        allow_inf_nan=False,
        description="Mass per unit volume; the mass of a particle is its volume times this.",
    )


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


class Gsd3dExporter(SolidExporter):
    """One HOOMD-blue GSD frame (3D) with a type and a convex-polyhedron shape per placed particle.

    See the module's documentation for the layout. Besides the standard
    chunks the frame logs ``particles/regopack/mineral``,
    ``particles/regopack/index`` (draw index), ``particles/regopack/insertion_index``,
    ``particles/regopack/rotation`` (the packing's quaternion ``(w, x, y, z)``),
    ``regopack/origin``, ``regopack/density`` and ``regopack/periodic``.

    Raises
    ------
    ExportError
        When ``gsd`` is not installed (on construction), or the file cannot
        be written.
    """

    suffix = ".gsd"

    def __init__(self, config: Gsd3dConfig | None = None) -> None:
        self.config = config or Gsd3dConfig()
        _gsd_hoomd()

    def export(
        self, packing: Packing[Box], path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the frame; return ``path``."""
        hoomd = _gsd_hoomd()
        path = Path(path)
        box = packing.domain
        lo, hi = box.bounds().reshape(3, 2).T
        length = hi - lo
        origin = 0.5 * (lo + hi)
        solids = placed_solids(packing, "gsd3d", spheres=True)
        n = len(solids)
        density = self.config.density
        pos = np.zeros((n, 3))
        quat = np.zeros((n, 4))
        mass = np.zeros(n)
        inertia = np.zeros((n, 3))
        diameter = np.zeros(n)
        types: list[str] = []
        shapes: list[dict[str, Any]] = []
        for i, s in enumerate(solids):
            types.append(f"{packing.mineral_names[packing.mineral[s.index]]}_{s.index}")
            if s.rounding > 0:  # a sphere: the GSD shape of a sphere, turned by nothing
                rho = s.rounding
                pos[i] = s.centre - origin
                quat[i] = (1.0, 0.0, 0.0, 0.0)
                mass[i] = 4.0 / 3.0 * np.pi * rho**3 * density
                inertia[i] = 0.4 * mass[i] * rho * rho
                diameter[i] = 2.0 * rho
                shapes.append({"type": "Sphere", "diameter": 2.0 * rho})
                continue
            volume, c, moments = mass_properties(s.local, s.loops)
            values, axes = principal_frame(moments * density)
            body = (s.local - c) @ axes  # box frame -> body frame: axesᵀ (x - c)
            pos[i] = s.centre + c - origin
            quat[i] = quaternion_from_matrix(axes)
            mass[i] = volume * density
            inertia[i] = values
            diameter[i] = 2.0 * float(np.linalg.norm(body, axis=1).max())
            shapes.append(
                {"type": "ConvexPolyhedron", "rounding_radius": 0.0, "vertices": body.tolist()}
            )
        image = np.zeros((n, 3), dtype=np.int32)
        periodic = bool(box.periodic)
        if periodic:
            shift = np.floor((pos + 0.5 * length) / length)
            pos -= shift * length
            image[:] = shift.astype(np.int32)
        idx = np.array([s.index for s in solids], dtype=np.int64)
        frame = hoomd.Frame()
        frame.configuration.step = 0
        frame.configuration.dimensions = 3
        frame.configuration.box = np.array([*length, 0.0, 0.0, 0.0], dtype=np.float32)
        frame.particles.N = n
        if n:
            frame.particles.types = types
            frame.particles.type_shapes = shapes
        frame.particles.typeid = np.arange(n, dtype=np.uint32)
        frame.particles.position = pos.astype(np.float32)
        frame.particles.orientation = quat.astype(np.float32)
        frame.particles.mass = mass.astype(np.float32)
        frame.particles.moment_inertia = inertia.astype(np.float32)
        frame.particles.diameter = diameter.astype(np.float32)
        frame.particles.image = image
        frame.log["particles/regopack/mineral"] = packing.mineral[idx].astype(np.int32)
        frame.log["particles/regopack/index"] = idx
        frame.log["particles/regopack/insertion_index"] = packing.insertion_index[idx]
        frame.log["particles/regopack/rotation"] = packing.rotation[idx].reshape(n, 4)
        frame.log["regopack/origin"] = origin.astype(np.float64)
        frame.log["regopack/density"] = np.array([density])
        frame.log["regopack/length_unit_m"] = np.array([METRES[length_unit(packing)]])
        frame.log["regopack/periodic"] = np.array([int(periodic)], dtype=np.uint8)
        _write_frame(path, frame, hoomd)
        return path
