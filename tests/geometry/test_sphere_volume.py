"""The volume of a sphere inside a box, against exact cases and Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from regopack.geometry.sphere_volume import disk_in_rectangle, sphere_in_box


@pytest.mark.parametrize(
    ("lo", "fraction"),
    [((-5, -5, -5), 1.0), ((0, -5, -5), 0.5), ((0, 0, -5), 0.25), ((0, 0, 0), 0.125)],
)
def test_whole_half_quarter_and_eighth_spheres(lo: tuple[float, ...], fraction: float) -> None:
    v = sphere_in_box([0, 0, 0], 2.0, lo, (5, 5, 5))
    assert v == pytest.approx(fraction * 4 / 3 * math.pi * 8, rel=1e-9)


def test_a_disk_in_a_rectangle_matches_its_quadrants() -> None:
    assert disk_in_rectangle(1.0, 0, 1, 0, 1) == pytest.approx(math.pi / 4, rel=1e-12)
    assert disk_in_rectangle(1.0, -1, 1, 0.5, 2) == pytest.approx(
        math.acos(0.5) - 0.5 * math.sqrt(0.75), rel=1e-12
    )


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_cuts_agree_with_monte_carlo(seed: int) -> None:
    rng = np.random.default_rng(seed)
    c = rng.uniform(-1, 1, 3)
    r = rng.uniform(0.5, 1.5)
    lo = c + rng.uniform(-1.2 * r, 0.2 * r, 3)
    hi = lo + rng.uniform(0.5 * r, 2.0 * r, 3)
    v = sphere_in_box(c, r, lo, hi)
    n = 400_000
    p = rng.uniform(c - r, c + r, (n, 3))
    inside = (np.sum((p - c) ** 2, axis=1) < r * r) & np.all((p >= lo) & (p <= hi), axis=1)
    share = inside.mean()
    sigma = math.sqrt(share * (1 - share) / n) * (2 * r) ** 3
    assert abs(v - share * (2 * r) ** 3) < 5 * sigma + 1e-12


@pytest.mark.parametrize("seed", range(3))
def test_a_ball_one_face_cuts_agrees_with_the_quadrature(seed: int) -> None:
    """The closed-form cap agrees with the disks integrated over height (any face, either side)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array([-2.0, -3.0, -1.0]), np.array([2.0, 1.0, 4.0])
    for _ in range(200):
        r = float(rng.uniform(0.05, 0.9))
        axis, side = int(rng.integers(3)), int(rng.integers(2))
        c = 0.5 * (lo + hi)
        c[axis] = (hi if side else lo)[axis] + rng.uniform(-r, r)  # only this face cuts
        b0, b1 = lo - c, hi - c
        z0, z1 = max(b0[2], -r), min(b1[2], r)
        # the heights where the disk's edge meets a side: the integrand's kinks
        kinks = [math.sqrt(r * r - d * d) for d in (*b0[:2], *b1[:2]) if abs(d) < r]
        breaks = sorted({p for k in kinks for p in (k, -k) if z0 < p < z1}) or None
        ref = quad(
            lambda z, b0=b0, b1=b1, r=r: disk_in_rectangle(
                math.sqrt(max(r * r - z * z, 0.0)), b0[0], b1[0], b0[1], b1[1]
            ),
            z0,
            z1,
            epsabs=0.0,
            epsrel=1e-12,
            limit=400,
            points=breaks,
        )[0]
        assert sphere_in_box(c, r, lo, hi) == pytest.approx(ref, rel=1e-9)


@pytest.mark.parametrize("r", [2.0**-20, 2.0**-10, 1.0, 2.0**10])
@pytest.mark.parametrize("gap", [2.0**-10, 2.0**-20, 2.0**-30, 2.0**-40])
def test_a_ball_barely_inside_one_face_keeps_its_cap(r: float, gap: float) -> None:
    """A ball whose centre is outside one face by ``(1 - gap) r`` holds a cap of height ``gap r``.

    The ball less the outer cap cancels to rounding there: it gave 0 or a
    negative volume. (Powers of two: the centre and the cap height are exact.)
    """
    h = gap * r
    cap = math.pi * h * h * (3.0 * r - h) / 3.0
    lo, hi = np.array([0.0, -8.0, -8.0]) * r, np.array([8.0, 8.0, 8.0]) * r
    for axis, sign in ((0, -1.0), (2, 1.0)):
        c = 0.5 * (lo + hi)
        c[axis] = (lo if sign < 0 else hi)[axis] + sign * (r - h)
        assert sphere_in_box(c, r, lo, hi) == pytest.approx(cap, rel=1e-6, abs=0.0)
