"""Shape generators besides the ``octagon``: regular, random convex and template polygons.

Three shapes are registered:

``regular``
    The regular m-gon with a uniformly random orientation.
``random-polygon``
    A random convex m-gon: ``m`` vertices at sorted random polar angles,
    optionally pulled towards the centre by a radial jitter that keeps the
    polygon convex.
``template``
    Outlines read from a file (CSV or JSON), for example measured particle
    contours, convexified when needed, randomly rotated and scaled.

Every outline is counter-clockwise, has no repeated consecutive vertices, lies
around a reference point strictly inside it and has the area ``pi r^2`` of its
particle's equivalent radius ``r``.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError
from regopack.base.toml import not_a_file
from regopack.geometry.population import ShapeBatch
from regopack.plugins.shapes import __all__ as __all__  # public names, listed in the package
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import ShapeGenerator
from regopack.registry.plugin_types import ShapeSpec

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

TWO_PI = 2.0 * math.pi

GAP_MARGIN = 1e-6
"""Angular gaps of ``random-polygon`` are below ``pi (1 - GAP_MARGIN)``."""

MIN_GAP = 1e-6
"""Angular gaps of ``random-polygon`` exceed ``MIN_GAP * 2 pi / m``."""

HULL_TOL = 1e-12
"""Collinearity and degeneracy tolerance of templates, relative to their extent."""

CONVEX_RTOL = 1e-9
"""A template outline whose area differs from its hull's by more than this is not convex."""


# ---------------------------------------------------------------------------
# configuration


class RegularConfig(BaseModel):
    """Parameters of the regular m-gon."""

    model_config = ConfigDict(extra="forbid", strict=True)

    m: int = Field(6, ge=3, le=256, description="Number of vertices m (3 to 256).")


class RandomPolygonConfig(BaseModel):
    """Parameters of the random convex m-gon."""

    model_config = ConfigDict(extra="forbid", strict=True)

    m: int = Field(8, ge=3, le=256, description="Number of vertices m (3 to 256).")
    jitter: float = Field(
        0.0,
        ge=0.0,
        lt=1.0,
        allow_inf_nan=False,
        description=(
            "Radial jitter in [0, 1): each vertex moves towards the centre by up to this "
            "fraction of the room that keeps the polygon convex; 0 keeps every vertex on "
            "the circle."
        ),
    )


class TemplateConfig(BaseModel):
    """Parameters of the template shape."""

    model_config = ConfigDict(extra="forbid", strict=True)

    path: str = Field(
        min_length=1,
        description=(
            "File of outlines: CSV with columns id,x,y or JSON list of [[x, y], ...] lists. "
            "A relative path is resolved against the current directory."
        ),
    )
    choice: Literal["random", "cycle"] = Field(
        "random",
        description=(
            'How each particle picks its outline: "random" (uniformly) or "cycle" '
            "(in file order, starting again after the last)."
        ),
    )


# ---------------------------------------------------------------------------
# helpers


def _batch(x: FloatArray, y: FloatArray, orientation: FloatArray) -> ShapeBatch:
    """Shape batch of ``(n, m)`` vertex coordinates (every particle has ``m`` vertices)."""
    n, m = x.shape
    vertices = np.stack([x.ravel(), y.ravel()], axis=1).astype(np.float64, copy=False)
    offsets = np.arange(0, n * m + 1, m, dtype=np.int64)
    return ShapeBatch(vertices=vertices, offsets=offsets, orientation=orientation)


def _radii(radius: FloatArray) -> FloatArray:
    r = np.asarray(radius, dtype=np.float64)
    if r.ndim != 1:
        raise ValueError(f"radius must be one-dimensional, not of shape {r.shape}")
    return r


# ---------------------------------------------------------------------------
# regular


