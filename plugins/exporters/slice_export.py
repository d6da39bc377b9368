"""The ``slice`` exporter: a planar section of a 3D packing as a 2D packing file and a picture.

The plane ``x[axis] = at`` cuts every placed solid
(:func:`regopack.packing.drawing.section_polygons`); each cut is a convex polygon,
which becomes one particle of a 2D :class:`~regopack.packing.core.Packing` in the
plane's coordinates (the two other axes in order: x, y for a z section; y, z
for an x section; x, z for a y section), keeping its mineral, in a walled
rectangle, the box's face (in a walled cylinder: its circle for a z section,
the rectangle of the chord the plane cuts for an x or y one). Every 2D
analysis and export then reads the section as it reads a packing of polygons.

- **Particles**: the cuts, in the order their solids were inserted, each
  with its centroid as centre, its outline around it counter-clockwise, the
  equivalent radius of its area (area = π r²) as radius and orientation 0.
  Cuts of less than 10⁻¹² of the section's area (the plane grazing a vertex
  or an edge) are left out.
- **Scene**: ``name`` (the 3D scene's, with ``-slice``), a ``rectangle``
  (or ``circle``) domain, the 3D scene's ``density`` section and a ``slice`` table (the 3D
  scene's name, ``axis``, ``at``, and the index of each cut's solid in the
  3D packing, ``solids``). There is no ``size`` section: the sizes of the
  cuts do not follow the 3D size distribution.
- **Stats**: ``interior_margin`` (the 3D scene's ``d_max``, so that the 2D
  analyses leave out the band that the walls order in 3D), ``slice_at``,
  ``slice_axis`` (0, 1, 2) and ``slice_phi`` (the area fraction of the cut).
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError, ExportError
from regopack.base.units import reference_diameter
from regopack.geometry.domain import Box, Circle, Cylinder, Rectangle
from regopack.packing.core import Packing, save
from regopack.plugins.exporters.solid_export_common import write_bytes
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["SliceConfig", "SliceExporter", "image_path", "slice_packing"]

FloatArray = NDArray[np.float64]

SLIVER = 1e-12
"""Cuts smaller than this fraction of the section's area are left out."""

AXES = "xyz"


