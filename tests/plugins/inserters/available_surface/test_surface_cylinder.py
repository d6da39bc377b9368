"""The available-surface inserter in a cylinder: the inscribed prism, containment, contacts.

The side wall is taken as the regular prism inscribed in it
(:mod:`regopack.plugins.inserters.available_surface.prism_wall`): every
particle must lie inside the true cylinder, inside the prism up to the
analyses' tolerance, touch an earlier particle, overlap none, and the
particles nearest the wall must come within the prism's sagitta of it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Cylinder
from regopack.geometry.population import Population
from regopack.packing.core import Packing
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.available_surface.inserter import (
    AvailableSurface,
    AvailableSurfaceConfig,
)
from regopack.plugins.inserters.available_surface.prism_wall import (
    MAX_FACETS,
    MIN_FACETS,
    facet_count,
    prism_wall,
    sagitta,
    wall_planes,
)
from regopack.plugins.shapes.polyhedra.shape import PolyhedronConfig, RandomPolyhedron
from regopack.plugins.shapes.sphere import Sphere
from regopack.testing import extreme_radii
from regopack.verification.polyhedra import separating_gap

FAST = settings(
    max_examples=20,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)


@given(
    radius=st.floats(1e-6, 1e6),
    gap=st.floats(1e-9, 10.0),
)
@settings(max_examples=200, deadline=None, derandomize=True)
def test_the_facet_count_is_the_least_that_keeps_the_gap(radius: float, gap: float) -> None:
    allowed = gap * radius
    n = facet_count(radius, allowed)
    assert n >= MIN_FACETS
    assert sagitta(radius, n) <= allowed
    if n > MIN_FACETS:
        assert sagitta(radius, n - 1) > allowed


def test_a_gap_that_needs_too_many_facets_is_refused_in_one_line() -> None:
    with pytest.raises(ConfigError, match=r"insertion\.wall_gap = 1e-09") as caught:
        prism_wall(0.0, 0.0, 1e6, 1.0, 1e-9)
    assert "\n" not in str(caught.value) and str(MAX_FACETS) in str(caught.value)


def _all_planes(wall: np.ndarray, qv: np.ndarray, r: float) -> np.ndarray:
    """Every facet's admissible plane, by brute force."""
    nf = int(wall[3])
    t = 2.0 * math.pi * np.arange(nf) / nf
    n = np.column_stack([np.cos(t), np.sin(t)])
    h = np.full(nf, r) if qv.shape[0] == 0 else (qv[:, :2] @ n.T).max(axis=0)
    return np.column_stack([n, np.zeros(nf), n @ wall[:2] + wall[2] - h])


@given(
    facets=st.integers(MIN_FACETS, 5000),
    rho=st.floats(0.0, 1.2),
    theta=st.sampled_from([0.0, 1e-12, -1e-12, math.pi, -math.pi, 1.0, -2.5]),
    reach=st.floats(1e-6, 3.0),
    sphere=st.booleans(),
    seed=st.integers(0, 1000),
)
@settings(max_examples=300, deadline=None, derandomize=True)
def test_every_facet_within_reach_is_listed(
    facets: int, rho: float, theta: float, reach: float, sphere: bool, seed: int
) -> None:
    """The angular window misses no facet, also about angle 0 (the window wraps there)."""
    radius = 1.0
    wall = np.array([0.3, -0.2, radius * math.cos(math.pi / facets), float(facets)])
    rng = np.random.default_rng(seed)
    qv = np.zeros((0, 3)) if sphere else rng.normal(size=(8, 3)) * 0.05
    r = 0.05 if sphere else 0.0
    c = np.array([0.3 + rho * math.cos(theta), -0.2 + rho * math.sin(theta), 0.7])
    got = wall_planes(wall, c, reach, qv, r)
    every = _all_planes(wall, qv, r)
    near = every[every[:, 3] - every[:, :2] @ c[:2] < reach]
    key = {tuple(np.round(row, 12)) for row in got}
    assert {tuple(np.round(row, 12)) for row in near} <= key
    # and nothing listed is a facet that is not one (rows of the brute force)
    assert key <= {tuple(np.round(row, 12)) for row in every}


scenes = st.fixed_dictionaries(
    {
        "seed": st.integers(0, 2**31 - 1),
        "n": st.integers(2, 30),
        "ratio": st.sampled_from([1.0, 10.0, 1e2]),
        "scale": st.sampled_from([1e-6, 1.0, 1e6]),
        "psi": st.sampled_from([0.01, 1.0, 1000.0]),
        "shape": st.sampled_from(["polyhedron", "sphere"]),
        "order": st.sampled_from(["paper", "sweep"]),
        "eta": st.sampled_from([0.0, 30.0]),
        "wide": st.sampled_from([2.2, 3.0, 6.0]),
        "gap": st.sampled_from([1e-3, 0.3]),
    }
)


