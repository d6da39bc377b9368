"""The vertices' certificate that caps cover a sphere, against the circles' exact arcs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.inserters.available_surface.cap_cover import (
    COVERED,
    OPEN,
    UNSURE,
    cover_by_vertices,
)
from regopack.plugins.inserters.available_surface.spheres import (
    covers,
    drop_contained,
    free_arcs,
    is_free,
)


def _caps(normals: np.ndarray, h: np.ndarray) -> np.ndarray:
    caps = np.empty((len(h), 4))
    caps[:, :3] = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    caps[:, 3] = h
    return caps


def _random_caps(seed: int, scale: float) -> tuple[np.ndarray, int]:
    """Caps of angular radii 0.2-1.4 about random axes, some of them walls along an axis."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    normals = rng.normal(size=(n, 3))
    for m in range(n):
        if rng.random() < 0.1:
            normals[m] = 0.0
            normals[m, rng.integers(0, 3)] = rng.choice([-1.0, 1.0])
    caps = _caps(normals, scale * np.cos(rng.uniform(0.2, 1.4, n)))
    return caps, drop_contained(caps, n, scale, 1e-12 * scale)


@settings(max_examples=400, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1e-6, 1e-3, 1.0, 7.0, 1e6]))
def test_covered_means_no_free_arc_and_a_strict_cover(seed: int, scale: float) -> None:
    caps, n = _random_caps(seed, scale)
    tau = 1e-12 * scale
    answer = cover_by_vertices(caps, n, scale, tau, 1e-9 * scale)
    no_arc = free_arcs(caps, n, scale, tau).shape[0] == 0
    if answer == COVERED:
        assert no_arc
        assert covers(caps, n, scale, 1e-9 * scale)
    if answer == OPEN:
        assert not no_arc  # a free vertex is a free point beside some circle
    if no_arc and covers(caps, n, scale, 1e-9 * scale):
        assert answer != OPEN


def test_the_certificate_decides_almost_every_random_set_as_the_arcs_do() -> None:
    decided = agree = 0
    for seed in range(3000):
        caps, n = _random_caps(seed, 1.0)
        answer = cover_by_vertices(caps, n, 1.0, 1e-12, 1e-9)
        if answer == UNSURE:
            continue
        decided += 1
        agree += (answer == COVERED) == (free_arcs(caps, n, 1.0, 1e-12).shape[0] == 0)
    assert decided >= 2970 and agree == decided


