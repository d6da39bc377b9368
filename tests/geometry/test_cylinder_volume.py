"""Volumes of spheres and polyhedra inside a vertical cylinder, against closed forms and others."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.spatial import ConvexHull, Delaunay

from regopack.geometry.cylinder_volume import (
    disk_disk_area,
    polygons_disk_area,
    polyhedra_in_cylinder,
    spheres_in_cylinder,
)
from regopack.geometry.domain import polygon_disk_area

CUBE = np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
SCALES = [1.0, 1e-3, 1e3]


def _cap(r: float, h: float) -> float:
    return math.pi * h * h * (3 * r - h) / 3


@pytest.mark.parametrize("scale", SCALES)
def test_spheres_in_closed_form(scale):
    r = 1.0 * scale
    centres = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [2, 1, 0]]) * scale
    # inside; on the axis cut by the floor (a cap); on the axis, wider than the wall
    # (a ball less its two caps and the ring between); apart
    floors = [-5.0, 0.3, -5.0, -5.0]
    radii = [5.0, 5.0, 0.6, 1.0]
    for c, zmin, wall, exact in zip(
        centres,
        floors,
        radii,
        [4 / 3 * math.pi, _cap(1.0, 0.7), 4 / 3 * math.pi * (1 - (1 - 0.36) ** 1.5), 0.0],
        strict=True,
    ):
        v = spheres_in_cylinder([c], [r], (0.0, 0.0), wall * scale, zmin * scale, 5 * scale)[0]
        assert v == pytest.approx(exact * scale**3, rel=1e-12, abs=1e-14 * scale**3)


def test_lens_and_polygon_areas_agree_with_the_scalar_forms():
    rng = np.random.default_rng(3)
    for _ in range(100):
        k = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))
        poly = np.c_[np.cos(ang), np.sin(ang)] * rng.uniform(0.5, 2) + rng.uniform(-1, 1, 2)
        c, radius = rng.uniform(-1, 1, 2), rng.uniform(0.2, 2)
        assert polygons_disk_area(poly[None], c, radius)[0] == pytest.approx(
            polygon_disk_area(poly, c, radius), rel=1e-12, abs=1e-15
        )
    # two unit disks a radius apart share 2 pi / 3 - sqrt(3) / 2; tangent disks nothing
    assert disk_disk_area(1.0, 1.0, 0.0) == pytest.approx(2 * math.pi / 3 - math.sqrt(3) / 2)
    assert disk_disk_area(1.0, 1.0, 1.0) == 0.0
    assert disk_disk_area(1.0, 3.0, -2.0) == pytest.approx(math.pi, rel=1e-15)


def _chord(y: float, radius: float) -> float:
    return 0.5 * (y * math.sqrt(radius * radius - y * y) + radius * radius * math.asin(y / radius))


@pytest.mark.parametrize("scale", SCALES)
@pytest.mark.parametrize("radius", [3.0, 1e3])
def test_a_cube_cut_by_the_side_wall_in_closed_form(scale, radius):
    """The arc x = sqrt(R^2 - y^2) crosses the cube's faces y = -1 and y = 1."""
    x0 = radius - 0.8
    cube = CUBE + (x0 + 1.0, 0.0, 0.0)
    exact = 2.0 * (_chord(1.0, radius) - _chord(-1.0, radius) - 2.0 * x0)
    got = polyhedra_in_cylinder([cube * scale], (0.0, 0.0), radius * scale, -5 * scale, 5 * scale)
    assert got[0] == pytest.approx(exact * scale**3, rel=1e-10)


def _slice(points: np.ndarray, z: float) -> np.ndarray:
    """The slice of the hull of ``points`` at height ``z``, by a route of its own."""
    below, above = points[points[:, 2] <= z], points[points[:, 2] > z]
    t = (z - below[:, None, 2]) / (above[None, :, 2] - below[:, None, 2])
    cross = below[:, None, :2] + t[..., None] * (above[None, :, :2] - below[:, None, :2])
    flat = cross.reshape(-1, 2)
    return flat[ConvexHull(flat).vertices]


def _reference(points: np.ndarray, axis, radius, zmin, zmax) -> float:
    """QUADPACK over height of the scalar polygon-disk area of an independent slice."""
    lo, hi = max(points[:, 2].min(), zmin), min(points[:, 2].max(), zmax)
    heights = sorted({float(z) for z in points[:, 2] if lo < z < hi})

    def f(z: float) -> float:
        return polygon_disk_area(_slice(points, z), axis, radius)

    value, _ = quad(f, lo, hi, points=heights or None, limit=500, epsabs=0, epsrel=1e-12)
    return value


@pytest.mark.parametrize("seed", range(4))
def test_random_polyhedra_against_quadpack_and_monte_carlo(seed):
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(14, 3)) + (1.6, 0.3, 0.0)
    axis, radius, zmin, zmax = (0.0, 0.0), 2.0, -0.4, 10.0
    got = polyhedra_in_cylinder([points], axis, radius, zmin, zmax)[0]
    assert got == pytest.approx(_reference(points, axis, radius, zmin, zmax), rel=1e-9)
    # and an estimate that shares nothing: points in the bounding box
    n = 400_000
    lo, hi = points.min(axis=0), points.max(axis=0)
    x = rng.uniform(lo, hi, (n, 3))
    hit = (Delaunay(points).find_simplex(x) >= 0) & (np.hypot(x[:, 0], x[:, 1]) <= radius)
    hit &= x[:, 2] >= zmin
    f = hit.mean()
    box = float(np.prod(hi - lo))
    assert abs(got - f * box) < 5 * box * math.sqrt(f * (1 - f) / n)