class SliceConfig(BaseModel):
    """Parameters of the ``slice`` exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    axis: Literal["x", "y", "z"] = Field("z", description="Normal of the cutting plane.")
    fraction: float = Field(
        0.5,
        gt=0,
        lt=1,
        description="Position of the plane as a fraction of the box along `axis` (0.5: middle).",
    )
    at: float | None = Field(
        None,
        allow_inf_nan=False,
        description="Position of the plane in the packing's coordinates; replaces `fraction`.",
    )
    image: bool = Field(True, description="Also draw the section as <stem>.png.")


def image_path(path: Path) -> Path:
    """Return the picture written beside the section ``path``: ``<stem>.png``.

    Examples
    --------
    >>> image_path(Path("runs/a/packing.slice.npz")).as_posix()
    'runs/a/packing.slice.png'
    """
    return Path(path).with_suffix(".png")


def _plane(packing: Packing[Box], config: SliceConfig) -> tuple[int, float]:
    axis = AXES.index(config.axis)
    lo, hi = (float(v) for v in packing.domain.bounds().reshape(3, 2)[axis])
    if config.at is None:
        return axis, lo + config.fraction * (hi - lo)
    if not lo < config.at < hi:
        raise ConfigError(
            f"exporter 'slice': at = {config.at:g}: outside the box along {config.axis}, "
            f"which spans {lo:g} to {hi:g}; give a value between them"
        )
    return axis, float(config.at)


def _section_domain(box: Box | Cylinder, axis: int, at: float) -> Rectangle | Circle:
    """Return the domain of the section ``x[axis] = at``, in the plane's coordinates.

    A box's face, a rectangle; a cylinder's is its circle (a z section) or the
    rectangle of the chord that the plane cuts from its circle (x or y).

    Raises
    ------
    ConfigError
        When the plane misses the cylinder's circle.
    """
    bounds = box.bounds().reshape(3, 2)
    keep = [a for a in range(3) if a != axis]
    if not isinstance(box, Cylinder):
        return Rectangle(*bounds[keep[0]], *bounds[keep[1]])
    if axis == 2:
        return Circle(box.cx, box.cy, box.radius)
    offset = at - (box.cx, box.cy)[axis]
    half = float(np.sqrt(max(box.radius**2 - offset**2, 0.0)))
    if not half > 0:
        raise ConfigError(
            f"exporter 'slice': at = {at:g}: the plane misses the cylinder's circle; give a "
            "value between its sides"
        )
    across = (box.cy, box.cx)[axis]
    return Rectangle(across - half, across + half, box.zmin, box.zmax)


def _area_centroid(poly: FloatArray) -> tuple[float, FloatArray]:
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * float(cross.sum())
    centroid = np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * area)
    return area, centroid


def slice_packing(packing: Packing[Box], config: SliceConfig | None = None) -> Packing:
    """Cut ``packing`` with the configured plane; return the section as a 2D packing.

    Raises
    ------
    ConfigError
        When ``at`` lies outside the box.
    ExportError
        For a periodic box, whose sections are not cut yet.
    """
    from regopack.packing.drawing import section_polygons

    cfg = config or SliceConfig()
    box = packing.domain
    if box.periodic:
        raise ExportError("the slice export cuts walled boxes only, not a periodic box")
    axis, at = _plane(packing, cfg)
    domain = _section_domain(box, axis, at)
    polygons, owners = section_polygons(packing, axis, at)
    smallest = SLIVER * domain.area
    rows = []
    for poly, j in zip(polygons, owners.tolist(), strict=True):
        cut_area, centroid = _area_centroid(poly)
        if cut_area > smallest:
            rows.append((int(packing.insertion_index[j]), j, poly, cut_area, centroid))
    rows.sort(key=lambda row: row[0])
    n = len(rows)
    outlines = [poly - c for _, _, poly, _, c in rows]
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum([len(o) for o in outlines], out=offsets[1:])
    area = np.array([row[3] for row in rows])
    scene3d = packing.scene
    size = scene3d.get("size") if isinstance(scene3d, dict) else None
    d_max = size.get("d_max") if isinstance(size, dict) else None
    if not isinstance(d_max, int | float):
        d_max = 2.0 * float(packing.solids.circumradius[packing.placed].max(initial=0.0))
    name = str(scene3d.get("name", "packing"))
    scene: dict[str, Any] = {
        "name": f"{name}-slice",
        "seed": packing.seed,
        "domain": domain.to_dict(),
        "slice": {
            "of": name,
            "axis": cfg.axis,
            "at": at,
            "solids": [row[1] for row in rows],
        },
    }
    if isinstance(scene3d.get("density"), dict):
        scene["density"] = dict(scene3d["density"])
    if "length_unit" in scene3d:
        scene["length_unit"] = scene3d["length_unit"]
    return Packing(
        radius=np.sqrt(area / np.pi),
        mineral=packing.mineral[[row[1] for row in rows]].astype(np.int64).reshape(n),
        mineral_names=packing.mineral_names,
        vertices=np.concatenate(outlines) if n else np.zeros((0, 2)),
        offsets=offsets,
        orientation=np.zeros(n),
        centre=np.array([row[4] for row in rows]).reshape(n, 2),
        insertion_index=np.arange(n, dtype=np.int64),
        domain=domain,
        scene=scene,
        seed=packing.seed,
        version=packing.version,
        stats={
            "interior_margin": float(d_max),
            # the 3D d_min, not the smallest cut, scales the section's default lengths
            "reference_diameter": reference_diameter(packing),
            "slice_axis": float(axis),
            "slice_at": at,
            "slice_phi": float(area.sum() / domain.area),
        },
    )


def _draw(packing: Packing[Box], axis: int, at: float, path: Path) -> None:
    from matplotlib.figure import Figure

    from regopack.packing.drawing import draw_section

    fig = Figure(figsize=(7.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    draw_section(packing, ax, axis, at)
    ax.set_title(f"{packing.scene.get('name', 'packing')}: section {AXES[axis]} = {at:g}")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=150, bbox_inches="tight")
    write_bytes(path, buf.getvalue())


class SliceExporter(Exporter[Packing[Box]]):
    """A section of a 3D packing as a 2D packing file (``.slice.npz``) and its picture.

    See the module's documentation for what the 2D packing holds. The
    picture ``<stem>.png`` (with ``image = true``) draws the cuts by
    mineral, as :func:`regopack.packing.drawing.draw_section` does.
    """

    suffix = ".slice.npz"

    def __init__(self, config: SliceConfig | None = None) -> None:
        self.config = config or SliceConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the picture written beside the section, when there is one."""
        return (image_path(path),) if self.config.image else ()

    def export(
        self, packing: Packing[Box], path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the 2D packing (and the picture); return the packing file's path."""
        path = Path(path)
        section = slice_packing(packing, self.config)
        try:
            save(section, path)
        except OSError as err:
            raise ExportError(f"cannot write {path}: {err.strerror or type(err).__name__}") from err
        if self.config.image:
            axis, at = _plane(packing, self.config)
            _draw(packing, axis, at, image_path(path))
        return path
