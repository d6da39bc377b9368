"""The oracle's containment in a walled cylinder: side wall, floor and lid; spheres, polyhedra."""

from __future__ import annotations

import math

import numpy as np
import pytest
from packings3d import cube_packing

import regopack
from regopack.base.errors import ConfigError
from regopack.geometry.domain import Cylinder
from regopack.packing.core import Packing
from regopack.verification.polyhedra import verify_polyhedra, verify_spheres
from regopack.verification.summary import verify_summary

SCALES = [1.0, 1e-3, 1e3]
R, H = 5.0, 10.0  # the cylinder: axis at (5, 5), floor 0, lid 10 (times the scale)
CUBE = np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def _cylinder(scale: float) -> tuple[list[float], list[float], tuple[float, float, float]]:
    lo = [0.0, 0.0, 0.0]
    hi = [2 * R * scale, 2 * R * scale, H * scale]
    return lo, hi, (R * scale, R * scale, R * scale)


def _turn(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _side_cube(half: float, beyond: float, theta: float = 0.3) -> np.ndarray:
    """A cube of half-side ``half`` whose outermost vertical edge, along the direction
    ``theta`` from the axis, lies ``beyond`` outside the side wall (tangent at 0)."""
    local = CUBE * half @ _turn(math.pi / 4).T  # a vertical edge at (half sqrt 2, 0)
    d = R + beyond - half * math.sqrt(2)  # the cube's centre from the axis
    outward = np.array([math.cos(theta), math.sin(theta), 0.0])
    return local @ _turn(theta).T + np.array([R, R, H / 2]) + d * outward


@pytest.mark.parametrize("scale", SCALES)
def test_a_sphere_tangent_to_the_side_wall_is_inside_and_one_beyond_is_out(scale):
    lo, hi, cyl = _cylinder(scale)
    r = 1.0
    size = (4 / 3 * math.pi) ** (1 / 3) * r  # the cube root of the ball's volume
    theta = 0.7
    out = np.array([math.cos(theta), math.sin(theta), 0.0])

    def at(beyond: float) -> np.ndarray:
        return (np.array([R, R, H / 2]) + (R - r + beyond * size) * out) * scale

    tangent = verify_spheres([at(0.0)], [r * scale], lo, hi, cylinder=cyl)
    assert tangent.ok and tangent.n_outside == 0
    grazing = verify_spheres([at(1e-12)], [r * scale], lo, hi, cylinder=cyl)
    assert grazing.ok  # within the inserter's rounding of a wall
    beyond = verify_spheres(
        [at(0.0), at(1e-9)], [r * scale, r * scale], lo, hi, cylinder=cyl, rel_tol=1e-10
    )
    assert not beyond.ok and beyond.n_outside == 1
    assert beyond.worst_outside == (1, pytest.approx(1e-9, rel=1e-3))
    assert "leave the cylinder" in str(beyond) and "particle 1" in str(beyond)


@pytest.mark.parametrize("scale", SCALES)
def test_a_cube_with_corners_on_the_side_wall_is_inside_and_one_beyond_is_out(scale):
    lo, hi, cyl = _cylinder(scale)
    half = 0.75
    size = 2 * half  # the cube root of the cube's volume
    tangent = _side_cube(half, 0.0) * scale
    radial = np.hypot(tangent[:, 0] - R * scale, tangent[:, 1] - R * scale)
    assert radial.max() == pytest.approx(R * scale, rel=1e-15)
    assert verify_polyhedra([tangent], None, lo, hi, cylinder=cyl).ok
    assert verify_polyhedra([_side_cube(half, 1e-12 * size) * scale], None, lo, hi, cylinder=cyl).ok
    beyond = verify_polyhedra(
        [tangent, _side_cube(half, 1e-9 * size, theta=2.0) * scale],
        None,
        lo,
        hi,
        rel_tol=1e-10,
        cylinder=cyl,
    )
    assert beyond.n_outside == 1
    assert beyond.worst_outside == (1, pytest.approx(1e-9, rel=1e-3))
    assert "particle 1, by 1e-09 of its size" in str(beyond)


@pytest.mark.parametrize("scale", SCALES)
def test_the_floor_and_the_lid(scale):
    lo, hi, cyl = _cylinder(scale)
    half = 0.5
    on_floor = (CUBE * half + (R, R, half)) * scale
    on_lid = (CUBE * half + (R, R + 2, H - half)) * scale
    below = (CUBE * half + (R + 2, R, half - 1e-8)) * scale
    above = (CUBE * half + (R - 2, R, H - half + 2e-8)) * scale
    report = verify_polyhedra([on_floor, on_lid, below, above], None, lo, hi, cylinder=cyl)
    assert report.n_outside == 2 and report.n_overlapping_pairs == 0
    assert report.worst_outside == (3, pytest.approx(2e-8, rel=1e-4))
    r = half * scale
    spheres = verify_spheres(
        np.array(
            [
                [R, R, half],
                [R, R + 2, H - half],
                [R + 2, R, half - 1e-8],
                [R - 2, R, H - half + 2e-8],
            ]
        )
        * scale,
        [r] * 4,
        lo,
        hi,
        cylinder=cyl,
    )
    size = (4 / 3 * math.pi) ** (1 / 3) * half
    assert spheres.n_outside == 2
    assert spheres.worst_outside == (3, pytest.approx(2e-8 / size, rel=1e-4))


@pytest.mark.parametrize("scale", SCALES)
def test_a_particle_in_a_corner_of_the_bounding_box_is_outside(scale):
    """Inside the cylinder's bounding box, outside its circle: the side wall is a circle."""
    lo, hi, cyl = _cylinder(scale)
    corner = np.array([R + 0.8 * R, R + 0.8 * R, H / 2])  # 1.13 R from the axis
    cube = verify_polyhedra([(CUBE * 0.5 + corner) * scale], None, lo, hi, cylinder=cyl)
    assert cube.n_outside == 1
    assert cube.worst_outside == (0, pytest.approx(math.hypot(4.5, 4.5) - R, rel=1e-9))
    ball = verify_spheres([corner * scale], [0.5 * scale], lo, hi, cylinder=cyl)
    size = (4 / 3 * math.pi) ** (1 / 3) * 0.5
    assert ball.n_outside == 1
    assert ball.worst_outside == (0, pytest.approx((0.8 * R * math.sqrt(2) + 0.5 - R) / size))
    # the same particles in the box of the same bounds are inside
    assert verify_polyhedra([(CUBE * 0.5 + corner) * scale], None, lo, hi).ok


def test_a_bad_cylinder_is_refused_in_one_line():
    with pytest.raises(ConfigError, match="radius > 0"):
        verify_spheres([[0, 0, 0]], [1], [-1, -1, -1], [1, 1, 1], cylinder=(0, 0, -1))
    with pytest.raises(ConfigError, match="cannot be periodic"):
        verify_polyhedra([CUBE], None, [-1, -1, -1], [1, 1, 1], periodic=True, cylinder=(0, 0, 1))


@pytest.mark.parametrize("scale", SCALES)
def test_a_cylinder_packing_is_verified_by_the_summary(scale):
    cyl = Cylinder(R * scale, R * scale, R * scale, 0.0, H * scale)
    half = 0.5
    centres = [[R, R, half], [2 * R - half, R, H / 2]]  # on the floor, touching the side
    spheres = Packing.of_spheres(np.array(centres) * scale, [half * scale] * 2, cyl)
    assert regopack.verify(spheres).ok
    assert verify_summary(spheres) == {
        "ok": True,
        "overlap_pairs": 0,
        "worst_overlap": 0.0,
        "outside": 0,
    }
    cubes = cube_packing(
        [[R, R, half], [2 * R - half + 0.1, R, H / 2], [1.8 * R, 1.8 * R, H / 2]],
        half=half,
        domain=Cylinder(R, R, R, 0.0, H),
    )
    report = regopack.verify(cubes)
    assert not report.ok and report.n_outside == 2
    assert "particle 2" in str(report) and "leave the cylinder" in str(report)
    assert verify_summary(cubes)["outside"] == 2
