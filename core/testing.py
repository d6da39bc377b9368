"""Helpers for testing regopack and its plugins.

Plugin authors get two kinds of help:

- building blocks: :func:`make_registry` (a registry with the plugins under
  test, without installed plugins), :func:`packing_from_polygons` (a packing
  with known particles) and :func:`assert_valid_packing`;
- ready checks of the core contracts, which raise :class:`AssertionError`
  with a message naming the broken rule, so a pytest test is one line:
  :func:`check_shape_generator`, :func:`check_size_distribution` and
  :func:`check_density_controller`.

Examples
--------
>>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 1, 0, 1))
>>> assert_valid_packing(p).ok
True

>>> from regopack.plugins.density.eta import EtaConfig, EtaController
>>> check_density_controller(EtaController(EtaConfig(eta=20)))
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.geometry.domain import PlaneDomain, Rectangle, domain_from_dict
from regopack.geometry.population import ShapeBatch
from regopack.geometry.solids import SolidBatch
from regopack.packing.core import Packing
from regopack.registry.interfaces import (
    DensityController,
    ShapeGenerator,
    SizeDistribution,
    SolidGenerator,
)
from regopack.registry.manager import BUILTIN_PLUGINS, Registry, build_plugin_manager
from regopack.verification.polygons import VerifyReport, assert_valid_packing, verify

__all__ = [
    "DEFAULT_RADII",
    "VerifyReport",
    "assert_valid_packing",
    "check_density_controller",
    "check_shape_generator",
    "check_size_distribution",
    "check_solid_generator",
    "extreme_radii",
    "make_registry",
    "packing_from_polygons",
    "scaled_packing",
    "scaled_scene",
    "touching_squares",
    "verify",
]

FloatArray = NDArray[np.float64]

DEFAULT_RADII: tuple[float, ...] = tuple(float(r) for r in np.geomspace(0.01, 1000.0, 41))
"""Radii that :func:`check_shape_generator` asks for: 41 values from 0.01 to 1000."""


def make_registry(*plugins: object, builtins: Sequence[str] = BUILTIN_PLUGINS) -> Registry:
    """Registry of the given plugin objects (plus ``builtins``), without entry points.

    Parameters
    ----------
    *plugins
        Modules or objects with ``@hookimpl`` methods.
    builtins
        Built-in plugin modules to register as well; pass ``()`` for none.
    """
    return Registry.from_manager(
        build_plugin_manager(autoload=False, extra=plugins, builtins=builtins)
    )


def extreme_radii(n: int, ratio: float, scale: float, rng: np.random.Generator) -> FloatArray:
    """Draw ``n >= 2`` radii log-uniformly in ``[scale, scale * ratio]``, both ends included.

    The largest and the smallest radius are always present (at random places),
    so a test sees the full size ratio; ``ratio = 1`` gives ``n`` equal radii.

    Examples
    --------
    >>> r = extreme_radii(5, 1e4, 1e-6, np.random.default_rng(0))
    >>> float(r.max() / r.min())
    10000.0
    """
    if ratio > 1:
        radius = scale * np.exp(rng.uniform(0.0, np.log(ratio), size=n))
    else:
        radius = np.full(n, scale)
    radius[0] = scale * ratio
    radius[-1] = scale
    rng.shuffle(radius)
    return radius


def packing_from_polygons(
    polygons: Sequence[ArrayLike],
    domain: PlaneDomain | tuple[float, float, float, float] | None = None,
    *,
    placed: Sequence[bool] | None = None,
) -> Packing:
    """Build a :class:`~regopack.packing.core.Packing` from absolute polygon outlines.

    Each particle's centre is the mean of its vertices. Useful to construct
    packings with known defects.

    Parameters
    ----------
    polygons
        One ``(k, 2)`` array of counter-clockwise vertices per particle.
    domain
        The container (any :class:`~regopack.geometry.domain.PlaneDomain`) or the rectangle
        ``(xmin, xmax, ymin, ymax)``; by
        default the bounding box of the polygons.
    placed
        Which particles count as placed (default: all), in order.
    """
    outlines = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in polygons]
    n = len(outlines)
    if domain is None:
        allv = np.concatenate(outlines) if n else np.zeros((1, 2))
        domain = Rectangle(
            float(allv[:, 0].min()),
            float(allv[:, 0].max()),
            float(allv[:, 1].min()),
            float(allv[:, 1].max()),
        )
    elif not isinstance(domain, PlaneDomain):
        domain = Rectangle(*(float(v) for v in domain))
    centre = np.array([o.mean(axis=0) for o in outlines]).reshape(n, 2)
    counts = np.array([len(o) for o in outlines], dtype=np.int64)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    vertices = (
        np.concatenate([o - c for o, c in zip(outlines, centre, strict=True)])
        if n
        else np.zeros((0, 2))
    )
    mask = np.ones(n, dtype=bool) if placed is None else np.asarray(placed, dtype=bool)
    insertion_index = np.where(mask, np.cumsum(mask) - 1, -1).astype(np.int64)
    centre = np.where(mask[:, None], centre, np.nan)
    area = np.array(
        [
            0.5 * abs(np.sum(o[:, 0] * np.roll(o[:, 1], -1) - np.roll(o[:, 0], -1) * o[:, 1]))
            for o in outlines
        ]
    )
    return Packing(
        radius=np.sqrt(area / np.pi),
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("test",),
        vertices=vertices,
        offsets=offsets,
        orientation=np.zeros(n, dtype=np.float64),
        centre=centre,
        insertion_index=insertion_index,
        domain=domain,
        scene={"name": "test"},
        seed=0,
    )


# ---------------------------------------------------------------------------
# contract checks


def touching_squares(k: int, scale: float = 1.0) -> Packing:
    """Return a ``k`` by ``k`` grid of touching squares of side ``scale``, 8 vertices each.

    Every neighbour touches along a whole side: no pair of an overlap test can
    be passed over by its distance (a worst case for :func:`verify`).
    """
    if not (isinstance(k, (int, np.integer)) and k >= 1):
        raise ValueError(f"touching_squares: k = {k!r}; allowed: an integer >= 1")
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"touching_squares: scale = {scale!r}; allowed: a finite number > 0")
    n = k * k
    t = np.linspace(0, 1, 3)[:-1]
    edge = [np.c_[t, 0 * t], np.c_[1 + 0 * t, t], np.c_[1 - t, 1 + 0 * t], np.c_[0 * t, 1 - t]]
    local = (np.concatenate(edge) - 0.5) * scale
    g = (np.arange(k) + 0.5) * scale
    cx, cy = np.meshgrid(g, g)
    return Packing(
        radius=np.full(n, scale / np.sqrt(np.pi)),
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("a",),
        vertices=np.tile(local, (n, 1)),
        offsets=np.arange(0, 8 * n + 1, 8, dtype=np.int64),
        orientation=np.zeros(n),
        centre=np.c_[cx.ravel(), cy.ravel()],
        insertion_index=np.arange(n, dtype=np.int64),
        domain=Rectangle(0, k * scale, 0, k * scale),
    )


def _name(obj: object) -> str:
    return type(obj).__name__


def _same(a: Any, b: Any) -> bool:
    """Equality of nested dicts, lists and arrays (a random generator's state)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(a, b))
    return bool(a == b)


@contextmanager
def _global_random_untouched(what: str) -> Iterator[None]:
    """Fail when the code inside draws from numpy's global random generator."""
    # the legacy global state is read, on purpose, to catch plugins that use it
    before = np.random.get_state(legacy=False)  # noqa: NPY002
    yield
    after = np.random.get_state(legacy=False)  # noqa: NPY002
    if not _same(before, after):
        raise AssertionError(
            f"{what} draws from numpy's global random generator; use only the "
            "numpy.random.Generator it is given"
        )


def _as_array(value: Any, what: str, dtype: type[Any] = np.float64) -> NDArray[Any]:
    try:
        return np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as err:
        raise AssertionError(f"{what} is not a numeric array: {err}") from None


def _check_batch(batch: object, n: int, who: str) -> tuple[FloatArray, NDArray[np.int64]]:
    if not isinstance(batch, ShapeBatch):
        raise AssertionError(f"{who}.generate returned a {_name(batch)}, not a ShapeBatch")
    vertices = _as_array(batch.vertices, f"{who}: vertices")
    offsets = _as_array(batch.offsets, f"{who}: offsets", np.int64)
    orientation = _as_array(batch.orientation, f"{who}: orientation")
    if vertices.ndim != 2 or vertices.shape[1] != 2:
        raise AssertionError(f"{who}: vertices have shape {vertices.shape}, expected (M, 2)")
    if offsets.shape != (n + 1,):
        raise AssertionError(
            f"{who}: offsets have shape {offsets.shape}, expected ({n + 1},) for {n} radii"
        )
    if offsets[0] != 0 or offsets[-1] != vertices.shape[0] or np.any(np.diff(offsets) < 0):
        raise AssertionError(
            f"{who}: offsets must rise from 0 to the number of vertices "
            f"({vertices.shape[0]}); got {offsets[0]} ... {offsets[-1]}"
        )
    if orientation.shape != (n,):
        raise AssertionError(f"{who}: orientation has shape {orientation.shape}, expected ({n},)")
    if not (np.all(np.isfinite(vertices)) and np.all(np.isfinite(orientation))):
        raise AssertionError(f"{who}: vertices or orientations are not all finite")
    return vertices, offsets


def _check_outline(
    v: FloatArray, r: float, j: int, who: str, rtol: float, rho: float = 0.0
) -> None:
    where = f"{who}: outline {j} (radius {r:g})"
    expected = math.pi * r * r
    if rho < 0 or not math.isfinite(rho):
        raise AssertionError(f"{where} has the rounding radius {rho:g}; it must be >= 0")
    if rho > 0 and v.shape[0] == 1:  # a disk: one vertex, the reference point
        if np.any(v != 0.0):
            raise AssertionError(f"{where}: a disk's single vertex must be (0, 0), not {v[0]}")
        if abs(math.pi * rho * rho - expected) > rtol * expected:
            raise AssertionError(f"{where}: a disk of radius {rho:.9g} has not the area pi r^2")
        return
    if v.shape[0] < 3:
        raise AssertionError(f"{where} has {v.shape[0]} vertices; a polygon needs at least 3")
    edges = np.roll(v, -1, axis=0) - v
    signed = 0.5 * float(np.sum(v[:, 0] * edges[:, 1] - v[:, 1] * edges[:, 0]))
    if rho > 0:  # the rounding adds strips along the edges and a disk at the corners
        perimeter = float(np.sum(np.hypot(edges[:, 0], edges[:, 1])))
        signed += perimeter * rho + math.pi * rho * rho
    if signed <= 0:
        raise AssertionError(
            f"{where} is not counter-clockwise (signed area {signed:.6g}); list the "
            "vertices counter-clockwise"
        )
    if abs(signed - expected) > rtol * expected:
        raise AssertionError(
            f"{where} has area {signed:.9g}, expected pi r^2 = {expected:.9g} "
            f"(relative error {abs(signed - expected) / expected:.2e} > rtol {rtol:g})"
        )
    scale = float(np.max(np.hypot(v[:, 0], v[:, 1])))
    length = np.hypot(edges[:, 0], edges[:, 1])
    real = edges[length > 1e-12 * scale]  # edges of zero length are allowed
    turn_cross = real[:, 0] * np.roll(real[:, 1], -1) - real[:, 1] * np.roll(real[:, 0], -1)
    turn_dot = np.sum(real * np.roll(real, -1, axis=0), axis=1)
    turns = np.arctan2(turn_cross, turn_dot)
    worst = int(np.argmin(turns))
    if turns[worst] < -1e-9:
        raise AssertionError(
            f"{where} is not convex: it turns clockwise by {-turns[worst]:.3g} rad "
            f"after edge {worst}"
        )
    if abs(float(np.sum(turns)) - 2.0 * math.pi) > 1e-6:
        raise AssertionError(
            f"{where} is not convex: its edges turn by {float(np.sum(turns)):.6g} rad in total, "
            "not 2 pi (it winds around more than once)"
        )
    # reference point strictly inside: on the left of every edge, by a margin
    inner = edges[:, 0] * (-v[:, 1]) - edges[:, 1] * (-v[:, 0])
    margin = np.where(length > 1e-12 * scale, inner / np.where(length > 0, length, 1.0), np.inf)
    if float(np.min(margin)) <= 1e-9 * scale:
        raise AssertionError(
            f"{where}: the reference point (0, 0) is not strictly inside the outline "
            f"(distance {float(np.min(margin)):.3g} from edge {int(np.argmin(margin))})"
        )


def check_shape_generator(
    generator: ShapeGenerator,
    radii: ArrayLike = DEFAULT_RADII,
    seed: int = 0,
    *,
    rtol: float = 1e-6,
) -> ShapeBatch:
    """Check the contract of a shape generator; raise :class:`AssertionError` if broken.

    The rules checked:

    - ``generate`` returns a :class:`~regopack.geometry.population.ShapeBatch` of the
      right shapes (one outline per radius, offsets rising from 0), with finite
      values, also for an empty array of radii;
    - every outline has at least three vertices, is counter-clockwise and convex
      (edges of zero length are allowed) and has the area ``pi r^2`` within
      ``rtol``, counting its rounding (``ShapeBatch.rounding``); a rounded
      outline may instead be the single vertex ``(0, 0)``, a disk;
    - the reference point ``(0, 0)`` lies strictly inside every outline;
    - the same seed gives the same outlines, and numpy's global random
      generator is not used.

    Parameters
    ----------
    generator
        The shape generator to check.
    radii
        Radii to ask outlines for (default: :data:`DEFAULT_RADII`).
    seed
        Seed of the generator passed to ``generate``.
    rtol
        Tolerated relative error of the areas.

    Returns
    -------
    ShapeBatch
        The outlines generated for ``radii``, for further checks.

    Examples
    --------
    >>> from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
    >>> batch = check_shape_generator(RandomPolygon(OctagonConfig(psi=2.0)))
    >>> len(batch)
    41
    """
    who = _name(generator)
    r = _as_array(radii, "radii").reshape(-1)
    with _global_random_untouched(f"{who}.generate"):
        empty = generator.generate(np.zeros(0), np.random.default_rng(seed))
        _check_batch(empty, 0, f"{who} (no radii)")
        batch = generator.generate(r.copy(), np.random.default_rng(seed))
        again = generator.generate(r.copy(), np.random.default_rng(seed))
    vertices, offsets = _check_batch(batch, r.shape[0], who)
    rounding = batch.rounding_radius
    if rounding.shape != (r.shape[0],):
        raise AssertionError(f"{who}: rounding has shape {rounding.shape}, expected ({len(r)},)")
    for j in range(r.shape[0]):
        outline = vertices[offsets[j] : offsets[j + 1]]
        _check_outline(outline, float(r[j]), j, who, rtol, float(rounding[j]))
    v2, o2 = _check_batch(again, r.shape[0], who)
    same = (
        np.array_equal(offsets, o2)
        and np.array_equal(vertices, v2)
        and np.array_equal(np.asarray(batch.orientation), np.asarray(again.orientation))
    )
    if not same:
        raise AssertionError(
            f"{who} is not deterministic: two calls with generators seeded {seed} gave "
            "different outlines; draw random numbers only from the generator passed in"
        )
    return batch


def _check_solid(batch: SolidBatch, j: int, r: float, who: str, rtol: float) -> None:
    """One solid: a sphere of radius ``r``, or a closed convex polyhedron of volume 4/3 pi r^3."""
    where = f"{who}: solid {j} (radius {r:g})"
    verts, loops = batch.solid(j)
    rho = float(batch.rounding_radius[j])
    expected = 4.0 / 3.0 * math.pi * r**3
    if not loops:
        if verts.shape[0] != 1 or np.any(verts != 0.0) or rho <= 0:
            raise AssertionError(
                f"{where} has no faces; only a sphere (the vertex (0, 0, 0) rounded by its "
                "radius) may have none"
            )
    else:
        f0, f1 = int(batch.face_offsets[j]), int(batch.face_offsets[j + 1])
        normals, support = batch.normals[f0:f1], batch.support[f0:f1]
        scale = float(np.max(np.linalg.norm(verts, axis=1)))
        if np.any(np.abs(np.linalg.norm(normals, axis=1) - 1.0) > 1e-9):
            raise AssertionError(f"{where} has face normals that are not unit vectors")
        if float(np.min(support)) <= 1e-9 * scale:
            raise AssertionError(
                f"{where}: the reference point (0, 0, 0) is not strictly inside "
                f"(a face plane at distance {float(np.min(support)):.3g})"
            )
        outside = verts @ normals.T - support
        if float(np.max(outside)) > 1e-9 * scale:
            raise AssertionError(
                f"{where} is not convex: a vertex lies {float(np.max(outside)):.3g} outside "
                "a face's plane"
            )
        used = np.zeros(verts.shape[0], dtype=bool)
        edges: dict[tuple[int, int], int] = {}
        for f, loop in enumerate(loops):
            if loop.size and (loop.min() < 0 or loop.max() >= verts.shape[0]):
                raise AssertionError(
                    f"{where}: face {f} has a vertex index outside [0, {verts.shape[0]}) "
                    "(indices are local to the particle)"
                )
            if np.unique(loop).size != loop.size:
                raise AssertionError(f"{where}: face {f} repeats a vertex")
            for a, b in zip(loop.tolist(), np.roll(loop, -1).tolist(), strict=True):
                edges[(a, b)] = edges.get((a, b), 0) + 1
            p = verts[loop]
            used[loop] = True
            if p.shape[0] < 3 or np.max(np.abs(p @ normals[f] - support[f])) > 1e-9 * scale:
                raise AssertionError(
                    f"{where}: face {f} is not a planar loop of 3 or more vertices"
                )
            area = 0.5 * np.cross(p - p[0], np.roll(p, -1, axis=0) - p[0]).sum(axis=0)
            if float(np.dot(area, normals[f])) <= 0:
                raise AssertionError(
                    f"{where}: face {f} is not counter-clockwise seen from outside"
                )
        if not used.all():
            raise AssertionError(f"{where} has vertices on no face")
        # closed: every edge runs once each way, in two faces
        if any(n != 1 or edges.get((b, a)) != 1 for (a, b), n in edges.items()):
            raise AssertionError(
                f"{where} is not a closed surface: an edge is not shared by exactly two "
                "faces running it in opposite directions"
            )
        if np.unique(np.round(verts / max(scale, 1e-300), 12), axis=0).shape[0] != verts.shape[0]:
            raise AssertionError(f"{where} has two vertices at the same place")
        if rho != 0:
            raise AssertionError(f"{where}: rounded polyhedra are not checked yet")
    volume = float(batch.volume[j])
    if abs(volume - expected) > rtol * expected:
        raise AssertionError(
            f"{where} has volume {volume:.9g}, expected 4/3 pi r^3 = {expected:.9g}"
        )


def check_solid_generator(
    generator: SolidGenerator,
    radii: ArrayLike = DEFAULT_RADII,
    seed: int = 0,
    *,
    rtol: float = 1e-6,
) -> SolidBatch:
    """Check the contract of a 3D shape generator; raise :class:`AssertionError` if broken.

    The rules checked: ``generate`` returns a
    :class:`~regopack.geometry.solids.SolidBatch` with one solid per radius (also for
    no radii); each solid is a sphere (the vertex ``(0, 0, 0)`` rounded by
    its radius) or a sharp convex polyhedron whose faces are planar loops of
    local vertex indices without repeats, counter-clockwise seen from
    outside, forming a closed surface (every edge in two faces, once each
    way), with unit normals, distinct vertices, every vertex on some face and
    inside every face's plane, the reference point strictly
    inside, and the volume ``4/3 pi r^3`` within ``rtol``; rotations are
    unit quaternions; the same seed gives the same solids, and numpy's
    global random generator is not used.

    Returns
    -------
    SolidBatch
        The solids generated for ``radii``, for further checks.
    """
    who = _name(generator)
    r = _as_array(radii, "radii").reshape(-1)
    with _global_random_untouched(f"{who}.generate"):
        empty = generator.generate(np.zeros(0), np.random.default_rng(seed))
        batch = generator.generate(r.copy(), np.random.default_rng(seed))
        again = generator.generate(r.copy(), np.random.default_rng(seed))
    for got, n, label in ((empty, 0, f"{who} (no radii)"), (batch, r.shape[0], who)):
        if not isinstance(got, SolidBatch):
            raise AssertionError(f"{label}.generate returned a {_name(got)}, not a SolidBatch")
        if len(got) != n:
            raise AssertionError(f"{label} returned {len(got)} solids for {n} radii")
    if not (np.isfinite(batch.vertices).all() and np.isfinite(batch.rotation).all()):
        raise AssertionError(f"{who}: vertices or rotations are not all finite")
    if np.any(np.abs(np.linalg.norm(batch.rotation, axis=1) - 1.0) > 1e-9):
        raise AssertionError(f"{who}: rotations are not unit quaternions")
    for j in range(r.shape[0]):
        _check_solid(batch, j, float(r[j]), who, rtol)
    fields = ("vertices", "offsets", "face_vertices", "normals", "support", "rotation")
    if not all(np.array_equal(getattr(batch, f), getattr(again, f)) for f in fields):
        raise AssertionError(
            f"{who} is not deterministic: two calls with generators seeded {seed} gave "
            "different solids; draw random numbers only from the generator passed in"
        )
    return batch


def check_size_distribution(
    dist: SizeDistribution,
    n: int = 100_000,
    seed: int = 0,
    rtol: float = 0.02,
) -> FloatArray:
    """Check the contract of a size distribution; raise :class:`AssertionError` if broken.

    The rules checked:

    - ``r_min`` and ``r_max`` are finite, ``0 < r_min <= r_max``;
    - ``sample(n, rng)`` returns ``n`` finite radii within ``[r_min, r_max]``,
      and an empty array for ``n = 0``;
    - the mean particle area of the sample, mean(pi r^2), matches the declared
      ``mean_area`` within ``rtol`` (relative);
    - the same seed gives the same radii, and numpy's global random generator
      is not used.

    Parameters
    ----------
    dist
        The size distribution to check.
    n
        Sample size. The statistical error of the sample's mean area shrinks as
        ``1 / sqrt(n)``; raise ``n`` or ``rtol`` for very wide distributions.
    seed
        Seed of the generator passed to ``sample``.
    rtol
        Tolerated relative difference between the sample's mean area and
        ``mean_area``.

    Returns
    -------
    ndarray
        The ``n`` radii drawn, for further checks.

    Examples
    --------
    >>> from regopack.plugins.sizes.change5 import Change5, Change5Config
    >>> radii = check_size_distribution(Change5(Change5Config()), n=20_000)
    >>> radii.shape
    (20000,)
    """
    who = _name(dist)
    r_min, r_max = float(dist.r_min), float(dist.r_max)
    if not (math.isfinite(r_min) and math.isfinite(r_max) and 0 < r_min <= r_max):
        raise AssertionError(
            f"{who}: r_min = {r_min:g} and r_max = {r_max:g} must be finite with 0 < r_min <= r_max"
        )
    declared = float(dist.mean_area)
    if not (math.isfinite(declared) and declared > 0):
        raise AssertionError(f"{who}: mean_area = {declared:g} must be finite and positive")
    with _global_random_untouched(f"{who}.sample"):
        empty = _as_array(dist.sample(0, np.random.default_rng(seed)), f"{who}.sample(0)")
        radii = _as_array(dist.sample(n, np.random.default_rng(seed)), f"{who}.sample")
        again = _as_array(dist.sample(n, np.random.default_rng(seed)), f"{who}.sample")
    if empty.shape != (0,):
        raise AssertionError(f"{who}.sample(0) returned shape {empty.shape}, expected (0,)")
    if radii.shape != (n,):
        raise AssertionError(f"{who}.sample({n}) returned shape {radii.shape}, expected ({n},)")
    if not np.all(np.isfinite(radii)):
        raise AssertionError(f"{who}.sample returned radii that are not finite")
    slack = 1e-12 * r_max
    low, high = int(np.argmin(radii)), int(np.argmax(radii))
    if radii[low] < r_min - slack:
        raise AssertionError(
            f"{who}.sample returned radius {radii[low]:.9g} (sample {low}), below r_min = {r_min:g}"
        )
    if radii[high] > r_max + slack:
        raise AssertionError(
            f"{who}.sample returned radius {radii[high]:.9g} (sample {high}), above "
            f"r_max = {r_max:g}"
        )
    areas = math.pi * radii**2
    mean = float(np.mean(areas))
    error = float(np.std(areas)) / math.sqrt(n)
    if abs(mean - declared) > rtol * declared:
        raise AssertionError(
            f"{who}: the mean particle area of {n} samples is {mean:.6g}, but mean_area "
            f"declares {declared:.6g} (relative difference {abs(mean - declared) / declared:.2e} "
            f"> rtol {rtol:g}; the sample's standard error is {error / declared:.1e})"
        )
    if not np.array_equal(radii, again):
        raise AssertionError(
            f"{who} is not deterministic: two calls with generators seeded {seed} gave "
            "different radii; draw random numbers only from the generator passed in"
        )
    return radii


def _random_arcs(rng: np.random.Generator) -> FloatArray:
    """Disjoint, sorted, unwrapped arcs of one candidate, as the inserter passes them."""
    k = int(rng.integers(1, 6))
    lo = float(rng.uniform(-2.0 * math.pi, 0.0))
    ends = np.sort(rng.uniform(lo, lo + 2.0 * math.pi, 2 * k))
    arcs = ends.reshape(k, 2)
    return arcs[arcs[:, 1] > arcs[:, 0]]


def _arc_cases(rng: np.random.Generator, trials: int) -> list[tuple[FloatArray, float, float]]:
    fixed = [
        np.zeros((0, 2)),
        np.array([[-math.pi, math.pi]]),  # the whole circle
        np.array([[0.0, 1e-9]]),  # a tiny arc
        np.array([[2.5, 4.0]]),  # through pi: ends beyond [-pi, pi]
        np.array([[-4.0, -3.5], [-1.0, 0.5], [1.0, 2.0]]),
    ]
    cases: list[tuple[FloatArray, float, float]] = []
    for arcs in fixed:
        for r_new, r_cand in ((1.0, 1.0), (0.5, 20.0), (20.0, 0.5)):
            cases.append((arcs, r_new, r_cand))
    for _ in range(trials):
        r_new, r_cand = (float(x) for x in rng.uniform(0.05, 50.0, 2))
        cases.append((_random_arcs(rng), r_new, r_cand))
    return cases


def _check_arcs(out: object, arcs: FloatArray, case: str, who: str) -> FloatArray:
    result = _as_array(out, f"{who}.shrink({case})")
    if result.ndim != 2 or result.shape[1] != 2:
        raise AssertionError(f"{who}.shrink({case}) returned shape {result.shape}, expected (k, 2)")
    if not np.all(np.isfinite(result)):
        raise AssertionError(f"{who}.shrink({case}) returned arcs that are not finite")
    if np.any(result[:, 1] <= result[:, 0]):
        bad = result[result[:, 1] <= result[:, 0]][0]
        raise AssertionError(
            f"{who}.shrink({case}) returned the arc [{bad[0]:.9g}, {bad[1]:.9g}] of no "
            "length; drop such arcs"
        )
    tol = 1e-12 * max(1.0, float(np.max(np.abs(arcs))) if arcs.size else 1.0)
    used = np.zeros(arcs.shape[0])
    for start, end in result:
        inside = np.flatnonzero((arcs[:, 0] - tol <= start) & (end <= arcs[:, 1] + tol))
        if inside.size == 0:
            raise AssertionError(
                f"{who}.shrink({case}) lengthened an arc: [{start:.9g}, {end:.9g}] is not "
                f"inside any input arc {arcs.tolist()}"
            )
        used[inside[0]] += end - start
    length = arcs[:, 1] - arcs[:, 0]
    over = np.flatnonzero(used > length + tol)
    if over.size:
        i = int(over[0])
        raise AssertionError(
            f"{who}.shrink({case}) lengthened an arc: the arcs it returned inside "
            f"[{arcs[i, 0]:.9g}, {arcs[i, 1]:.9g}] (length {length[i]:.9g}) add up to "
            f"{used[i]:.9g}"
        )
    return result


def check_density_controller(
    controller: DensityController, seed: int = 0, *, trials: int = 200
) -> None:
    """Check the contract of a density controller; raise :class:`AssertionError` if broken.

    ``shrink`` is called on fixed edge cases (no arcs, the whole circle, a
    tiny arc, arcs with ends beyond ``[-pi, pi]``) and on ``trials`` random
    sets of disjoint arcs with random radii. The rules checked:

    - it returns a ``(k', 2)`` array of finite arcs of positive length;
    - it never lengthens an arc: every arc returned lies inside one input arc,
      and those inside one input arc are no longer than it, together;
    - it does not change its input array;
    - a controller with ``identity = True`` returns the arcs unchanged;
    - the same seed gives the same arcs, and numpy's global random generator
      is not used.

    Parameters
    ----------
    controller
        The density controller to check.
    seed
        Seed of the cases and of the generator passed to ``shrink``.
    trials
        Number of random cases.

    Examples
    --------
    >>> from regopack.plugins.density.eta import EtaConfig, EtaController
    >>> check_density_controller(EtaController(EtaConfig(eta=0)))
    """
    who = _name(controller)
    cases = _arc_cases(np.random.default_rng([seed, 1]), trials)

    def run() -> list[FloatArray]:
        rng = np.random.default_rng(seed)
        outputs = []
        for arcs, r_new, r_cand in cases:
            case = f"{arcs.shape[0]} arcs, r_new={r_new:.3g}, r_candidate={r_cand:.3g}"
            given = arcs.copy()
            out = controller.shrink(given, r_new, r_cand, rng)
            if not np.array_equal(given, arcs):
                raise AssertionError(
                    f"{who}.shrink({case}) changed its input array; return a new array"
                )
            result = _check_arcs(out, arcs, case, who)
            if getattr(controller, "identity", False) and not np.array_equal(result, arcs):
                raise AssertionError(
                    f"{who} declares identity = True but shrink({case}) changed the arcs"
                )
            outputs.append(result)
        return outputs

    with _global_random_untouched(f"{who}.shrink"):
        first = run()
        second = run()
    for (arcs, r_new, r_cand), a, b in zip(cases, first, second, strict=True):
        if not np.array_equal(a, b):
            raise AssertionError(
                f"{who} is not deterministic: shrink({arcs.shape[0]} arcs, r_new={r_new:.3g}, "
                f"r_candidate={r_cand:.3g}) gave different arcs with generators seeded {seed}; "
                "draw random numbers only from the generator passed in"
            )


# ---------------------------------------------------------------------------
# scaling

SCENE_LENGTHS: dict[str, tuple[str, ...]] = {
    "domain": ("width", "height", "depth", "center", "radius", "vertices"),
    "size": ("d_min", "d_max", "d0", "median", "mean", "d63", "d"),
    "insertion": ("zone", "strip"),
}
"""Keys of the scene's sections that hold lengths (numbers or lists of them)."""

STAT_LENGTHS: tuple[str, ...] = ("interior_margin",)
"""Keys of a packing's ``stats`` that hold lengths."""


def _times(value: Any, s: float) -> Any:
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, int | float):
        return float(value) * s
    if isinstance(value, list | tuple):
        return [_times(v, s) for v in value]
    return value