class RegularPolygon(ShapeGenerator):
    """Regular m-gon of area ``pi r^2`` around its centre.

    The orientation (the polar angle of the first vertex) is uniform in
    ``[0, 2 pi / m)``; one draw per particle.

    Examples
    --------
    >>> import numpy as np
    >>> gen = RegularPolygon(RegularConfig(m=4))
    >>> batch = gen.generate(np.array([1.0, 2.0]), np.random.default_rng(0))
    >>> batch.vertices.shape
    (8, 2)
    """

    def __init__(self, config: RegularConfig) -> None:
        self.config = config

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Draw one outline per radius (random draws: the orientations)."""
        r = _radii(radius)
        m = self.config.m
        n = int(r.shape[0])
        theta0 = rng.random(n) * (TWO_PI / m)
        step = TWO_PI / m
        # circumradius of the regular m-gon of area pi: pi = (m / 2) R^2 sin(2 pi / m)
        circum = math.sqrt(TWO_PI / (m * math.sin(step)))
        ang = theta0[:, None] + step * np.arange(m)
        rho = (r * circum)[:, None]
        return _batch(rho * np.cos(ang), rho * np.sin(ang), theta0)


# ---------------------------------------------------------------------------
# random convex polygon


def _angular_gaps(n: int, m: int, rng: np.random.Generator) -> FloatArray:
    """Uniform random spacings of ``m`` points on the circle, every one below pi.

    A particle whose spacings break the bounds (:data:`GAP_MARGIN`,
    :data:`MIN_GAP`) draws all of them again, in particle order, from ``rng``.
    """
    gaps = np.empty((n, m), dtype=np.float64)
    todo = np.arange(n)
    hi = math.pi * (1.0 - GAP_MARGIN)
    lo = MIN_GAP * TWO_PI / m
    while todo.size:
        e = rng.standard_exponential((todo.size, m))
        g = e * (TWO_PI / e.sum(axis=1, keepdims=True))
        ok = (g.max(axis=1) < hi) & (g.min(axis=1) > lo)
        gaps[todo[ok]] = g[ok]
        todo = todo[~ok]
    return gaps


class RandomConvexPolygon(ShapeGenerator):
    """Random convex m-gon of area ``pi r^2`` around the centre of its circle.

    The ``m`` vertices lie at sorted uniform random polar angles, redrawn for a
    particle until every angular gap is below pi so that the centre lies
    strictly inside. With ``jitter > 0`` vertex ``i`` lies at the distance
    ``1 - jitter * u_i * (1 - h_i)`` from the centre (before scaling), where
    ``u_i`` is uniform in ``[0, 1)`` and ``h_i`` is where the ray through the
    vertex meets the chord between its two neighbours on the unit circle. A
    vertex beyond that chord stays a convex corner whatever its neighbours do,
    so every particle keeps exactly ``m`` vertices.

    Random draws, in order: the orientations (uniform in ``[0, 2 pi)``, the
    polar angle of the first vertex), the angular gaps (with redraws), then,
    when ``jitter > 0``, the ``u_i``.

    Examples
    --------
    >>> import numpy as np
    >>> gen = RandomConvexPolygon(RandomPolygonConfig(m=5, jitter=0.5))
    >>> batch = gen.generate(np.array([1.0, 2.0, 3.0]), np.random.default_rng(0))
    >>> batch.vertices.shape
    (15, 2)
    """

    def __init__(self, config: RandomPolygonConfig) -> None:
        self.config = config

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Draw one outline per radius."""
        r = _radii(radius)
        m = self.config.m
        jitter = self.config.jitter
        n = int(r.shape[0])
        theta0 = rng.random(n) * TWO_PI
        gaps = _angular_gaps(n, m, rng)
        start = np.zeros((n, m), dtype=np.float64)
        np.cumsum(gaps[:, :-1], axis=1, out=start[:, 1:])
        ang = theta0[:, None] + start
        rho = np.ones((n, m), dtype=np.float64)
        if jitter > 0.0:
            before = np.roll(gaps, 1, axis=1)  # gap to the previous vertex
            after = gaps  # gap to the next vertex
            h = np.maximum(np.cos(0.5 * (before + after)), 0.0) / np.cos(0.5 * (after - before))
            rho -= jitter * rng.random((n, m)) * (1.0 - h)
        # area as a sum of positive triangle areas around the centre
        area = 0.5 * np.sum(rho * np.roll(rho, -1, axis=1) * np.sin(gaps), axis=1)
        scale = r * np.sqrt(math.pi / area)
        rho *= scale[:, None]
        return _batch(rho * np.cos(ang), rho * np.sin(ang), theta0)


