"""Packing domains in two and three dimensions: one family.

Every :class:`Domain` answers the same questions whatever its dimension: its
measure (area or volume) and bounding box, the window of its interior at a
given distance from the walls, which points lie inside, and how it is written
to a packing file (:meth:`Domain.to_dict`, :func:`domain_from_dict`).

In the plane (:class:`PlaneDomain`): walled rectangles, convex polygons and
circles, and periodic rectangles; they also give their outline and the area
of polygons that lies inside them. In space: the walled :class:`Box` and the
:class:`PeriodicBox`, and the walled :class:`Cylinder` (a vertical axis, a
side wall, a floor and a lid: the container of a triaxial or oedometer
specimen).

A periodic domain (:class:`PeriodicDomain`) has no walls: particles may cross
its sides and continue on the opposite side. Its interior window is the whole
domain.
"""

from __future__ import annotations

import itertools
import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, Self, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack._compat import warn_moved
from regopack.base.errors import GeometryError

__all__ = [
    "DOMAIN_KINDS",
    "Box",
    "Circle",
    "ConvexPolygon",
    "Cylinder",
    "Domain",
    "PeriodicBox",
    "PeriodicDomain",
    "PeriodicRectangle",
    "PlaneDomain",
    "Rectangle",
    "domain_from_dict",
    "polygon_disk_area",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class Domain(ABC):
    """A container for a packing, in the plane or in space."""

    dimension: ClassVar[int]
    """2 for a domain in the plane, 3 for one in space."""
    kind: ClassVar[str] = ""
    """Name of the domain in scenes and packing files (a key of :data:`DOMAIN_KINDS`)."""
    periodic: ClassVar[bool] = False
    """True when particles wrap around the sides instead of meeting walls."""

    @property
    @abstractmethod
    def measure(self) -> float:
        """Area (in the plane) or volume (in space) of the domain."""

    @abstractmethod
    def bounds(self) -> FloatArray:
        """Bounding box ``[xmin, xmax, ymin, ymax]`` (and ``zmin, zmax`` in 3D) as a float array."""

    @property
    def center(self) -> tuple[float, ...]:
        """Centre point of the domain (the bounding box's, unless the kind says otherwise)."""
        b = self.bounds()
        return tuple(0.5 * float(b[2 * a] + b[2 * a + 1]) for a in range(self.dimension))

    @abstractmethod
    def interior(self, margin: float) -> Domain:
        """Return the window of points farther than ``margin`` from every wall.

        An empty window has zero measure. A periodic domain has no walls and
        returns itself.
        """

    @abstractmethod
    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the ``(n, dimension)`` points strictly inside the domain (NaN is outside)."""

    @abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """Return the domain as plain data, read back by :func:`domain_from_dict`."""


class PlaneDomain(Domain):
    """A container in the plane.

    Besides the questions of every :class:`Domain`, it gives its outline and
    the area of a set of polygons that lies inside it.
    """

    dimension: ClassVar[int] = 2

    @property
    @abstractmethod
    def area(self) -> float:
        """Area of the domain."""

    @property
    def measure(self) -> float:
        """Area of the domain (:attr:`area`)."""
        return self.area

    @property
    def center(self) -> tuple[float, float]:
        """Centre point of the domain (centre of the box, polygon centroid, circle centre)."""
        x, y = super().center
        return (x, y)

    @property
    def width(self) -> float:
        """Extent of the bounding box along x."""
        b = self.bounds()
        return float(b[1] - b[0])

    @property
    def height(self) -> float:
        """Extent of the bounding box along y."""
        b = self.bounds()
        return float(b[3] - b[2])

    @abstractmethod
    def interior(self, margin: float) -> PlaneDomain:
        """Return the window farther than ``margin`` from every wall (:meth:`Domain.interior`)."""

    @abstractmethod
    def outline(self) -> FloatArray:
        """``(k, 2)`` counter-clockwise boundary for drawing (a circle as a fine polygon)."""

    def covered_area(self, geoms: NDArray[np.object_]) -> float:
        """Total area of the shapely polygons ``geoms`` that lies inside the domain."""
        return self.add_parts(self.covered_parts(geoms))

    def covered_parts(self, geoms: NDArray[np.object_]) -> list[FloatArray]:
        """Area inside the domain of each of ``geoms``, in groups that :meth:`add_parts` sums.

        The groups keep the order of ``geoms``, so the parts of consecutive
        batches, joined group by group, sum to the area of the whole set
        exactly as :meth:`covered_area` of the whole set would.
        """
        import shapely

        if len(geoms) == 0:
            return [np.zeros(0), np.zeros(0)]
        window = shapely.Polygon(self.outline())
        inside = shapely.contains_properly(window, geoms)
        rest = ~inside
        clipped = shapely.area(shapely.intersection(geoms[rest], window)) if rest.any() else []
        return [
            np.asarray(shapely.area(geoms[inside]), dtype=np.float64),
            np.asarray(clipped, dtype=np.float64),
        ]

    def add_parts(self, parts: list[FloatArray]) -> float:
        """Sum the groups of :meth:`covered_parts`: each group as an array, then in order."""
        total = 0.0
        for part in parts:
            total += float(part.sum())
        return total


class PeriodicDomain(Domain):
    """A domain whose opposite sides are identified: no walls, and positions wrap.

    The base of :class:`PeriodicRectangle` and :class:`PeriodicBox`. A
    particle's centre lies in the half-open cell ``[xmin, xmax) x [ymin,
    ymax)`` (``x [zmin, zmax)`` in 3D); its outline may cross a side and
    continue on the opposite one.
    """

    periodic: ClassVar[bool] = True

    @property
    def period(self) -> tuple[float, ...]:
        """Lengths of the periods, one per axis: ``(Lx, Ly)`` or ``(Lx, Ly, Lz)``."""
        b = self.bounds()
        return tuple(float(b[2 * a + 1] - b[2 * a]) for a in range(self.dimension))

    def interior(self, margin: float) -> Self:
        """Return the whole domain: there are no walls to keep away from."""
        return self

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the finite points (every point lies in some periodic image)."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, self.dimension)
        return np.asarray(np.isfinite(c).all(axis=1), dtype=np.bool_)

    def wrap(self, points: ArrayLike) -> FloatArray:
        """Map the ``(n, dimension)`` points into the half-open cell."""
        c = np.array(points, dtype=np.float64).reshape(-1, self.dimension)
        lo = self.bounds()[0::2]
        period = np.array(self.period)
        c = lo + np.mod(c - lo, period)
        out: FloatArray = np.where(c >= lo + period, lo, c)  # rounding of mod at the upper side
        return out

    def minimum_image(self, delta: ArrayLike) -> FloatArray:
        """Return the shortest periodic image of the ``(n, dimension)`` displacements ``delta``."""
        d = np.array(delta, dtype=np.float64).reshape(-1, self.dimension)
        period = np.array(self.period)
        out: FloatArray = d - period * np.round(d / period)
        return out


@dataclass(frozen=True)
class Rectangle(PlaneDomain):
    """Axis-aligned rectangular domain with rigid walls.

    Parameters
    ----------
    xmin, xmax, ymin, ymax
        Wall positions (any length unit; micrometres by convention).
    """

    kind: ClassVar[str] = "rectangle"

    xmin: float
    xmax: float
    ymin: float
    ymax: float

    @classmethod
    def centred(cls, width: float, height: float, center: tuple[float, float] = (0.0, 0.0)) -> Self:
        """Build the rectangle (of this class) of the given size around ``center``."""
        cx, cy = center
        return cls(cx - width / 2, cx + width / 2, cy - height / 2, cy + height / 2)

    @property
    def width(self) -> float:
        """Extent along x."""
        return self.xmax - self.xmin

    @property
    def height(self) -> float:
        """Extent along y."""
        return self.ymax - self.ymin

    @property
    def area(self) -> float:
        """Area of the domain."""
        return self.width * self.height

    @property
    def center(self) -> tuple[float, float]:
        """Centre point of the domain."""
        return (0.5 * (self.xmin + self.xmax), 0.5 * (self.ymin + self.ymax))

    def bounds(self) -> FloatArray:
        """Return ``[xmin, xmax, ymin, ymax]`` as a float array."""
        return np.array([self.xmin, self.xmax, self.ymin, self.ymax], dtype=np.float64)

    def shrunk(self, margin: float) -> Rectangle:
        """Return the window inset by ``margin`` from every wall (empty windows are clamped)."""
        cx, cy = self.center
        hw = max(0.0, self.width / 2 - margin)
        hh = max(0.0, self.height / 2 - margin)
        return Rectangle(cx - hw, cx + hw, cy - hh, cy + hh)

    def interior(self, margin: float) -> Rectangle:
        """Return the rectangle inset by ``margin`` (see :meth:`shrunk`)."""
        return self.shrunk(margin)

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the points strictly inside the rectangle."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        with np.errstate(invalid="ignore"):
            out: BoolArray = (
                (c[:, 0] > self.xmin)
                & (c[:, 0] < self.xmax)
                & (c[:, 1] > self.ymin)
                & (c[:, 1] < self.ymax)
            )
        return out

    def outline(self) -> FloatArray:
        """Return the four corners, counter-clockwise from ``(xmin, ymin)``."""
        return np.array(
            [
                [self.xmin, self.ymin],
                [self.xmax, self.ymin],
                [self.xmax, self.ymax],
                [self.xmin, self.ymax],
            ],
            dtype=np.float64,
        )

    def covered_parts(self, geoms: NDArray[np.object_]) -> list[FloatArray]:
        """Area of ``geoms`` inside the rectangle, by exact clipping (see :class:`PlaneDomain`)."""
        import shapely

        if len(geoms) == 0:
            return [np.zeros(0), np.zeros(0)]
        b = shapely.bounds(geoms)
        inside = (
            (b[:, 0] >= self.xmin)
            & (b[:, 2] <= self.xmax)
            & (b[:, 1] >= self.ymin)
            & (b[:, 3] <= self.ymax)
        )
        away = (
            (b[:, 2] <= self.xmin)
            | (b[:, 0] >= self.xmax)
            | (b[:, 3] <= self.ymin)
            | (b[:, 1] >= self.ymax)
        )
        straddling = ~inside & ~away
        clipped: FloatArray = np.zeros(0)
        if straddling.any():
            box = shapely.box(self.xmin, self.ymin, self.xmax, self.ymax)
            clipped = shapely.area(shapely.intersection(geoms[straddling], box))
        return [np.asarray(shapely.area(geoms[inside]), dtype=np.float64), clipped]

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "rectangle", "bounds": [xmin, xmax, ymin, ymax]}``."""
        return {"kind": self.kind, "bounds": [self.xmin, self.xmax, self.ymin, self.ymax]}