def _pack(case: dict[str, Any]) -> Packing:
    rng = np.random.default_rng(case["seed"])
    n, scale = case["n"], case["scale"]
    radius = extreme_radii(n, case["ratio"], scale, rng)
    if case["shape"] == "sphere":
        shapes = Sphere().generate(radius, rng)
    else:
        shapes = RandomPolyhedron(PolyhedronConfig(psi=case["psi"])).generate(radius, rng)
    pop = Population(
        radius=radius, mineral=np.zeros(n, dtype=np.int64), mineral_names=("m",), shapes=shapes
    )
    rmax = float(shapes.circumradius.max())
    big = scale * max(2.0 * case["ratio"], float(np.cbrt(np.sum((radius / scale) ** 3))))
    r_cyl = max(case["wide"] * rmax, big)
    cyl = Cylinder.centred(r_cyl, 2.5 * r_cyl, (3.0 * scale, -2.0 * scale, scale))
    cfg = AvailableSurfaceConfig(order=case["order"], wall_gap=case["gap"])
    result = AvailableSurface(cfg).pack(pop, cyl, EtaController(EtaConfig(eta=case["eta"])), rng)
    return Packing.from_parts(pop, result, cyl, {}, case["seed"])


def _outer(packing: Packing, k: int) -> np.ndarray:
    """Radial distances from the axis of particle ``k``'s outermost points, and its z range."""
    d = packing.domain
    if packing.rounded:
        c = packing.centre[k]
        r = float(packing.solids.circumradius[k])
        return np.array([math.hypot(c[0] - d.cx, c[1] - d.cy) + r, c[2] - r, c[2] + r])
    v = packing.world_vertices(k)
    rad = np.hypot(v[:, 0] - d.cx, v[:, 1] - d.cy).max()
    return np.array([rad, v[:, 2].min(), v[:, 2].max()])


def check_cylinder(packing: Packing, gap: float) -> None:
    """Inside the cylinder, no overlap, every particle touching an earlier one, the wall met."""
    d = packing.domain
    assert isinstance(d, Cylinder)
    order = packing.placed_in_order()
    assert len(order) >= 1
    radius = packing.solids.circumradius
    size = float(np.cbrt(packing.solids.volume[order].min()))
    tol = 1e-9 * d.radius
    outer = np.array([_outer(packing, int(k)) for k in order])
    assert np.all(outer[:, 0] <= d.radius + tol), outer[:, 0].max() - d.radius
    assert np.all(outer[:, 1] >= d.zmin - tol) and np.all(outer[:, 2] <= d.zmax + tol)
    for a in range(len(order)):
        i = int(order[a])
        gaps = []
        for b in order[:a]:
            dist = float(np.linalg.norm(packing.centre[b] - packing.centre[i]))
            if dist > (radius[b] + radius[i]) * 1.000001:
                continue
            if packing.rounded:
                gaps.append(dist - float(radius[b] + radius[i]))
            else:
                pa, pb = packing.world_vertices(i), packing.world_vertices(int(b))
                gaps.append(separating_gap(pa, pb))
        if a == 0:
            continue
        assert gaps, f"particle {i} has no earlier particle within reach"
        assert min(gaps) >= -1e-8 * size, (i, min(gaps))
        assert min(gaps) == pytest.approx(0.0, abs=1e-8 * size), (i, min(gaps))


@FAST
@given(case=scenes)
def test_inside_overlap_free_and_touching_at_the_extremes(case: dict[str, Any]) -> None:
    packing = _pack(case)
    check_cylinder(packing, case["gap"])
    # inside the prism too, up to the analyses' tolerance (1e-9 R, over the smallest diameter)
    d_min = 2.0 * float(packing.radius.min())
    assert _facet_clearance(packing, case["gap"]).min() >= -1e-9 * packing.domain.radius / d_min


@pytest.mark.parametrize("shape", ["sphere", "polyhedron"])
def test_the_particles_reach_the_wall_within_its_gap(shape: str) -> None:
    """A dense packing's outermost particle lies within the prism's sagitta of the wall.

    (A particle touches the wall only where the free set it is drawn from
    ends on a facet, so one or two do, not most.) And none lies beyond the
    prism: removing the wall (a mutation) puts particles outside the cylinder.
    """
    case = {"seed": 5, "n": 150, "ratio": 3.0, "scale": 1.0, "psi": 1.0, "shape": shape,
            "order": "sweep", "eta": 0.0, "wide": 3.0, "gap": 1e-3}  # fmt: skip
    packing = _pack(case)
    check_cylinder(packing, 1e-3)
    d = packing.domain
    d_min = 2.0 * float(packing.radius.min())
    wall = prism_wall(d.cx, d.cy, d.radius, d_min, 1e-3)
    s = sagitta(d.radius, int(wall[3]))
    assert s <= 1e-3 * d_min
    order = packing.placed_in_order()
    outer = np.array([_outer(packing, int(k))[0] for k in order])
    assert d.radius - outer.max() <= s * (1 + 1e-9)