def test_covered_points_lie_deeper_than_the_margin() -> None:
    rng = np.random.default_rng(3)
    points = rng.normal(size=(20_000, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    shown = 0
    for seed in range(400):
        caps, n = _random_caps(seed, 1.0)
        if cover_by_vertices(caps, n, 1.0, 0.0, 1e-3) != COVERED:
            continue
        shown += 1
        depth = (points @ caps[:n, :3].T - caps[:n, 3]).max(axis=1)
        assert depth.min() > 1e-3
    assert shown > 20


def _cube(h: float) -> np.ndarray:
    rows = [(s * (a == 0), s * (a == 1), s * (a == 2)) for a in range(3) for s in (-1.0, 1.0)]
    return _caps(np.array(rows, dtype=float), np.full(6, h))


def test_touching_caps_are_never_certified() -> None:
    corner = 1.0 / math.sqrt(3.0)
    assert cover_by_vertices(_cube(0.999 * corner), 6, 1.0, 0.0, 1e-9) == COVERED
    # the faces of a cube that meet exactly at its corners: each corner is a point left
    assert cover_by_vertices(_cube(corner), 6, 1.0, 0.0, 0.0) != COVERED
    assert cover_by_vertices(_cube(0.999 * corner), 6, 1.0, 0.0, 1e-3) != COVERED
    assert cover_by_vertices(_cube(0.999 * corner)[:5], 5, 1.0, 0.0, 0.0) == OPEN
    # two hemispheres meet along the equator: the equator is left (a tangency of planes)
    halves = _caps(np.array([(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]), np.zeros(2))
    assert cover_by_vertices(halves, 2, 1.0, 0.0, 0.0) != COVERED
    assert cover_by_vertices(halves - [0, 0, 0, 1e-3], 2, 1.0, 0.0, 1e-6) != OPEN
    # two equal caps that touch at one point, with a third over that point: still a gap
    pair = _caps(np.array([(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)]), np.zeros(2))
    assert cover_by_vertices(pair, 2, 1.0, 1e-14, 0.0) != COVERED


def test_a_circle_that_meets_no_other_is_inside_a_cap_or_free() -> None:
    # a small cap deep inside a large one: its circle meets no other and is covered
    inside = _caps(np.array([(0.0, 0.0, 1.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]),
                   np.array([0.95, -0.5, 0.2]))  # fmt: skip
    assert cover_by_vertices(inside, 3, 1.0, 0.0, 1e-9) == COVERED
    # a small cap alone in the free band between two others: its circle is free
    band = _caps(np.array([(0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)]),
                 np.array([0.3, 0.3, 0.95]))  # fmt: skip
    assert cover_by_vertices(band, 3, 1.0, 0.0, 0.0) == OPEN
    assert not is_free(band, 3, 0.0, 0.0, 1.0, 0.0)
    assert cover_by_vertices(np.zeros((0, 4)), 0, 1.0, 0.0, 0.0) == OPEN
    whole = _caps(np.array([(1.0, 0.0, 0.0)]), np.array([-1.0 - 1e-6]))
    assert cover_by_vertices(whole, 1, 1.0, 0.0, 0.0) == COVERED


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_the_answer_does_not_depend_on_the_unit(scale: float) -> None:
    for seed in range(200):
        caps, n = _random_caps(seed, 1.0)
        scaled = caps.copy()
        scaled[:, 3] *= scale
        one = cover_by_vertices(caps, n, 1.0, 1e-12, 1e-9)
        assert cover_by_vertices(scaled, n, scale, 1e-12 * scale, 1e-9 * scale) == one


@pytest.mark.parametrize("pole", [1.0, -1.0])
def test_a_hole_at_either_pole_is_found_from_either_vertex_of_a_pair(pole: float) -> None:
    # three caps about the equator leave small holes at both poles; a fourth cap
    # covers one pole, so the hole left is bounded by the other vertex of each pair
    angles = np.radians([0.0, 120.0, 240.0])
    normals = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(3)])
    h = np.full(3, math.cos(math.radians(88.0)))  # angular radii 88 degrees: not to the pole
    ring = _caps(normals, h)
    cover = _caps(np.array([(0.0, 0.0, pole)]), np.array([0.0]))
    caps = np.vstack([ring, cover])
    assert cover_by_vertices(caps, 4, 1.0, 0.0, 0.0) == OPEN
    assert free_arcs(caps, 4, 1.0, 1e-12).shape[0] > 0
    plug = _caps(np.array([(0.0, 0.0, -pole)]), np.array([0.9]))
    assert cover_by_vertices(np.vstack([caps, plug]), 5, 1.0, 0.0, 1e-9) == COVERED


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_caps_all_shrunk_to_nothing_leave_the_whole_sphere_free(scale: float) -> None:
    # caps narrower than the shrinking (h < R <= h + shrink + margin) cover nothing:
    # the uncovered set is the whole sphere, which has no boundary to find
    caps = _caps(np.array([(0.0, 0.0, 1.0), (1.0, 0.0, 0.0)]), np.full(2, (1.0 - 5e-10) * scale))
    tau = 1e-12 * scale
    assert free_arcs(caps, 2, scale, tau).shape[0] > 0
    assert cover_by_vertices(caps, 2, scale, tau, 1e-9 * scale) == OPEN
    assert not covers(caps, 2, scale, 1e-9 * scale)
    # one cap left after the shrinking decides as before
    wide = np.vstack([caps, _caps(np.array([(0.0, 1.0, 0.0)]), np.array([0.5 * scale]))])
    assert cover_by_vertices(wide, 3, scale, tau, 1e-9 * scale) == OPEN


def test_a_sphere_whose_caps_are_all_narrower_than_the_margin_is_analysed() -> None:
    # a periodic cube just under two diameters wide: the first sphere's own images cut
    # six caps from its sphere of centres, each narrower than the certificate's margin;
    # the other spheres still touch it (as the exact arcs say)
    import regopack

    d = 10.0
    side = 2.0 * d * (1.0 - 5e-10)
    overrides = {f"phases.{i}.shape": {"kind": "sphere"} for i in range(6)}
    overrides.update(
        {
            "size": {"kind": "monodisperse", "d": d},
            "domain.kind": "periodic-box",
            "domain.width": side,
            "domain.height": side,
            "domain.depth": side,
            "insertion.order": "paper",
            "count": 4,
        }
    )
    packing = regopack.pack(regopack.scene("dem3d", **overrides), verify=False)
    assert np.isfinite(np.asarray(packing.centre)).all()