@dataclass(frozen=True)
class PeriodicRectangle(PeriodicDomain, Rectangle):
    """Axis-aligned rectangle whose opposite sides are identified (no walls).

    A particle's centre lies in ``[xmin, xmax) x [ymin, ymax)``; its outline
    may cross a side and continue on the opposite one.
    """

    kind: ClassVar[str] = "periodic"

    def covered_parts(self, geoms: NDArray[np.object_]) -> list[FloatArray]:
        """Area of each of ``geoms``: every part of a particle lies in the torus once."""
        import shapely

        return [np.asarray(shapely.area(geoms), dtype=np.float64) if len(geoms) else np.zeros(0)]


@dataclass(frozen=True)
class ConvexPolygon(PlaneDomain):
    """Convex polygonal container with rigid walls.

    Parameters
    ----------
    vertices
        Corners in order (either orientation; stored counter-clockwise).

    Raises
    ------
    GeometryError
        When the corners are not finite, fewer than three, or not a strictly
        convex polygon of positive area.
    """

    kind: ClassVar[str] = "polygon"

    vertices: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 2)
        check_convex_polygon(v)
        if _signed_area(v) < 0:
            v = v[::-1]
        object.__setattr__(self, "vertices", tuple((float(x), float(y)) for x, y in v))

    @property
    def array(self) -> FloatArray:
        """The corners as an ``(k, 2)`` counter-clockwise array."""
        return np.asarray(self.vertices, dtype=np.float64)

    @property
    def area(self) -> float:
        """Area of the polygon."""
        return _signed_area(self.array)

    @property
    def center(self) -> tuple[float, float]:
        """Centroid of the polygon."""
        v = self.array
        w = np.roll(v, -1, axis=0)
        cross = v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]
        a = 3.0 * cross.sum()
        return (
            float(((v[:, 0] + w[:, 0]) * cross).sum() / a),
            float(((v[:, 1] + w[:, 1]) * cross).sum() / a),
        )

    def bounds(self) -> FloatArray:
        """Bounding box ``[xmin, xmax, ymin, ymax]``."""
        v = self.array
        return np.array([v[:, 0].min(), v[:, 0].max(), v[:, 1].min(), v[:, 1].max()])

    def halfplanes(self) -> tuple[FloatArray, FloatArray]:
        """Outward unit normals ``(k, 2)`` and offsets ``(k,)``: inside is ``n . x <= b``."""
        v = self.array
        e = np.roll(v, -1, axis=0) - v
        normal = np.column_stack([e[:, 1], -e[:, 0]])
        normal /= np.hypot(normal[:, 0], normal[:, 1])[:, None]
        offset = np.einsum("ij,ij->i", normal, v)
        return normal, offset

    def interior(self, margin: float) -> PlaneDomain:
        """Return the polygon with every wall moved inward by ``margin`` (mitred, exact)."""
        import shapely

        inset = shapely.Polygon(self.array).buffer(
            -float(margin), join_style="mitre", mitre_limit=1e6
        )
        if inset.is_empty or inset.area <= 0 or inset.geom_type != "Polygon":
            return _empty_window(self.center)
        ring = np.asarray(inset.exterior.coords)[:-1]
        try:
            return ConvexPolygon(tuple(map(tuple, ring)))
        except GeometryError:
            return _empty_window(self.center)

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the points strictly inside every wall."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        normal, offset = self.halfplanes()
        with np.errstate(invalid="ignore"):
            out: BoolArray = np.all(c @ normal.T < offset, axis=1)
        return out

    def outline(self) -> FloatArray:
        """Return the corners, counter-clockwise."""
        return self.array

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "polygon", "vertices": [[x, y], ...]}``."""
        return {"kind": self.kind, "vertices": [list(p) for p in self.vertices]}


@dataclass(frozen=True)
class Circle(PlaneDomain):
    """Circular container with a rigid wall.

    Parameters
    ----------
    cx, cy
        Centre.
    radius
        Radius of the wall.
    """

    kind: ClassVar[str] = "circle"

    cx: float
    cy: float
    radius: float

    OUTLINE_POINTS: ClassVar[int] = 512

    @property
    def area(self) -> float:
        """Area of the disk."""
        return math.pi * self.radius * self.radius

    @property
    def center(self) -> tuple[float, float]:
        """Centre of the circle."""
        return (self.cx, self.cy)

    def bounds(self) -> FloatArray:
        """Bounding box of the disk."""
        r = self.radius
        return np.array([self.cx - r, self.cx + r, self.cy - r, self.cy + r])

    def interior(self, margin: float) -> Circle:
        """Return the concentric disk of radius ``radius - margin`` (zero when negative)."""
        return Circle(self.cx, self.cy, max(0.0, self.radius - float(margin)))

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the points strictly inside the circle."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        with np.errstate(invalid="ignore"):
            out: BoolArray = np.hypot(c[:, 0] - self.cx, c[:, 1] - self.cy) < self.radius
        return out

    def outline(self) -> FloatArray:
        """Return :attr:`OUTLINE_POINTS` corners on the circle, for drawing."""
        t = np.linspace(0.0, 2.0 * math.pi, self.OUTLINE_POINTS, endpoint=False)
        return np.column_stack(
            [self.cx + self.radius * np.cos(t), self.cy + self.radius * np.sin(t)]
        )

    def covered_parts(self, geoms: NDArray[np.object_]) -> list[FloatArray]:
        """Area of each of ``geoms`` inside the disk, by exact polygon-disk intersection."""
        import shapely

        if len(geoms) == 0 or self.radius <= 0:
            return [np.zeros(0)]
        areas = np.empty(len(geoms))
        for j, g in enumerate(geoms):
            ring = np.asarray(shapely.get_exterior_ring(g).coords)[:-1]
            areas[j] = polygon_disk_area(ring, (self.cx, self.cy), self.radius)
        return [areas]

    def add_parts(self, parts: list[FloatArray]) -> float:
        """Sum the areas one by one, in order."""
        total = 0.0
        for part in parts:
            for value in part.tolist():
                total += value
        return total

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "circle", "center": [x, y], "radius": r}``."""
        return {"kind": self.kind, "center": [self.cx, self.cy], "radius": self.radius}