@pytest.mark.parametrize("scale", SCALES)
def test_random_spheres_against_quadpack(scale):
    rng = np.random.default_rng(7)
    c = rng.uniform(-3, 3, (30, 3))
    r = rng.uniform(0.3, 1.5, 30)
    got = (
        spheres_in_cylinder(
            c * scale, r * scale, (0.2 * scale, 0.0), 2.5 * scale, -1 * scale, 2 * scale
        )
        / scale**3
    )
    for k in range(30):
        lo, hi = max(c[k, 2] - r[k], -1.0), min(c[k, 2] + r[k], 2.0)
        d = math.hypot(c[k, 0] - 0.2, c[k, 1])

        def f(z: float, k: int = k, d: float = d) -> float:
            rho = math.sqrt(max(r[k] ** 2 - (z - c[k, 2]) ** 2, 0.0))
            # the textbook lens of two disks (acos of the two half-angles)
            if d + rho <= 2.5:
                return math.pi * rho * rho
            if d >= rho + 2.5 or rho == 0:
                return 0.0
            if d + 2.5 <= rho:
                return math.pi * 2.5**2
            a1 = math.acos((d * d + rho * rho - 2.5**2) / (2 * d * rho))
            a2 = math.acos((d * d + 2.5**2 - rho * rho) / (2 * d * 2.5))
            return rho * rho * (a1 - math.sin(2 * a1) / 2) + 2.5**2 * (a2 - math.sin(2 * a2) / 2)

        exact = quad(f, lo, hi, limit=500, epsabs=0, epsrel=1e-12)[0] if hi > lo else 0.0
        assert got[k] == pytest.approx(exact, rel=1e-9, abs=1e-12 * r[k] ** 3)


def test_cut_volumes_add_up_over_adjacent_windows():
    rng = np.random.default_rng(11)
    polys = [rng.normal(size=(12, 3)) * 0.8 + rng.uniform(-3, 3, 3) for _ in range(20)]
    whole = polyhedra_in_cylinder(polys, (0.1, -0.2), 2.2, -2.0, 2.0)
    parts = sum(
        polyhedra_in_cylinder(polys, (0.1, -0.2), 2.2, a, b)
        for a, b in [(-2.0, -0.7), (-0.7, 0.4), (0.4, 2.0)]
    )
    np.testing.assert_allclose(parts, whole, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("bump", [1e-9, 1e-7, 1e-6])
def test_a_face_folded_by_a_hair_keeps_its_fold(bump):
    """Two faces that meet at a tiny angle still meet along an edge: the slice has a corner there.

    A tilted cube whose corner ``(1, 1, 1)`` is pushed out by ``bump``: each of its three faces
    there folds along a diagonal. Cut by the floor, the two parts add up to the whole hull.
    """
    c, s = math.cos(0.5), math.sin(0.5)
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, math.cos(0.3), -math.sin(0.3)], [0.0, math.sin(0.3), math.cos(0.3)]]
    )
    cube = CUBE.copy()
    cube[7] += bump
    points = cube @ turn.T
    whole = ConvexHull(points).volume
    above = polyhedra_in_cylinder([points], (0.0, 0.0), 10.0, 0.0, 10.0)[0]
    below = polyhedra_in_cylinder([points], (0.0, 0.0), 10.0, -10.0, 0.0)[0]
    assert above + below == pytest.approx(whole, rel=1e-13)


def test_the_breakpoints_keep_the_slices_few(monkeypatch):
    """The heights where the area is not smooth bound the work: without them the halving
    finds the kinks itself, at many times the slices (and less accurately).

    About 400 slices per cut polyhedron and 140 per cut ball here; dropping the heights where
    an edge crosses the wall or a ball's slice circle is tangent to it costs several times more.
    """
    import regopack.geometry.cylinder_volume as cv

    slices = [0]

    def counted(name):
        real = getattr(cv, name)

        def wrapper(first, *rest):
            slices[0] += int(np.prod(np.shape(first)[:1] or (1,)))
            return real(first, *rest)

        monkeypatch.setattr(cv, name, wrapper)

    counted("polygons_disk_area")
    counted("disk_disk_area")
    rng = np.random.default_rng(5)
    polys = []
    for _ in range(50):
        points = rng.normal(size=(12, 3))
        points /= np.ptp(points, axis=0).max()
        angle, d = rng.uniform(0, 2 * np.pi), 3 + rng.uniform(-0.5, 0.5)
        polys.append(points + (d * math.cos(angle), d * math.sin(angle), 0.0))
    volume = cv.polyhedra_in_cylinder(polys, (0.0, 0.0), 3.0, -5.0, 5.0)
    cut = np.count_nonzero(volume > 0)
    assert cut > 30 and slices[0] < 600 * cut
    slices[0] = 0
    centres = np.c_[rng.uniform(-4, 4, (100, 2)), rng.uniform(-1, 1, 100)]
    radii = rng.uniform(0.3, 1.5, 100)
    cv.spheres_in_cylinder(centres, radii, (0.0, 0.0), 3.0, -0.5, 0.5)
    assert slices[0] < 200 * 100
