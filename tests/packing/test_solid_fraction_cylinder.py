"""The volume fraction of a coaxial cylinder window, and the run summary's φ of a cylinder."""

from __future__ import annotations

import math

import numpy as np
import pytest
from packings3d import cube_packing

from regopack.geometry.cylinder_volume import spheres_in_cylinder
from regopack.geometry.domain import Cylinder
from regopack.packing.core import Packing
from regopack.packing.solid_fraction import cylinder_volumes, fraction_in, phi_in_cylinder
from regopack.run.pipeline import _phi_interior

SCALES = [1.0, 1e-3]


def _spheres(scale: float) -> Packing:
    """Spheres of radius 0.9 on a lattice of step 2 in a cylinder of radius 5 and height 10."""
    centres = [
        [x, y, z]
        for x in np.arange(1.0, 10, 2.0)
        for y in np.arange(1.0, 10, 2.0)
        for z in np.arange(1.0, 10, 2.0)
        if math.hypot(x - 5, y - 5) + 0.9 <= 5
    ]
    cyl = Cylinder(5 * scale, 5 * scale, 5 * scale, 0.0, 10 * scale)
    return Packing.of_spheres(np.array(centres) * scale, np.full(len(centres), 0.9 * scale), cyl)


@pytest.mark.parametrize("scale", SCALES)
def test_the_whole_cylinder_holds_every_solid(scale):
    p = _spheres(scale)
    assert phi_in_cylinder(p, p.domain) == pytest.approx(p.phi, rel=1e-14)
    assert fraction_in(p, p.domain) == phi_in_cylinder(p, p.domain)
    assert p.phi == pytest.approx(
        p.n_placed * 4 / 3 * math.pi * 0.9**3 / (math.pi * 25 * 10), rel=1e-14
    )


@pytest.mark.parametrize("scale", SCALES)
def test_the_interior_window_cuts_spheres_as_their_own_volumes_say(scale):
    p = _spheres(scale)
    window = p.domain.interior(1.5 * scale)
    assert isinstance(window, Cylinder) and window.radius == pytest.approx(3.5 * scale)
    got = phi_in_cylinder(p, window)
    each = spheres_in_cylinder(
        p.centre,
        np.full(p.n_particles, 0.9 * scale),
        (window.cx, window.cy),
        window.radius,
        window.zmin,
        window.zmax,
    )
    assert got == pytest.approx(each.sum() / window.volume, rel=1e-12)
    # a sphere on the axis at z = 1 cut by the floor 1.5: a cap of height 0.4 inside
    k = int(np.flatnonzero(np.all(np.isclose(p.centre / scale, [5, 5, 1]), axis=1))[0])
    cap = math.pi * 0.4**2 * (3 * 0.9 - 0.4) / 3 * scale**3
    assert cylinder_volumes(p, window)[k] == pytest.approx(cap, rel=1e-12)
    # the same at another scale: relative tolerances only
    assert got == pytest.approx(
        phi_in_cylinder(_spheres(1.0), _spheres(1.0).domain.interior(1.5)), rel=1e-12
    )


@pytest.mark.parametrize("scale", SCALES)
def test_cubes_in_a_window_add_up_over_layers_and_match_a_monte_carlo_estimate(scale):
    rng = np.random.default_rng(5)
    centres = [
        [5 + 3.2 * math.cos(a), 5 + 3.2 * math.sin(a), z]
        for a in np.linspace(0, 6, 7)
        for z in (1.5, 4.5, 7.5)
    ]
    p = cube_packing(
        np.array(centres) * scale,
        half=0.9 * scale,
        domain=Cylinder(5 * scale, 5 * scale, 5 * scale, 0.0, 10 * scale),
    )
    window = p.domain.interior(1.6 * scale)  # radius 3.4: every cube is cut
    inside = cylinder_volumes(p, window)
    assert np.all((inside > 0) & (inside < (1.8 * scale) ** 3))
    layers = [
        Cylinder(window.cx, window.cy, window.radius, a, b)
        for a, b in [
            (window.zmin, 3.0 * scale),
            (3.0 * scale, 6.1 * scale),
            (6.1 * scale, window.zmax),
        ]
    ]
    total = sum(cylinder_volumes(p, layer) for layer in layers)
    np.testing.assert_allclose(total, inside, rtol=1e-10)
    # Monte Carlo on one cube: points in its bounding box, inside the window
    j = 0
    lo = p.centre[j] - 0.9 * scale
    x = lo + rng.uniform(0, 1.8 * scale, (400_000, 3))
    hit = window.contains(x)
    f = hit.mean()
    err = (1.8 * scale) ** 3 * math.sqrt(f * (1 - f) / len(x))
    assert abs(inside[j] - f * (1.8 * scale) ** 3) < 5 * err


def test_the_summary_interior_of_a_cylinder():
    p = _spheres(1.0)
    phi, note = _phi_interior(p, 1.5)
    assert note == "" and phi == pytest.approx(phi_in_cylinder(p, p.domain.interior(1.5)))
    empty, why = _phi_interior(p, 6.0)
    assert math.isnan(empty) and "empty" in why