# ---------------------------------------------------------------------------
# templates


class TemplateError(ConfigError, ValueError):
    """A template file cannot be read or holds an unusable outline."""


class TemplateWarning(UserWarning):
    """Template outlines were replaced by their convex hulls."""


@dataclass(frozen=True)
class Template:
    """Outlines of a template file, normalised.

    Attributes
    ----------
    ids
        Identifier of each outline (the CSV ``id``, or the position in a JSON list).
    vertices
        ``(M, 2)`` counter-clockwise vertices of all outlines, each outline with
        its centroid at the origin and the area 1.
    offsets
        ``(k + 1,)`` outline ``j`` is ``vertices[offsets[j]:offsets[j + 1]]``.
    n_convexified
        Number of outlines that were not convex and were replaced by their hulls.
    """

    ids: tuple[str, ...]
    vertices: FloatArray
    offsets: IntArray
    n_convexified: int

    def __len__(self) -> int:
        return len(self.ids)

    def outline(self, j: int) -> FloatArray:
        """Normalised vertices of outline ``j``."""
        return self.vertices[self.offsets[j] : self.offsets[j + 1]]


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split())


def _number(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text.strip()!r} is not finite")
    return value


def _read_csv(name: str, text: str) -> list[tuple[str, list[tuple[float, float]]]]:
    rows = [row for row in csv.reader(text.splitlines()) if any(c.strip() for c in row)]
    if not rows:
        raise TemplateError(f"{name}: empty template file (expected the header id,x,y)")
    header = [c.strip().lower() for c in rows[0]]
    if header != ["id", "x", "y"]:
        raise TemplateError(
            f"{name}: line 1: expected the header id,x,y, found {','.join(rows[0])!r}"
        )
    outlines: dict[str, list[tuple[float, float]]] = {}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 3:
            raise TemplateError(f"{name}: row {line}: expected 3 fields id,x,y, found {len(row)}")
        ident = row[0].strip()
        try:
            point = (_number(row[1]), _number(row[2]))
        except ValueError as err:
            raise TemplateError(
                f"{name}: row {line}: x and y must be finite numbers ({_one_line(err)})"
            ) from err
        outlines.setdefault(ident, []).append(point)
    return list(outlines.items())


def _json_point(point: Any) -> tuple[float, float] | None:
    """``(x, y)`` of a JSON pair of finite numbers, else None."""
    if not (isinstance(point, list) and len(point) == 2):
        return None
    out: list[float] = []
    for c in point:
        if isinstance(c, bool) or not isinstance(c, int | float):
            return None
        try:
            value = float(c)
        except OverflowError:
            return None
        if not math.isfinite(value):
            return None
        out.append(value)
    return out[0], out[1]


def _read_json(name: str, text: str) -> list[tuple[str, list[tuple[float, float]]]]:
    try:
        data: Any = json.loads(text)
    except json.JSONDecodeError as err:
        raise TemplateError(f"{name}: invalid JSON: {_one_line(err)}") from err
    if not isinstance(data, list):
        raise TemplateError(
            f"{name}: expected a JSON list of outlines, found {type(data).__name__}"
        )
    out: list[tuple[str, list[tuple[float, float]]]] = []
    for j, item in enumerate(data):
        if not isinstance(item, list):
            raise TemplateError(f"{name}: outline {j}: expected a list of [x, y] pairs")
        points: list[tuple[float, float]] = []
        for point in item:
            xy = _json_point(point)
            if xy is None:
                raise TemplateError(
                    f"{name}: outline {j}: every point must be a pair [x, y] of finite numbers, "
                    f"found {json.dumps(point)[:40]}"
                )
            points.append(xy)
        out.append((str(j), points))
    return out


