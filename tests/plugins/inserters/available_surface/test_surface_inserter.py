"""The available-surface inserter: touching, overlap-free, contained, reproducible packings."""

from __future__ import annotations

import tracemalloc
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import regopack
from regopack.base.errors import ConfigError
from regopack.packing.core import Packing
from regopack.plugins.inserters.available_surface import sweep as sweep_module
from regopack.verification.polyhedra import separating_gap, verify_polyhedra


def scene(**changes: Any) -> dict[str, Any]:
    base: dict[str, Any] = {
        "name": "surface",
        "seed": 3,
        "count": 60,
        "domain": {"kind": "box", "width": 30.0, "height": 30.0, "depth": 30.0},
        "size": {"kind": "uniform", "d_min": 3.0, "d_max": 8.0},
        "phases": [
            {"name": "pyroxene", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 0.25}},
            {"name": "ilmenite", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 15.0}},
        ],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }
    base.update(changes)
    return base


def _pack(data: dict[str, Any]) -> Packing:
    packing = regopack.pack(data, verify=False)
    assert packing.dimension == 3
    return packing


def _check(packing: Packing) -> None:
    """Overlap-free and inside the box (the oracle), and each particle touches an earlier one."""
    order = packing.placed_in_order()
    solids = [packing.world_vertices(int(j)) for j in order]
    box = packing.domain
    report = verify_polyhedra(
        solids, None, [box.xmin, box.ymin, box.zmin], [box.xmax, box.ymax, box.zmax]
    )
    assert report.ok, str(report)
    size = float(np.cbrt(packing.solids.volume.min()))
    centre = packing.centre[order]
    radius = packing.solids.circumradius[order]
    for a in range(1, len(order)):
        # only particles whose circumspheres meet can touch
        reach = (
            np.linalg.norm(centre[:a] - centre[a], axis=1) <= (radius[:a] + radius[a]) * 1.000001
        )
        gaps = [separating_gap(solids[a], solids[b]) for b in np.flatnonzero(reach)]
        assert min(gaps) == pytest.approx(0.0, abs=1e-8 * size)  # touches its candidate


def test_a_box_of_polyhedra_is_touching_and_overlap_free() -> None:
    packing = _pack(scene())
    assert packing.n_placed >= 50
    _check(packing)
    assert packing.stats["candidate_analyses"] >= packing.n_placed - 1


def test_same_scene_and_seed_give_the_same_packing() -> None:
    a, b = _pack(scene(count=30)), _pack(scene(count=30))
    assert np.array_equal(a.centre, b.centre, equal_nan=True)
    assert np.array_equal(a.insertion_index, b.insertion_index)
    c = _pack(scene(count=30, seed=4))
    assert not np.array_equal(a.centre, c.centre, equal_nan=True)


def test_the_first_particle_sits_at_the_centre_and_too_large_ones_are_refused() -> None:
    packing = _pack(
        scene(
            count=8,
            size={"kind": "uniform", "d_min": 3.0, "d_max": 60.0},
            domain={"kind": "box", "width": 40.0, "height": 40.0, "depth": 40.0},
        )
    )
    first = packing.placed_in_order()[0]
    assert packing.centre[first].tolist() == [0.0, 0.0, 0.0]
    too_big = packing.solids.circumradius > 40.0
    assert not packing.placed[too_big].any()


