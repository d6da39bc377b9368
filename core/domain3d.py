"""Three-dimensional packing domains: the walled box and the periodic box.

They answer the questions of :class:`regopack.domain.Domain` in three
dimensions: volume and bounding box, the interior window at a distance from
the walls, which points lie inside, and how the domain is written to a
packing file (:meth:`Box.to_dict`, :func:`domain3d_from_dict`).

A cylinder container is not offered: the available-surface inserter clips
centres by boxes, and a curved wall would need its own exact clipping.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.errors import GeometryError

__all__ = ["DOMAIN3D_KINDS", "Box", "PeriodicBox", "domain3d_from_dict"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Box:
    """Axis-aligned box with rigid walls.

    Parameters
    ----------
    xmin, xmax, ymin, ymax, zmin, zmax
        Wall positions (any length unit; micrometres by convention).
    """

    kind: ClassVar[str] = "box"
    periodic: ClassVar[bool] = False
    """True when particles wrap around the faces instead of meeting walls."""
    dimension: ClassVar[int] = 3

    xmin: float
    xmax: float
    ymin: float
    ymax: float
    zmin: float
    zmax: float

    def __post_init__(self) -> None:
        b = self.bounds()
        if not np.isfinite(b).all():
            raise GeometryError(f"box bounds {b.tolist()} must be finite")
        if not (self.xmin < self.xmax and self.ymin < self.ymax and self.zmin < self.zmax):
            raise GeometryError(
                f"box bounds {b.tolist()} must be [xmin, xmax, ymin, ymax, zmin, zmax] "
                "with every min below its max"
            )

    @classmethod
    def centred(
        cls,
        width: float,
        height: float,
        depth: float,
        center: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> Self:
        """Build the box (of this class) of the given size around ``center``.

        ``width`` is along x, ``depth`` along y and ``height`` along z, the
        vertical: packings grow from the bottom wall ``z = zmin``.
        """
        cx, cy, cz = center
        return cls(
            cx - width / 2, cx + width / 2, cy - depth / 2, cy + depth / 2,
            cz - height / 2, cz + height / 2,
        )  # fmt: skip

    @property
    def size(self) -> tuple[float, float, float]:
        """Extents ``(x, y, z)``."""
        return (self.xmax - self.xmin, self.ymax - self.ymin, self.zmax - self.zmin)

    @property
    def volume(self) -> float:
        """Volume of the domain."""
        sx, sy, sz = self.size
        return sx * sy * sz

    @property
    def center(self) -> tuple[float, float, float]:
        """Centre point of the domain."""
        return (
            0.5 * (self.xmin + self.xmax),
            0.5 * (self.ymin + self.ymax),
            0.5 * (self.zmin + self.zmax),
        )

    def bounds(self) -> FloatArray:
        """Return ``[xmin, xmax, ymin, ymax, zmin, zmax]`` as a float array."""
        return np.array(
            [self.xmin, self.xmax, self.ymin, self.ymax, self.zmin, self.zmax], dtype=np.float64
        )

    def interior(self, margin: float) -> Box:
        """Return the box inset by ``margin`` from every wall.

        An inset larger than half a side collapses that side to the centre (a
        window of zero volume).
        """
        c = self.center
        half = [max(0.0, s / 2 - margin) for s in self.size]
        lo = [c[a] - half[a] for a in range(3)]
        hi = [c[a] + half[a] for a in range(3)]
        return _Window(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the ``(n, 3)`` points strictly inside the box (NaN is outside)."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        lo = np.array([self.xmin, self.ymin, self.zmin])
        hi = np.array([self.xmax, self.ymax, self.zmax])
        with np.errstate(invalid="ignore"):
            out = np.asarray(((c > lo) & (c < hi)).all(axis=1), dtype=np.bool_)
        return out

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": ..., "bounds": [xmin, xmax, ymin, ymax, zmin, zmax]}``."""
        return {"kind": self.kind, "bounds": [float(v) for v in self.bounds()]}


@dataclass(frozen=True)
class _Window(Box):
    """An interior window: a box that may have zero extent along some axes."""

    def __post_init__(self) -> None:
        b = self.bounds()
        if not np.isfinite(b).all() or not (
            self.xmin <= self.xmax and self.ymin <= self.ymax and self.zmin <= self.zmax
        ):
            raise GeometryError(f"window bounds {b.tolist()} are not a box")


@dataclass(frozen=True)
class PeriodicBox(Box):
    """Axis-aligned box whose opposite faces are identified (no walls).

    A particle's centre lies in ``[xmin, xmax) x [ymin, ymax) x [zmin, zmax)``;
    its solid may cross a face and continue on the opposite one.
    """

    kind: ClassVar[str] = "periodic-box"
    periodic: ClassVar[bool] = True

    @property
    def period(self) -> tuple[float, float, float]:
        """Lengths of the three periods."""
        return self.size

    def interior(self, margin: float) -> Box:
        """Return the whole domain: there are no walls to keep away from."""
        return self

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the finite points (every point lies in some periodic image)."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return np.asarray(np.isfinite(c).all(axis=1), dtype=np.bool_)

    def wrap(self, points: ArrayLike) -> FloatArray:
        """Map points into the box's half-open cell."""
        c = np.array(points, dtype=np.float64).reshape(-1, 3)
        lo = np.array([self.xmin, self.ymin, self.zmin])
        period = np.array(self.period)
        c = lo + np.mod(c - lo, period)
        out: FloatArray = np.where(c >= lo + period, lo, c)  # rounding of mod at the upper face
        return out

    def minimum_image(self, delta: ArrayLike) -> FloatArray:
        """Return the shortest periodic image of the displacements ``delta`` (``(n, 3)``)."""
        d = np.array(delta, dtype=np.float64).reshape(-1, 3)
        period = np.array(self.period)
        out: FloatArray = d - period * np.round(d / period)
        return out


DOMAIN3D_KINDS: dict[str, type[Box]] = {"box": Box, "periodic-box": PeriodicBox}
"""The 3D domain classes by the ``kind`` written in scenes and packing files."""


def domain3d_from_dict(data: Mapping[str, Any]) -> Box:
    """Rebuild a 3D domain written by :meth:`Box.to_dict`.

    Raises
    ------
    KeyError, TypeError, ValueError, GeometryError
        When the record is incomplete or malformed, or describes no valid box.
    """
    kind = data.get("kind")
    cls = DOMAIN3D_KINDS.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise ValueError(f"unknown 3D domain kind {kind!r}; known: {', '.join(DOMAIN3D_KINDS)}")
    bounds = data["bounds"]
    if not isinstance(bounds, list | tuple) or len(bounds) != 6:
        raise ValueError("bounds must be [xmin, xmax, ymin, ymax, zmin, zmax]")
    values = []
    for b in bounds:
        if isinstance(b, bool | str | bytes) or b is None:
            raise TypeError(f"bounds: {b!r} is not a number")
        try:
            v = float(b)
        except OverflowError:
            v = math.inf
        if not math.isfinite(v):
            raise ValueError(f"bounds: {v} is not finite")
        values.append(v)
    return cls(*values)