def _cross(o: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _convex_hull(points: FloatArray, tol: float) -> FloatArray:
    """Counter-clockwise convex hull (monotone chain) without collinear or repeated vertices."""
    pts = np.unique(points, axis=0).tolist()
    if len(pts) < 3:
        return np.asarray(pts, dtype=np.float64).reshape(-1, 2)

    def chain(seq: list[list[float]]) -> list[list[float]]:
        out: list[list[float]] = []
        for p in seq:
            while len(out) >= 2 and _cross(out[-2], out[-1], p) <= tol:
                out.pop()
            out.append(p)
        return out

    lower = chain(pts)
    upper = chain(pts[::-1])
    return np.asarray(lower[:-1] + upper[:-1], dtype=np.float64).reshape(-1, 2)


def _signed_area(p: FloatArray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _normalise(name: str, ident: str, raw: list[tuple[float, float]]) -> tuple[FloatArray, bool]:
    """Hull of one outline, centred on its centroid and scaled to area 1.

    Also returns whether the outline was convex (its area equals its hull's).
    """
    if len(raw) < 3:
        raise TemplateError(
            f"{name}: outline {ident!r}: degenerate outline ({len(raw)} points; at least 3 needed)"
        )
    p = np.asarray(raw, dtype=np.float64)
    lo, hi = p.min(axis=0), p.max(axis=0)
    extent = float(np.max(hi - lo))
    if not extent > 0.0:
        raise TemplateError(f"{name}: outline {ident!r}: degenerate outline (all points equal)")
    # work in coordinates of size about 1, so that tolerances are relative
    q = (p - 0.5 * (lo + hi)) / extent
    hull = _convex_hull(q, HULL_TOL)
    hull_area = _signed_area(hull) if len(hull) >= 3 else 0.0
    if len(hull) < 3 or hull_area <= HULL_TOL:
        raise TemplateError(
            f"{name}: outline {ident!r}: degenerate outline (zero area; {len(hull)} hull vertices)"
        )
    convex = abs(abs(_signed_area(q)) - hull_area) <= CONVEX_RTOL * hull_area
    # centroid of the hull, from the triangles it forms with its first vertex
    a, b, c = hull[0], hull[1:-1], hull[2:]
    tri = 0.5 * ((b[:, 0] - a[0]) * (c[:, 1] - a[1]) - (b[:, 1] - a[1]) * (c[:, 0] - a[0]))
    centroid = (tri[:, None] * (a + b + c)).sum(axis=0) / (3.0 * tri.sum())
    return (hull - centroid) / math.sqrt(hull_area), convex


def read_templates(path: str | Path) -> Template:
    """Read, convexify and normalise the outlines of a template file.

    Parameters
    ----------
    path
        A ``.csv`` file with the header ``id,x,y`` and one row per vertex (the
        rows of one ``id`` form one outline, in order), or a ``.json`` file
        holding a list of outlines, each a list of ``[x, y]`` pairs. A relative
        path is resolved against the current directory.

    Returns
    -------
    Template
        Every outline's convex hull, counter-clockwise, centred on its
        centroid and scaled to area 1.

    Raises
    ------
    TemplateError
        One line naming the file (and the outline) when the file cannot be
        read, is malformed, or holds an outline with fewer than 3 hull
        vertices or zero area.

    Warns
    -----
    TemplateWarning
        Once per file when some outlines were not convex (their hulls are used).

    Examples
    --------
    >>> import json, os, tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = os.path.join(d, "t.json")
    ...     with open(p, "w") as f:
    ...         json.dump([[[0, 0], [2, 0], [2, 1], [0, 1]]], f)
    ...     t = read_templates(p)
    >>> len(t), t.outline(0).shape
    (1, (4, 2))
    """
    name = str(path)
    file = Path(path)
    suffix = file.suffix.lower()
    if suffix not in (".csv", ".json"):
        hint = "; STL meshes are the 3D shape 'template-3d'" if suffix == ".stl" else ""
        raise TemplateError(f"{name}: unsupported template file type (use .csv or .json{hint})")
    what = not_a_file(file, "template")
    if what is not None:
        where = "" if file.is_absolute() else f" (relative to the current directory {Path.cwd()})"
        raise TemplateError(f"{name}: {what}{where}")
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise TemplateError(f"{name}: cannot read the template file: {_one_line(err)}") from err
    try:
        raw = _read_csv(name, text) if suffix == ".csv" else _read_json(name, text)
    except RecursionError:
        raise TemplateError(
            f"{name}: lists nested too deeply to read; a template file holds outlines of [x, y] "
            "pairs"
        ) from None
    if not raw:
        raise TemplateError(f"{name}: the template file holds no outlines")
    ids: list[str] = []
    parts: list[FloatArray] = []
    n_convexified = 0
    for ident, points in raw:
        outline, convex = _normalise(name, ident, points)
        ids.append(ident)
        parts.append(outline)
        n_convexified += not convex
    if n_convexified:
        warnings.warn(
            f"{name}: {n_convexified} of {len(raw)} template outlines were not convex; "
            "their convex hulls are used",
            TemplateWarning,
            stacklevel=2,
        )
    offsets = np.zeros(len(parts) + 1, dtype=np.int64)
    np.cumsum([len(p) for p in parts], out=offsets[1:])
    return Template(
        ids=tuple(ids),
        vertices=np.concatenate(parts),
        offsets=offsets,
        n_convexified=n_convexified,
    )


class TemplatePolygon(ShapeGenerator):
    """Outlines from a file, randomly rotated and scaled to the area ``pi r^2``.

    The reference point of a particle is its outline's centroid. The file is
    read on first use and kept per (resolved) path by the instance.

    Random draws, in order: with ``choice = "random"`` the outline of every
    particle (uniform over the file's outlines), then the rotations (uniform in
    ``[0, 2 pi)``). With ``choice = "cycle"`` particle ``j`` of a batch takes
    outline ``j mod k``.
    """

    def __init__(self, config: TemplateConfig) -> None:
        self.config = config
        self._cache: dict[Path, Template] = {}

    @property
    def templates(self) -> Template:
        """The parsed outlines of ``config.path`` (read once per resolved path)."""
        key = Path(self.config.path).resolve()
        found = self._cache.get(key)
        if found is None:
            found = self._cache[key] = read_templates(self.config.path)
        return found

    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Draw one outline per radius."""
        r = _radii(radius)
        tpl = self.templates
        n = int(r.shape[0])
        k = len(tpl)
        if self.config.choice == "random":
            pick = rng.integers(0, k, size=n).astype(np.int64)
        else:
            pick = np.arange(n, dtype=np.int64) % k
        angle = rng.random(n) * TWO_PI
        counts = np.diff(tpl.offsets)[pick]
        offsets = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        total = int(offsets[-1])
        src = np.repeat(tpl.offsets[pick] - offsets[:-1], counts) + np.arange(total)
        v = tpl.vertices[src]
        scale = np.repeat(r * math.sqrt(math.pi), counts)
        c = np.repeat(np.cos(angle), counts)
        s = np.repeat(np.sin(angle), counts)
        vertices = np.empty((total, 2), dtype=np.float64)
        vertices[:, 0] = scale * (c * v[:, 0] - s * v[:, 1])
        vertices[:, 1] = scale * (s * v[:, 0] + c * v[:, 1])
        return ShapeBatch(vertices=vertices, offsets=offsets, orientation=angle)


# ---------------------------------------------------------------------------
# registration


@hookimpl
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Register the ``regular``, ``random-polygon`` and ``template`` shapes."""
    return [
        ShapeSpec(
            name="regular",
            config_model=RegularConfig,
            factory=RegularPolygon,
            description="Regular m-gon with a random orientation.",
        ),
        ShapeSpec(
            name="random-polygon",
            config_model=RandomPolygonConfig,
            factory=RandomConvexPolygon,
            description="Random convex m-gon with vertices at random polar angles.",
        ),
        ShapeSpec(
            name="template",
            config_model=TemplateConfig,
            factory=TemplatePolygon,
            description="Outlines read from a file, randomly rotated and scaled.",
        ),
    ]