def _empty_window(c: tuple[float, float]) -> Rectangle:
    """Return a window of zero area at ``c`` (a domain narrower than twice the margin)."""
    return Rectangle(c[0], c[0], c[1], c[1])


@dataclass(frozen=True)
class Box(Domain):
    """Axis-aligned box with rigid walls.

    Parameters
    ----------
    xmin, xmax, ymin, ymax, zmin, zmax
        Wall positions (any length unit; micrometres by convention).

    Raises
    ------
    GeometryError
        When a wall position is not finite or a min is not below its max.
    """

    dimension: ClassVar[int] = 3
    kind: ClassVar[str] = "box"

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
    def measure(self) -> float:
        """Volume of the domain (:attr:`volume`)."""
        return self.volume

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
class PeriodicBox(PeriodicDomain, Box):
    """Axis-aligned box whose opposite faces are identified (no walls).

    A particle's centre lies in ``[xmin, xmax) x [ymin, ymax) x [zmin, zmax)``;
    its solid may cross a face and continue on the opposite one.
    """

    kind: ClassVar[str] = "periodic-box"


@dataclass(frozen=True)
class Cylinder(Domain):
    """Walled cylinder with a vertical axis: a side wall, a floor and a lid.

    Parameters
    ----------
    cx, cy
        Position of the axis (parallel to z).
    radius
        Radius of the side wall.
    zmin, zmax
        Heights of the floor and the lid.

    Raises
    ------
    GeometryError
        When a value is not finite, the radius is not positive or the floor
        is not below the lid.
    """

    dimension: ClassVar[int] = 3
    kind: ClassVar[str] = "cylinder"

    cx: float
    cy: float
    radius: float
    zmin: float
    zmax: float

    def __post_init__(self) -> None:
        values = [self.cx, self.cy, self.radius, self.zmin, self.zmax]
        if not all(math.isfinite(v) for v in values):
            raise GeometryError(f"cylinder {values} must be finite")
        self._check_extent()

    def _check_extent(self) -> None:
        if not (self.radius > 0 and self.zmin < self.zmax):
            raise GeometryError(
                f"cylinder of radius {self.radius:g} from z = {self.zmin:g} to {self.zmax:g}: "
                "the radius must be > 0 and the floor below the lid"
            )

    @classmethod
    def centred(
        cls, radius: float, height: float, center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ) -> Self:
        """Build the cylinder of this ``radius`` and ``height`` about its middle ``center``."""
        cx, cy, cz = center
        return cls(cx, cy, radius, cz - height / 2, cz + height / 2)

    @property
    def height(self) -> float:
        """Distance from the floor to the lid."""
        return self.zmax - self.zmin

    @property
    def size(self) -> tuple[float, float, float]:
        """Extents ``(x, y, z)`` of the bounding box."""
        return (2.0 * self.radius, 2.0 * self.radius, self.height)

    @property
    def volume(self) -> float:
        """Volume of the cylinder."""
        return math.pi * self.radius * self.radius * self.height

    @property
    def measure(self) -> float:
        """Volume of the domain (:attr:`volume`)."""
        return self.volume

    @property
    def center(self) -> tuple[float, float, float]:
        """Middle of the axis."""
        return (self.cx, self.cy, 0.5 * (self.zmin + self.zmax))

    def bounds(self) -> FloatArray:
        """Bounding box ``[xmin, xmax, ymin, ymax, zmin, zmax]``."""
        r = self.radius
        return np.array(
            [self.cx - r, self.cx + r, self.cy - r, self.cy + r, self.zmin, self.zmax],
            dtype=np.float64,
        )

    def interior(self, margin: float) -> Cylinder:
        """Return the coaxial cylinder farther than ``margin`` from the side, floor and lid.

        An inset larger than the radius or half the height collapses the
        window (zero volume).
        """
        m = float(margin)
        cz = 0.5 * (self.zmin + self.zmax)
        half = max(0.0, 0.5 * self.height - m)
        return _CylinderWindow(self.cx, self.cy, max(0.0, self.radius - m), cz - half, cz + half)

    def contains(self, points: ArrayLike) -> BoolArray:
        """Mask of the ``(n, 3)`` points strictly inside the cylinder (NaN is outside)."""
        c = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        with np.errstate(invalid="ignore"):
            out = np.asarray(
                (np.hypot(c[:, 0] - self.cx, c[:, 1] - self.cy) < self.radius)
                & (c[:, 2] > self.zmin)
                & (c[:, 2] < self.zmax),
                dtype=np.bool_,
            )
        return out

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "cylinder", "axis": [x, y], "radius": r, "z": [zmin, zmax]}``."""
        return {
            "kind": self.kind,
            "axis": [float(self.cx), float(self.cy)],
            "radius": float(self.radius),
            "z": [float(self.zmin), float(self.zmax)],
        }


@dataclass(frozen=True)
class _CylinderWindow(Cylinder):
    """An interior window: a cylinder that may have zero radius or height."""

    def _check_extent(self) -> None:
        if not (self.radius >= 0 and self.zmin <= self.zmax):
            raise GeometryError(f"window {self.to_dict()} is not a cylinder")


DOMAIN_KINDS: dict[str, type[Domain]] = {
    "rectangle": Rectangle,
    "polygon": ConvexPolygon,
    "circle": Circle,
    "periodic": PeriodicRectangle,
    "box": Box,
    "periodic-box": PeriodicBox,
    "cylinder": Cylinder,
}
"""Domain classes by the ``kind`` written in scenes and packing files (both dimensions)."""


@overload
def domain_from_dict(data: Mapping[str, Any], dimension: Literal[2]) -> PlaneDomain: ...
@overload
def domain_from_dict(data: Mapping[str, Any], dimension: Literal[3]) -> Box | Cylinder: ...
@overload
def domain_from_dict(data: Mapping[str, Any], dimension: int | None = None) -> Domain: ...
def domain_from_dict(data: Mapping[str, Any], dimension: int | None = None) -> Domain:
    """Rebuild a domain written by :meth:`Domain.to_dict`.

    The record is checked as the scene's ``[domain]`` is: finite numbers, the
    bounds of a rectangle or box in increasing order (a positive extent along
    every axis), a circle's radius positive, a polygon's corners strictly
    convex.

    Parameters
    ----------
    data
        The record: its ``kind`` (a record without one is a rectangle) and
        the fields of that kind.
    dimension
        2 or 3 to refuse a domain of the other dimension (a box in a 2D
        packing's file, say); ``None`` reads every kind.

    Raises
    ------
    KeyError, TypeError, ValueError, GeometryError
        When the record is incomplete or malformed, or describes no valid domain.
    """
    kind = data.get("kind", "rectangle")
    cls = DOMAIN_KINDS.get(kind) if isinstance(kind, str) else None
    known = [k for k, c in DOMAIN_KINDS.items() if dimension in (None, c.dimension)]
    if cls is None:
        raise ValueError(f"unknown domain kind {kind!r}; known: {', '.join(known)}")
    if dimension not in (None, cls.dimension):
        raise ValueError(
            f"{kind!r} is a {cls.dimension}D domain kind, not {dimension}D; "
            f"{dimension}D kinds: {', '.join(known)}"
        )
    if cls is ConvexPolygon:
        return ConvexPolygon(tuple((float(x), float(y)) for x, y in data["vertices"]))
    if cls is Cylinder:
        cx, cy = _pair(data["axis"], "axis")
        zmin, zmax = _pair(data["z"], "z")
        radius = _finite(data["radius"], "radius")
        if radius <= 0:
            raise GeometryError(f"radius {radius:g} must be > 0")
        if not zmin < zmax:
            raise GeometryError(f"z [{zmin:g}, {zmax:g}] must be [zmin, zmax] with zmin < zmax")
        return Cylinder(cx, cy, radius, zmin, zmax)
    if cls is Circle:
        cx, cy = (_finite(c, "center") for c in data["center"])
        radius = _finite(data["radius"], "radius")
        if radius <= 0:
            raise GeometryError(f"radius {radius:g} must be > 0")
        return Circle(cx, cy, radius)
    return cls(*_bounds(data["bounds"], cls.dimension))


def _bounds(values: Any, dimension: int) -> list[float]:
    """Return a record's ``bounds``: ``2 * dimension`` finite numbers, each min below its max."""
    if isinstance(values, str | bytes | Mapping) or not isinstance(values, Iterable):
        raise TypeError(f"bounds: {values!r} is not a list of numbers")
    bounds = [_finite(b, "bounds") for b in values]
    axes = "xyz"[:dimension]
    names = ", ".join(f"{a}min, {a}max" for a in axes)
    if len(bounds) != 2 * dimension:
        raise ValueError(f"bounds must be [{names}]")
    if not all(bounds[2 * a] < bounds[2 * a + 1] for a in range(dimension)):
        shown = ", ".join(f"{b:g}" for b in bounds)
        order = " and ".join(f"{a}min < {a}max" for a in axes)
        raise GeometryError(f"bounds [{shown}] must be [{names}] with {order}")
    return bounds


def _pair(values: Any, what: str) -> tuple[float, float]:
    """Return a record's two finite numbers named ``what``."""
    if isinstance(values, str | bytes | Mapping) or not isinstance(values, Iterable):
        raise TypeError(f"{what}: {values!r} is not a list of two numbers")
    pair = [_finite(v, what) for v in values]
    if len(pair) != 2:
        raise ValueError(f"{what} must be two numbers, not {len(pair)}")
    return pair[0], pair[1]


def _finite(value: Any, what: str) -> float:
    """Return ``value`` as a finite float; a string, boolean or non-finite number is refused."""
    if isinstance(value, bool | str | bytes) or value is None:
        raise TypeError(f"{what}: {value!r} is not a number")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond the floats
        number = math.inf
    if not math.isfinite(number):
        raise ValueError(f"{what}: {number} is not finite")
    return number


def _signed_area(v: FloatArray) -> float:
    w = np.roll(v, -1, axis=0)
    return 0.5 * float(np.sum(v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]))