@settings(max_examples=6, deadline=None)
@given(
    psi=st.sampled_from([0.01, 1.0, 1000.0]),
    a=st.sampled_from([0.05, 1.0]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    ratio=st.sampled_from([1.5, 30.0, 1000.0]),
    order=st.sampled_from(["paper", "sweep"]),
)
def test_extremes_stay_overlap_free(
    psi: float, a: float, scale: float, ratio: float, order: str
) -> None:
    d_max = 4.0 * scale
    data = scene(
        count=14,
        insertion={"kind": "available-surface", "order": order},
        domain={"kind": "box", "width": 12 * d_max, "height": 12 * d_max, "depth": 12 * d_max},
        size={"kind": "uniform", "d_min": d_max / ratio, "d_max": d_max},
        phases=[
            {"name": "a", "fraction": 1.0, "shape": {"kind": "polyhedron", "psi": psi, "a": a}}
        ],
    )
    _check(_pack(data))


def sweep_scene(**changes: Any) -> dict[str, Any]:
    """A tall box packed in the sweep order."""
    data = scene(
        count=200,
        domain={"kind": "box", "width": 12.0, "height": 30.0, "depth": 12.0},
        size={"kind": "uniform", "d_min": 1.5, "d_max": 4.0},
        insertion={"kind": "available-surface", "order": "sweep", "zone": 6.0},
    )
    data.update(changes)
    return data


@pytest.fixture(scope="module")
def swept() -> Packing:
    return _pack(sweep_scene())


def test_the_sweep_is_touching_overlap_free_and_starts_at_the_bottom(swept: Packing) -> None:
    _check(swept)
    order = swept.placed_in_order()
    first = int(order[0])
    verts = swept.world_vertices(first)
    assert float(verts[:, 2].min()) == pytest.approx(swept.domain.zmin, abs=1e-9)
    assert swept.centre[first, :2].tolist() == [0.0, 0.0]
    stats = swept.stats
    assert stats["zone"] == 6.0
    assert stats["refused"] + stats["not_offered"] + swept.n_placed == swept.n_particles


def test_the_sweep_places_each_particle_near_the_rising_front(swept: Packing) -> None:
    # a particle lands touching a candidate of the zone, whose bins span the zone
    # height below the zone's top; a particle placed above the top sits at most
    # two circumradii above it: so nothing lands in an old pore far below
    order = swept.placed_in_order()
    z = swept.centre[order, 2]
    reach = 2.0 * float(swept.solids.circumradius.max())
    front = np.maximum.accumulate(z)
    assert np.all(z[1:] >= front[:-1] - 6.0 - 2.0 * reach)
    # the front has risen through the box: the last particles sit in its upper half
    assert np.median(z[-20:]) > 0.0


def test_the_sweep_is_reproducible() -> None:
    a = _pack(sweep_scene(count=40))
    b = _pack(sweep_scene(count=40))
    assert np.array_equal(a.centre, b.centre, equal_nan=True)
    assert np.array_equal(a.insertion_index, b.insertion_index)


def _check_periodic(packing: Packing) -> None:
    """The oracle on all periodic images, and each particle touches an earlier image."""
    report = regopack.verify(packing)
    assert report.ok, str(report)
    box = packing.domain
    period = np.array(box.period)
    order = packing.placed_in_order()
    size = float(np.cbrt(packing.solids.volume.min()))
    radius = packing.solids.circumradius
    for a in range(1, len(order)):
        pa = packing.world_vertices(int(order[a]))
        gaps = []
        for b in order[:a]:
            pb = packing.world_vertices(int(b))
            for shift in np.array(np.meshgrid(*[[-1, 0, 1]] * 3)).reshape(3, -1).T * period:
                d = packing.centre[b] + shift - packing.centre[order[a]]
                if np.linalg.norm(d) <= (radius[b] + radius[order[a]]) * 1.000001:
                    gaps.append(separating_gap(pa, pb + shift))
        assert min(gaps) == pytest.approx(0.0, abs=1e-8 * size)
    c = packing.centre[order]
    lo = np.array([box.xmin, box.ymin, box.zmin])
    assert np.all(c >= lo) and np.all(c < lo + period)


@pytest.mark.parametrize("order", ["paper", "sweep"])
def test_a_periodic_box_is_packed_across_its_faces(order: str) -> None:
    # a small box: particles cross the faces and meet their own images
    out = regopack.pack_and_summarise(
        scene(
            count=40,
            domain={"kind": "periodic-box", "width": 12.0, "height": 12.0, "depth": 12.0},
            size={"kind": "uniform", "d_min": 2.5, "d_max": 6.0},
            insertion={"kind": "available-surface", "order": order},
        ),
        verify=True,
    )
    packing = out.packing
    assert packing.dimension == 3
    assert packing.n_placed >= 15
    assert out.summary["verify"]["ok"]
    # no walls: the interior is the whole cell, and every part of a solid counts once
    assert out.summary["phi_interior"] == out.summary["phi_domain"] == packing.phi
    _check_periodic(packing)
    lo = np.array([packing.domain.xmin, packing.domain.ymin, packing.domain.zmin])
    hi = lo + np.array(packing.domain.period)
    crossing = [
        j
        for j in packing.placed_in_order()
        if np.any(packing.world_vertices(int(j)) < lo)
        or np.any(packing.world_vertices(int(j)) > hi)
    ]
    assert crossing


def test_a_particle_that_meets_its_own_periodic_images_is_not_placed() -> None:
    # a slab thinner than some of the particles: those fit nowhere, the others are placed
    packing = _pack(
        scene(
            count=25,
            seed=1,
            domain={"kind": "periodic-box", "width": 14.0, "height": 14.0, "depth": 2.2},
            size={"kind": "uniform", "d_min": 1.6, "d_max": 2.6},
        )
    )
    assert 0 < packing.n_placed < 25
    period = np.array(packing.domain.size)
    size = float(np.cbrt(packing.solids.volume.min()))
    shifts = [np.array(s) for s in np.ndindex(5, 5, 5)]
    for j in packing.placed_in_order():
        solid = packing.world_vertices(int(j))
        for s in shifts:
            t = (s - 2) * period
            if np.any(t != 0):
                assert separating_gap(solid, solid + t) >= -1e-9 * size


@pytest.mark.parametrize("order", ["paper", "sweep"])
def test_eta_keeps_each_particle_its_margin_from_all_but_its_candidate(order: str) -> None:
    eta = 50.0
    packing = _pack(
        scene(
            count=40,
            density={"kind": "eta", "eta": eta},
            insertion={"kind": "available-surface", "order": order},
        )
    )
    assert packing.n_placed >= 20
    order_ = packing.placed_in_order()
    solids = [packing.world_vertices(int(j)) for j in order_]
    size = float(np.cbrt(packing.solids.volume.min()))
    box = packing.domain
    lo = np.array([box.xmin, box.ymin, box.zmin])
    hi = np.array([box.xmax, box.ymax, box.zmax])
    for a in range(1, len(order_)):
        # margin >= (eta - 1) / 100 of the equivalent diameter (xi >= 0)
        margin = (eta - 1.0) / 100.0 * 2.0 * float(packing.radius[order_[a]])
        gaps = sorted(separating_gap(solids[a], solids[b]) for b in range(a))
        assert gaps[0] == pytest.approx(0.0, abs=1e-8 * size)  # touches its candidate
        if len(gaps) > 1:
            assert gaps[1] >= margin * (1 - 1e-9)  # and keeps away from every other
        assert np.all(solids[a] >= lo + margin * (1 - 1e-9))
        assert np.all(solids[a] <= hi - margin * (1 - 1e-9))
    # eta = 0 places more in the same box
    assert _pack(scene(count=40)).n_placed > packing.n_placed or packing.n_placed == 40


def column_scene(strip: float, closing: str = "tail", kind: str = "box", **changes: Any) -> dict:
    """A wide box packed in the sweep order with columns about ``strip`` wide."""
    data = scene(
        count=400,
        domain={"kind": kind, "width": 24.0, "height": 14.0, "depth": 24.0},
        size={"kind": "uniform", "d_min": 1.5, "d_max": 4.0},
        insertion={
            "kind": "available-surface",
            "order": "sweep",
            "zone": 5.0,
            "strip": strip,
            "closing": closing,
        },
    )
    data.update(changes)
    return data


@pytest.mark.parametrize(
    "closing",
    # 7 s each: the paced and prompt closings' columns run in the default suite through
    # the screening-tree and periodic tests
    [
        "tail",
        pytest.param("paced", marks=pytest.mark.slow),
        pytest.param("prompt", marks=pytest.mark.slow),
    ],
)
def test_columns_pack_touching_overlap_free_and_contained(closing: str) -> None:
    packing = _pack(column_scene(8.0, closing))
    stats = packing.stats
    assert stats["strips"] == 9
    _check(packing)
    assert stats["refused"] + stats["not_offered"] + packing.n_placed == packing.n_particles
    assert packing.phi > 0.3


def test_columns_pack_a_periodic_box_across_its_faces() -> None:
    packing = _pack(column_scene(8.0, "paced", kind="periodic-box", count=90))
    assert packing.stats["strips"] == 9
    _check_periodic(packing)


def test_one_column_is_the_sweep_without_columns() -> None:
    a = _pack(column_scene(0.0, count=80))
    for strip in (24.0, 40.0):
        b = _pack(column_scene(strip, count=80))
        assert b.stats["strips"] == 1
        assert np.array_equal(a.centre, b.centre, equal_nan=True)
        assert np.array_equal(a.insertion_index, b.insertion_index)


def test_columns_are_reproducible_and_rise_together() -> None:
    a = _pack(column_scene(8.0))
    b = _pack(column_scene(8.0))
    assert np.array_equal(a.centre, b.centre, equal_nan=True)
    order = a.placed_in_order()
    c = a.centre[order]
    ij = np.minimum(((c[:, :2] + 12.0) // 8.0).astype(int), 2)
    column = ij[:, 1] * 3 + ij[:, 0]
    # the first half of the placements lies low in every column (the fronts rise
    # together): no column has run ahead to the top while another stays at the bottom
    half = c[: len(c) // 2]
    col = column[: len(c) // 2]
    heights = [np.median(half[col == k, 2]) for k in range(9) if np.any(col == k)]
    assert len(heights) == 9
    assert max(heights) - min(heights) < 5.0 + 2.0 * float(a.solids.circumradius.max())


def test_a_column_searches_only_its_own_candidates() -> None:
    """Each particle is offered to one column's zone: fewer analyses than one zone over all."""
    one = _pack(column_scene(0.0))
    nine = _pack(column_scene(8.0))
    per_one = one.stats["candidate_analyses"] / one.n_placed
    per_nine = nine.stats["candidate_analyses"] / nine.n_placed
    assert per_nine < 0.9 * per_one  # 5.3 against 7.0


def _small_zone(strip: float, kind: str = "box", count: int = 250) -> dict[str, Any]:
    data = column_scene(strip, "tail", kind=kind, count=count)
    data["insertion"]["zone"] = 0.5
    return data


def _capture(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    seen: dict[str, Any] = {"exact": 0}
    run, exhaustive = sweep_module.SurfaceSweep.run, sweep_module.SurfaceSweep._exhaustive

    def capture_run(self: Any, *args: Any, **kwargs: Any) -> None:
        seen["sweep"] = self
        run(self, *args, **kwargs)

    def count_exhaustive(self: Any, i: int, rng: np.random.Generator) -> Any:
        x = exhaustive(self, i, rng)
        seen["exact"] += x is not None
        return x

    monkeypatch.setattr(sweep_module.SurfaceSweep, "run", capture_run)
    monkeypatch.setattr(sweep_module.SurfaceSweep, "_exhaustive", count_exhaustive)
    return seen


def test_columns_do_not_multiply_the_bins() -> None:
    """A tiny zone gives 2^20 bins: columns file their candidates only in the bins used."""

    def peak(strip: float) -> int:
        data = column_scene(strip, count=3)
        data["insertion"]["zone"] = 1e-300
        tracemalloc.start()
        try:
            regopack.pack(data, verify=False)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    regopack.pack(column_scene(8.0, count=3), verify=False)  # compile outside the count
    one = peak(0.0)
    assert peak(8.0) < 2 * one  # 605 MB against 67 MB when every column held every bin


def test_every_column_holding_candidates_gets_a_zone(monkeypatch: pytest.MonkeyPatch) -> None:
    """A periodic box with a zone below the particles' size: every column gets its zone."""
    seen = _capture(monkeypatch)
    regopack.pack(_small_zone(8.0, "periodic-box"), verify=False)
    sweep = seen["sweep"]
    c = sweep.state.count
    for k, zone in enumerate(sweep.zones):
        if np.any(sweep.tile[:c] == k):
            assert zone.seeded, f"column {k} holds candidates but has no zone"


def test_columns_place_from_the_zone_not_from_the_exact_pass(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A zone below the particles' size is raised to two circumradii with columns.

    A column could otherwise not reach its next candidate within one zone of
    rises and placed its particles by the exact pass (165 of 248).
    """
    seen = _capture(monkeypatch)
    packing = regopack.pack(_small_zone(8.0), verify=False)
    assert seen["sweep"].zones and len(seen["sweep"].zones) == 9
    assert seen["exact"] <= 0.1 * packing.n_placed


def _screened_by_mask(self: Any, i: int, rng: np.random.Generator) -> Any:
    """The screened search listing every placed candidate, as the sweep did before its trees."""
    st = self.state
    c = st.count
    open_ = (self.flag[:c] == sweep_module.ACTIVE) & (st.radius[i] < self.t * st.rmin[:c])
    open_ &= self.tile[:c] == self.cur
    return st.scan(np.flatnonzero(open_), rng, tried=self.tried)


def test_the_screening_trees_search_the_candidates_a_full_listing_finds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = column_scene(8.0, "paced", count=200)
    seen = _capture(monkeypatch)
    fast = regopack.pack(data, verify=False)
    sweep = seen["sweep"]
    c = sweep.state.count
    for k, zone in enumerate(sweep.zones):
        members = zone.members[: zone.size]
        assert np.array_equal(members, np.flatnonzero(sweep.tile[:c] == k))
        leaves = zone.members.shape[0]
        leaf = zone.tree[leaves : leaves + zone.size]
        active = sweep.flag[members] == sweep_module.ACTIVE
        assert np.array_equal(leaf[active], sweep.state.rmin[members[active]])
        assert np.all(leaf[~active] == -np.inf)
        inner = np.arange(1, leaves)
        assert np.array_equal(
            zone.tree[inner], np.maximum(zone.tree[2 * inner], zone.tree[2 * inner + 1])
        )
    monkeypatch.setattr(sweep_module.SurfaceSweep, "_screened", _screened_by_mask)
    listed = regopack.pack(data, verify=False)
    assert np.array_equal(fast.centre, listed.centre, equal_nan=True)


def faceted_scene(kind: str = "box", count: int = 320, **insertion: Any) -> dict[str, Any]:
    """A cube of spheres packed by the sweep with a faceted front of one pyramid."""
    return scene(
        count=count,
        domain={"kind": kind, "width": 16.0, "height": 16.0, "depth": 16.0},
        size={"kind": "uniform", "d_min": 1.5, "d_max": 3.0},
        phases=[{"name": "s", "fraction": 1.0, "shape": {"kind": "sphere"}}],
        insertion={
            "kind": "available-surface",
            "order": "sweep",
            "zone": 4.0,
            "front": "faceted",
            "facet": 16.0,
            **insertion,
        },
    )


def _order_correlations(packing: Packing) -> dict[str, float]:
    """Rank correlations of the insertion order with ``z``, the faceted level and ``g``."""
    order = packing.placed_in_order()
    c = packing.centre[order]
    g = np.max(np.abs(c[:, :2]), axis=1)  # from the pyramid's axis (the box's middle)
    level = (c[:, 2] - packing.domain.zmin + np.sqrt(2.0) * g) / np.sqrt(3.0)
    n = np.arange(len(order))
    return {
        name: _rank_correlation(n, values)
        for name, values in (("z", c[:, 2]), ("level", level), ("g", g))
    }


def _rank_correlation(a: np.ndarray, b: np.ndarray) -> float:
    ra = np.argsort(np.argsort(a)).astype(float)
    rb = np.argsort(np.argsort(b)).astype(float)
    return float(np.corrcoef(ra, rb)[0, 1])


def test_a_faceted_front_rises_along_its_pyramids_not_along_z() -> None:
    faceted = _pack(faceted_scene())
    assert regopack.verify(faceted).ok
    first = faceted.placed_in_order()[0]
    centre = faceted.centre[first]
    # the first at the apex of the pyramid: on the floor below the box's centre
    assert centre[:2].tolist() == [0.0, 0.0]
    assert centre[2] == pytest.approx(faceted.domain.zmin + faceted.radius[first], abs=1e-9)
    assert faceted.n_placed > 280
    along = _order_correlations(faceted)
    # placed in the order of the faceted level, and the sides of the box after its axis
    assert along["level"] > along["z"] + 0.1
    assert along["g"] > 0.35


def test_a_faceted_front_in_a_periodic_box_is_overlap_free() -> None:
    packing = _pack(faceted_scene("periodic-box", facet=7.0))
    assert regopack.verify(packing).ok
    assert packing.n_placed > 0.9 * packing.n_particles


def test_the_faceted_level_rises_along_the_faces_of_the_pyramids(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    seen: list[sweep_module.SurfaceSweep] = []
    run = sweep_module.SurfaceSweep.run

    def keep(self: sweep_module.SurfaceSweep, *args: Any, **kwargs: Any) -> None:
        seen.append(self)
        run(self, *args, **kwargs)

    monkeypatch.setattr(sweep_module.SurfaceSweep, "run", keep)
    # a floor of 16 x 16 in squares of about 7: two of 8 each way, centred on the middle
    _pack(faceted_scene(count=5, facet=7.0))
    sweep = seen[-1]  # the run's (a pilot, when the box is tall enough, runs first)
    assert sweep.faceted
    z0 = -8.0
    r2, r3 = np.sqrt(2.0), np.sqrt(3.0)
    for point, level in (
        ((0.0, 0.0, z0), z0),  # an apex on the floor
        ((8.0, -8.0, z0 + 3.0), z0 + 3.0 / r3),  # the next apex, higher
        ((4.0, 1.0, z0), z0 + r2 * 4.0 / r3),  # on an edge between two squares
        ((-1.0, -2.5, z0 + 1.0), z0 + (1.0 + r2 * 2.5) / r3),  # on a face
    ):
        assert sweep._level(np.array(point)) == pytest.approx(level, abs=1e-12)
    # the bins reach the highest level: the box's top above an edge of a square
    assert sweep.nbins * sweep.delta >= (16.0 + r2 * 4.0) / r3


def test_the_faceted_front_and_its_facet_are_checked_by_the_config() -> None:
    with pytest.raises(ConfigError, match=r"facet = 5.0 sizes the faceted front's pyramids"):
        regopack.pack(faceted_scene(front="bottom-up", facet=5.0), verify=False)
    with pytest.raises(ConfigError, match=r"front = 'faceted' is a front of the sweep"):
        regopack.pack(faceted_scene(order="paper"), verify=False)


def test_a_steeper_facet_slope_tilts_the_faces(monkeypatch: pytest.MonkeyPatch) -> None:
    """``facet_slope`` sets the angle of the faces' normals from z: ``z cos + g sin``."""
    seen: list[sweep_module.SurfaceSweep] = []
    run = sweep_module.SurfaceSweep.run

    def keep(self: sweep_module.SurfaceSweep, *args: Any, **kwargs: Any) -> None:
        seen.append(self)
        run(self, *args, **kwargs)

    monkeypatch.setattr(sweep_module.SurfaceSweep, "run", keep)
    packing = _pack(faceted_scene(count=60, facet=7.0, facet_slope=68.0))
    assert regopack.verify(packing).ok
    sweep = seen[-1]
    z0, a = -8.0, np.radians(68.0)
    for point, level in (
        ((0.0, 0.0, z0 + 2.0), z0 + 2.0 * np.cos(a)),
        ((-1.0, -2.5, z0 + 1.0), z0 + np.cos(a) + 2.5 * np.sin(a)),
    ):
        assert sweep._level(np.array(point)) == pytest.approx(level, abs=1e-12)
    # the bins reach the highest level: the box's top above an edge of a square
    assert sweep.nbins * sweep.delta >= 16.0 * np.cos(a) + 4.0 * np.sin(a)


@pytest.mark.parametrize(
    ("insertion", "words"),
    [
        ({"facet_slope": 60.0, "front": "bottom-up", "facet": 0.0}, "facet_slope = 60.0 tilts"),
        ({"facet_slope": 90.0}, "facet_slope"),
        ({"facet_slope": 0.0}, "facet_slope"),
    ],
)
def test_a_facet_slope_is_checked_by_the_config(insertion: dict[str, Any], words: str) -> None:
    with pytest.raises(ConfigError, match=words) as caught:
        regopack.pack(faceted_scene(**insertion), verify=False)
    assert "\n" not in str(caught.value)