def test_a_looser_gap_takes_fewer_facets_and_keeps_the_particles_inside() -> None:
    case = {"seed": 2, "n": 60, "ratio": 2.0, "scale": 1.0, "psi": 1.0, "shape": "sphere",
            "order": "paper", "eta": 0.0, "wide": 3.0, "gap": 0.5}  # fmt: skip
    check_cylinder(_pack(case), 0.5)
    assert facet_count(10.0, 0.5) < facet_count(10.0, 1e-3)


@pytest.mark.parametrize("shape", ["sphere", "polyhedron"])
def test_a_scene_scaled_by_a_power_of_two_packs_the_same(shape: str) -> None:
    base = {"seed": 9, "n": 25, "ratio": 4.0, "scale": 1.0, "psi": 1.0, "shape": shape,
            "order": "sweep", "eta": 0.0, "wide": 3.0, "gap": 1e-3}  # fmt: skip
    a = _pack(base)
    b = _pack({**base, "scale": 2.0**-20})
    assert np.array_equal(a.insertion_index, b.insertion_index)
    assert np.array_equal(a.centre * 2.0**-20, b.centre, equal_nan=True)


def test_the_same_seed_gives_the_same_packing() -> None:
    case = {"seed": 4, "n": 30, "ratio": 5.0, "scale": 1.0, "psi": 0.5, "shape": "polyhedron",
            "order": "paper", "eta": 0.0, "wide": 3.0, "gap": 1e-3}  # fmt: skip
    a, b = _pack(case), _pack(case)
    assert np.array_equal(a.centre, b.centre, equal_nan=True)


def _facet_clearance(packing: Packing, gap: float) -> np.ndarray:
    """Each particle's distance inside the prism's nearest facet, in its own diameters."""
    d = packing.domain
    wall = prism_wall(d.cx, d.cy, d.radius, 2.0 * float(packing.radius.min()), gap)
    nf = int(wall[3])
    t = 2.0 * math.pi * np.arange(nf) / nf
    n = np.column_stack([np.cos(t), np.sin(t)])
    out = []
    for k in packing.placed_in_order():
        k = int(k)
        if packing.rounded:
            reach = n @ (packing.centre[k, :2] - wall[:2]) + packing.solids.circumradius[k]
        else:
            reach = (n @ (packing.world_vertices(k)[:, :2] - wall[:2]).T).max(axis=1)
        out.append((wall[2] - reach.max()) / (2.0 * float(packing.radius[k])))
    return np.array(out)


@pytest.mark.parametrize("shape", ["sphere", "polyhedron"])
def test_the_packing_control_moves_every_facet_in_by_its_margin(shape: str) -> None:
    """With ``eta`` the margin keeps each particle at least ``(eta - 1) / 100`` diameters
    inside every facet, as inside the floor and the roof: the facets listed for an
    analysis are those within its reach *plus* the margin (a facet just beyond the
    envelope comes within it once moved in)."""
    eta = 30.0
    case = {"seed": 3, "n": 25, "ratio": 1.0, "scale": 1.0, "psi": 1000.0, "shape": shape,
            "order": "paper", "eta": eta, "wide": 3.0, "gap": 1e-3}  # fmt: skip
    clearance = _facet_clearance(_pack(case), 1e-3)[1:]  # the first is placed as it fits
    assert clearance.size > 0
    assert clearance.min() >= (eta - 1.0) / 100.0 * (1.0 - 1e-9), clearance.min()


@pytest.mark.parametrize("order", ["paper", "sweep"])
def test_a_sphere_wider_than_the_prism_is_refused_though_it_fits_the_cylinder(order: str) -> None:
    """The first particle is placed without an analysis, at the axis: the prism alone
    refuses a sphere between the facets' distance and the radius; the others go in,
    inside the prism."""
    rng = np.random.default_rng(1)
    radius = np.array([1.0] + [0.3] * 12)
    pop = Population(
        radius=radius, mineral=np.zeros(13, dtype=np.int64), mineral_names=("m",),
        shapes=Sphere().generate(radius, rng),
    )  # fmt: skip
    cyl = Cylinder.centred(1.0003, 6.0, (5.0, -3.0, 0.0))
    cfg = AvailableSurfaceConfig(order=order)
    result = AvailableSurface(cfg).pack(pop, cyl, EtaController(EtaConfig(eta=0.0)), rng)
    packing = Packing.from_parts(pop, result, cyl, {}, 1)
    assert packing.insertion_index[0] < 0
    assert len(packing.placed_in_order()) == 12
    check_cylinder(packing, 1e-3)
    assert _facet_clearance(packing, 1e-3).min() >= -1e-9


@pytest.mark.parametrize(
    ("value", "words"),
    [(0.0, "greater than 0"), (2.0, "less than or equal to 1"), ("abc", "valid number")],
)
def test_a_bad_wall_gap_is_refused_in_one_line_naming_the_field(value: object, words: str) -> None:
    from pathlib import Path

    import regopack

    example = Path(__file__).resolve().parents[4] / "docs" / "examples" / "cylinder.toml"
    with pytest.raises(ConfigError, match=words) as caught:
        regopack.scene(example, **{"insertion.wall_gap": value})
    assert "insertion.wall_gap" in str(caught.value) and "\n" not in str(caught.value)