def scaled_scene(scene: Any, s: float) -> dict[str, Any]:
    """Return a copy of the scene dictionary with every length multiplied by ``s``.

    The lengths are those of :data:`SCENE_LENGTHS`; counts, fractions,
    exponents and shape coefficients stay.

    Examples
    --------
    >>> scaled_scene({"domain": {"width": 200.0}, "size": {"d_min": 2.0, "alpha": 6.9}}, 1e-3)
    {'domain': {'width': 0.2}, 'size': {'d_min': 0.002, 'alpha': 6.9}}
    """
    import copy

    out: dict[str, Any] = copy.deepcopy(dict(scene)) if isinstance(scene, dict) else {}
    for section, keys in SCENE_LENGTHS.items():
        part = out.get(section)
        if isinstance(part, dict):
            for key in keys:
                if key in part:
                    part[key] = _times(part[key], s)
    return out


def scaled_packing(packing: Any, s: float) -> Any:
    """Return a copy of a 2D or 3D packing with every length multiplied by ``s``.

    Centres, vertices, support values, radii, rounding radii, the domain,
    the length statistics and the embedded scene's lengths
    (:func:`scaled_scene`) are scaled; orientations, normals and counts stay.
    A packing and its scaled copy must analyse alike, lengths times ``s``.
    """
    from dataclasses import replace

    stats = {k: (float(v) * s if k in STAT_LENGTHS else v) for k, v in packing.stats.items()}
    common: dict[str, Any] = {
        "radius": packing.radius * s,
        "vertices": packing.vertices * s,
        "centre": packing.centre * s,
        "scene": scaled_scene(packing.scene, s),
        "stats": stats,
        "rounding": None if packing.rounding is None else packing.rounding * s,
    }
    record = packing.domain.to_dict()
    for key in ("bounds", "vertices", "center", "radius"):
        if key in record:
            record[key] = _times(record[key], s)
    domain = domain_from_dict(record)
    if domain.dimension == 3:
        return replace(packing, domain=domain, support=packing.support * s, **common)
    return replace(packing, domain=domain, **common)