def check_convex_polygon(v: FloatArray) -> None:
    """Raise :class:`GeometryError` unless ``v`` is a strictly convex polygon of positive area.

    Collinear corners and repeated corners are rejected, so that every corner
    is a proper turn of the boundary.
    """
    if v.ndim != 2 or v.shape[0] < 3 or not np.all(np.isfinite(v)):
        raise GeometryError("a polygon needs at least 3 finite corners")
    with np.errstate(over="ignore", invalid="ignore"):
        e = np.roll(v, -1, axis=0) - v
        f = np.roll(e, -1, axis=0)
        cross = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    spread = float(np.max(np.abs(v - v.mean(axis=0))))
    scale = spread * spread
    if not (math.isfinite(scale) and np.all(np.isfinite(cross))):
        raise GeometryError(
            "the corners are so far apart that the polygon's area overflows 64-bit floats; "
            "give smaller coordinates"
        )
    if scale <= 0 or not (np.all(cross > 1e-12 * scale) or np.all(cross < -1e-12 * scale)):
        raise GeometryError(
            "the corners must form a strictly convex polygon (no repeated, collinear "
            "or reflex corners), listed in order"
        )
    # a star polygon turns the same way at every corner but winds more than once
    turn = np.arctan2(cross, np.einsum("ij,ij->i", e, f))
    if abs(abs(float(turn.sum())) - 2.0 * math.pi) > 1e-6:
        raise GeometryError("the corners must form a simple convex polygon, listed in order")


def polygon_disk_area(ring: ArrayLike, center: Sequence[float], radius: float) -> float:
    """Area of the intersection of a simple polygon with a disk, exactly.

    The polygon is split into triangles with the disk centre; each triangle
    meets the disk in straight pieces (inside) and circular sectors (outside),
    whose signed areas add up.

    Parameters
    ----------
    ring
        ``(k, 2)`` corners of the polygon (either orientation; the result is positive).
    center, radius
        The disk.

    Examples
    --------
    >>> round(polygon_disk_area([(-2, -2), (2, -2), (2, 2), (-2, 2)], (0, 0), 1.0), 12)
    3.141592653590
    """
    v = np.asarray(ring, dtype=np.float64).reshape(-1, 2) - np.asarray(center, dtype=np.float64)
    r2 = radius * radius
    total = 0.0
    k = v.shape[0]
    for j in range(k):
        a = v[j]
        b = v[(j + 1) % k]
        d = b - a
        dd = float(d @ d)
        ts = [0.0]
        misses = False  # the edge's line does not enter the open disk (at most touches it)
        if dd > 0:
            # |a + t d|^2 = r^2
            p = float(a @ d) / dd
            q = (float(a @ a) - r2) / dd
            disc = p * p - q
            if disc > 0:
                s = math.sqrt(disc)
                ts += [t for t in (-p - s, -p + s) if 0.0 < t < 1.0]
            else:
                misses = True
        ts.append(1.0)
        for t0, t1 in itertools.pairwise(ts):
            p0 = a + t0 * d
            p1 = a + t1 * d
            mid = 0.5 * (p0 + p1)
            cross = float(p0[0] * p1[1] - p0[1] * p1[0])
            if not misses and float(mid @ mid) <= r2:
                total += 0.5 * cross
            else:
                total += 0.5 * r2 * math.atan2(cross, float(p0 @ p1))
    return abs(total)


def __getattr__(name: str) -> Any:
    """Names of the former ``regopack.domain3d``, deprecated for one release (PEP 562)."""
    if name == "DOMAIN3D_KINDS":
        warn_moved("regopack.domain3d.DOMAIN3D_KINDS", "regopack.geometry.domain.DOMAIN_KINDS")
        return {k: c for k, c in DOMAIN_KINDS.items() if c.dimension == 3}
    if name == "domain3d_from_dict":
        warn_moved(
            "regopack.domain3d.domain3d_from_dict",
            "regopack.geometry.domain.domain_from_dict(data, 3)",
        )
        return _domain3d_from_dict
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _domain3d_from_dict(data: Mapping[str, Any]) -> Box | Cylinder:
    """Rebuild a 3D domain: ``domain_from_dict(data, 3)``."""
    return domain_from_dict(data, 3)
