"""Spheres in the available-surface inserter: the free part of a sphere, uniform centres on it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import regopack
from regopack.base.errors import ConfigError
from regopack.plugins.common.kernel_random import kernel_source
from regopack.plugins.inserters.available_surface.spheres import free_arcs, is_free, sample_free


def _caps(rows: list[tuple[float, float, float, float]]) -> np.ndarray:
    caps = np.array(rows, dtype=np.float64).reshape(-1, 4)
    caps[:, :3] /= np.linalg.norm(caps[:, :3], axis=1, keepdims=True)
    return caps


def test_a_hemisphere_cap_leaves_free_arcs_and_uniform_points_on_the_rest() -> None:
    caps = _caps([(0, 0, 1, 0.0)])  # covers z > 0 on the unit sphere
    arcs = free_arcs(caps, 1, 1.0, 1e-12)
    assert arcs.shape == (1, 3) and arcs[0, 2] - arcs[0, 1] == pytest.approx(2 * math.pi)
    rng = kernel_source(np.random.default_rng(5))  # the kernels' own source
    z = np.array([sample_free(caps, 1, arcs, 1.0, 1e-12, rng)[2] for _ in range(4000)])
    assert np.all(z <= 1e-12)
    # uniform by area on a sphere: the height is uniform (Archimedes), here on [-1, 0]
    counts, _ = np.histogram(z, bins=10, range=(-1.0, 0.0))
    chi2 = float(((counts - 400.0) ** 2 / 400.0).sum())
    assert chi2 < 40.0  # 9 degrees of freedom: far beyond the 0.9999 quantile only if biased


def test_caps_that_cover_the_sphere_leave_no_arc_and_a_gap_is_found() -> None:
    # the six walls of a cube of admissible centres just inside the sphere: covered
    h = 1.0 / math.sqrt(3.0) * 0.999
    walls = [(s * (a == 0), s * (a == 1), s * (a == 2), h) for a in range(3) for s in (-1, 1)]
    assert free_arcs(_caps(walls), 6, 1.0, 1e-12).shape[0] == 0
    # a cube a little larger leaves its eight corners free
    h = 1.0 / math.sqrt(3.0) * 1.001
    walls = [(s * (a == 0), s * (a == 1), s * (a == 2), h) for a in range(3) for s in (-1, 1)]
    caps = _caps(walls)
    arcs = free_arcs(caps, 6, 1.0, 1e-12)
    assert arcs.shape[0] > 0
    rng = kernel_source(np.random.default_rng(1))  # the kernels' own source
    for _ in range(20):
        u = sample_free(caps, 6, arcs, 1.0, 1e-12, rng)
        assert is_free(caps, 6, *u, 1e-12)
        assert abs(abs(u[0]) - abs(u[1])) < 0.1 and abs(abs(u[1]) - abs(u[2])) < 0.1  # a corner


def test_a_tangent_point_is_no_free_surface() -> None:
    # two opposite hemispheres leave only the equator circle, which counts as nothing
    caps = _caps([(0, 0, 1, 0.0), (0, 0, -1, 0.0)])
    assert free_arcs(caps, 2, 1.0, 1e-12).shape[0] == 0


def test_a_free_set_pinched_at_the_middle_of_every_free_arc_is_found() -> None:
    # four caps of 60 degrees about the equator of u and the hemisphere opposite u leave a
    # rounded square about u; a cap about u inscribed in it touches each side at its middle,
    # and so does it the middle of its own circle (angle pi of its frame, u chosen for that):
    # four lobes remain, about 2 % of the sphere, though every free arc is pinched mid-way
    from regopack.plugins.inserters.available_surface.spheres import _frame

    u = np.array([0.7415052, 0.53854712, -0.40017126])
    u /= np.linalg.norm(u)
    e1x, e1y, e1z, e2x, e2y, e2z = _frame(*u)
    e1, e2 = np.array([e1x, e1y, e1z]), np.array([e2x, e2y, e2z])
    rows = []
    for i in range(4):
        b = math.pi + i * math.pi / 2
        rows.append((*(math.cos(b) * e1 + math.sin(b) * e2), 0.5))
    rows += [(*u, math.cos(math.pi / 6)), (*(-u), 0.0)]
    caps = np.array(rows)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200_000, 3))
    x /= np.linalg.norm(x, axis=1)[:, None]
    assert np.mean(np.all(x @ caps[:, :3].T <= caps[:, 3] - 1e-6, axis=1)) > 0.01
    arcs = free_arcs(caps, 6, 1.0, 1e-12)
    assert arcs.shape[0] > 0
    for _ in range(20):
        assert is_free(caps, 6, *sample_free(caps, 6, arcs, 1.0, 1e-12, kernel_source(rng)), 1e-12)


def scene(**changes: Any) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": "spheres",
        "seed": 2,
        "count": 120,
        "domain": {"kind": "box", "width": 16.0, "height": 16.0, "depth": 16.0},
        "size": {"kind": "uniform", "d_min": 2.0, "d_max": 5.0},
        "phases": [{"name": "glass", "fraction": 1.0, "shape": {"kind": "sphere"}}],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }
    data.update(changes)
    return data


@pytest.mark.parametrize(
    ("kind", "order"), [("box", "paper"), ("periodic-box", "paper"), ("box", "sweep")]
)
def test_spheres_touch_their_candidate_and_pass_the_oracle(kind: str, order: str) -> None:
    out = regopack.pack_and_summarise(
        scene(
            domain={"kind": kind, "width": 16.0, "height": 16.0, "depth": 16.0},
            insertion={"kind": "available-surface", "order": order},
        ),
        verify=True,
    )
    packing = out.packing
    assert packing.dimension == 3
    assert out.summary["verify"]["ok"], out.summary["verify"]
    assert packing.n_placed >= 60
    assert math.isfinite(out.summary["phi_interior"])
    order_ = packing.placed_in_order()
    c = packing.centre[order_]
    r = packing.radius[order_]
    period = np.array(packing.domain.size) if kind == "periodic-box" else None
    for a in range(1, len(order_)):
        d = c[:a] - c[a]
        if period is not None:
            d -= period * np.round(d / period)
        gap = np.linalg.norm(d, axis=1) - r[:a] - r[a]
        assert gap.min() == pytest.approx(0.0, abs=1e-9 * r[a])  # touches one
        assert gap.min() >= -1e-9 * r[a]  # overlaps none


def test_eta_keeps_each_sphere_its_margin_from_spheres_beyond_the_circumradius_test() -> None:
    # a sphere j with |c_j - c_k| >= r_k + r_j + 2 r cannot overlap the new sphere, but it
    # can come closer to it than the margin: it interferes when the margin is added
    eta = 30.0
    packing = regopack.pack(scene(count=150, density={"kind": "eta", "eta": eta}), verify=False)
    assert packing.dimension == 3
    order_ = packing.placed_in_order()
    c = packing.centre[order_]
    r = packing.radius[order_]
    assert len(order_) >= 40
    for a in range(1, len(order_)):
        gap = np.sort(np.linalg.norm(c[:a] - c[a], axis=1) - r[:a] - r[a])
        margin = (eta - 1.0) / 100.0 * 2.0 * r[a]  # xi >= 0
        assert gap[0] == pytest.approx(0.0, abs=1e-9 * r[a])  # touches its candidate
        if a > 1:
            assert gap[1] >= margin * (1 - 1e-9)  # keeps the margin from every other


def test_a_sphere_wider_than_a_periodic_box_is_not_placed() -> None:
    # it would overlap its own images wherever it went
    out = regopack.pack_and_summarise(
        scene(
            count=3,
            domain={"kind": "periodic-box", "width": 1.7, "height": 1.7, "depth": 1.7},
            size={"kind": "uniform", "d_min": 2.0, "d_max": 2.02},
        ),
        verify=True,
    )
    assert out.packing.n_placed == 0
    assert out.summary["verify"]["ok"]


def test_spheres_and_polyhedra_together_are_refused_in_one_line() -> None:
    phases = [
        {"name": "glass", "fraction": 0.5, "shape": {"kind": "sphere"}},
        {"name": "ilmenite", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 15.0}},
    ]
    with pytest.raises(ConfigError) as err:
        regopack.pack(scene(count=5, phases=phases))
    text = str(err.value)
    assert "phases.1.shape.kind: 'polyhedron' beside 'sphere' in phase 0" in text
    assert "spheres or polyhedra, not both" in text and "\n" not in text


def _free_points(caps: np.ndarray, n: int, seed: int) -> np.ndarray:
    x = np.random.default_rng(seed).normal(size=(n, 3))
    x /= np.linalg.norm(x, axis=1)[:, None]
    return x[np.all(x @ caps[:, :3].T <= caps[:, 3], axis=1)]


@pytest.mark.parametrize("seed", range(12))
def test_the_bounding_cap_holds_every_free_point(seed: int) -> None:
    # caps about random directions, large enough to leave a few small pieces free
    from regopack.plugins.inserters.available_surface.spheres import bounding_cap

    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 9))
    rows = rng.normal(size=(n, 3))
    caps = _caps([(*v, h) for v, h in zip(rows, rng.uniform(-0.4, 0.3, n), strict=True)])
    free = _free_points(caps, 100_000, seed)
    arcs = free_arcs(caps, n, 1.0, 1e-12)
    assert (arcs.shape[0] > 0) == (len(free) > 0)
    if len(free) == 0:
        return
    ax, ay, az, cos_max = bounding_cap(caps, n, arcs, 1.0, 1e-12)
    assert np.all(free @ np.array([ax, ay, az]) >= cos_max)


def test_a_small_free_corner_is_sampled_uniformly_by_area_from_its_cap() -> None:
    # three caps larger than hemispheres leave a small curved triangle about (1, 1, 1):
    # the proposals come from a small cap, and the points stay uniform by area
    from scipy.stats import ks_2samp

    from regopack.plugins.inserters.available_surface.spheres import bounding_cap

    caps = _caps([(-1, 0, 0, -0.5), (0, -1, 0, -0.5), (0, 0, -1, -0.5)])
    ref = _free_points(caps, 1_000_000, 3)
    assert 1000 < len(ref) < 0.01 * 1_000_000
    arcs = free_arcs(caps, 3, 1.0, 1e-12)
    *_, cos_max = bounding_cap(caps, 3, arcs, 1.0, 1e-12)
    assert cos_max > 0.98  # a cap much smaller than the sphere
    rng = kernel_source(np.random.default_rng(9))  # the kernels' own source
    got = np.array([sample_free(caps, 3, arcs, 1.0, 1e-12, rng) for _ in range(3000)])
    assert np.all(got @ caps[:, :3].T <= caps[:, 3] + 1e-12)
    for axis in range(3):  # the same distribution as uniform points filtered by the caps
        assert ks_2samp(got[:, axis], ref[:, axis]).pvalue > 1e-4


def test_free_pieces_on_opposite_sides_make_the_whole_sphere_the_cap() -> None:
    from regopack.plugins.inserters.available_surface.spheres import bounding_cap

    # a band of caps about the equator leaves two polar pieces
    rows = [(math.cos(b), math.sin(b), 0.0, 0.6) for b in np.linspace(0, 2 * math.pi, 9)[:-1]]
    caps = _caps(rows)
    arcs = free_arcs(caps, 8, 1.0, 1e-12)
    *_, cos_max = bounding_cap(caps, 8, arcs, 1.0, 1e-12)
    assert cos_max == -1.0
    rng = kernel_source(np.random.default_rng(4))  # the kernels' own source
    z = np.array([sample_free(caps, 8, arcs, 1.0, 1e-12, rng)[2] for _ in range(400)])
    assert 120 < np.count_nonzero(z > 0) < 280  # both pieces, about equally


def test_the_rest_of_a_sphere_beyond_a_small_cap_is_sampled_whole() -> None:
    # the free arcs (one circle) all lie near the cap: the free set is the other side, and
    # the point opposite the arcs' axis tells so
    caps = _caps([(0, 0, 1, 0.9)])
    arcs = free_arcs(caps, 1, 1.0, 1e-12)
    rng = kernel_source(np.random.default_rng(2))  # the kernels' own source
    z = np.array([sample_free(caps, 1, arcs, 1.0, 1e-12, rng)[2] for _ in range(2000)])
    assert np.all(z <= 0.9 + 1e-12)
    counts, _ = np.histogram(z, bins=10, range=(-1.0, 0.9))
    assert counts.min() > 120  # uniform heights on [-1, 0.9]: about 200 a bin


def _arc_geometry(caps: np.ndarray, arcs: np.ndarray) -> np.ndarray:
    """Free arcs as (cap row, start, end), independent of the caps' positions."""
    return np.c_[caps[arcs[:, 0].astype(np.int64)], arcs[:, 1:]]


@pytest.mark.parametrize("seed", range(16))
def test_dropping_contained_caps_changes_no_arc_and_no_drawn_centre(seed: int) -> None:
    # a crowd of caps of every size, many inside others, some nearly touching them from
    # inside: the free arcs, the free points and the centres drawn are the same without
    # the contained ones
    from regopack.plugins.inserters.available_surface.spheres import drop_contained

    rng = np.random.default_rng(seed)
    big_r, tau = 2.5, 2.5e-12
    n = int(rng.integers(4, 40))
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    h = big_r * rng.uniform(-0.2, 0.98, n)
    for q in range(n // 3):  # caps just inside a larger one, within a few tolerances
        p = int(rng.integers(n))
        tp, tq = math.acos(h[p] / big_r), 0.5 * math.acos(h[p] / big_r)
        tilt = tp - tq - float(rng.choice([1e-3, 1e-8, 1e-10]))
        side = np.cross(axes[p], rng.normal(size=3))
        side /= np.linalg.norm(side)
        axes[q] = math.cos(tilt) * axes[p] + math.sin(tilt) * side
        h[q] = big_r * math.cos(tq)
    caps = np.c_[axes, h]
    kept = caps.copy()
    m = drop_contained(kept, n, big_r, tau)
    kept = kept[:m]
    assert m <= n
    before = free_arcs(caps, n, big_r, tau)
    after = free_arcs(kept, m, big_r, tau)
    assert np.array_equal(_arc_geometry(caps, before), _arc_geometry(kept, after))
    u = rng.normal(size=(2000, 3))
    u *= big_r / np.linalg.norm(u, axis=1)[:, None]
    for x in u:
        assert is_free(caps, n, *x, tau) == is_free(kept, m, *x, tau)
    if before.shape[0]:
        a = sample_free(caps, n, before, big_r, tau, kernel_source(np.random.default_rng(seed)))
        b = sample_free(kept, m, after, big_r, tau, kernel_source(np.random.default_rng(seed)))
        assert a == b


def test_a_cap_inside_another_is_dropped_and_one_that_reaches_out_is_kept() -> None:
    from regopack.plugins.inserters.available_surface.spheres import drop_contained

    tau = 1e-12
    big = (0.0, 0.0, 1.0, math.cos(0.8))  # angular radius 0.8 about +z
    rows = [
        big,
        (math.sin(0.3), 0.0, math.cos(0.3), math.cos(0.4)),  # 0.3 + 0.4 < 0.8: inside
        (math.sin(0.5), 0.0, math.cos(0.5), math.cos(0.4)),  # 0.5 + 0.4 > 0.8: crosses
        (math.sin(0.4), 0.0, math.cos(0.4), math.cos(0.4 - 1e-13)),  # touches from inside
        (0.0, 0.0, -1.0, 0.5),  # elsewhere
        big,  # the same cap twice: neither holds the other strictly
    ]
    caps = np.array(rows)
    m = drop_contained(caps, len(rows), 1.0, tau)
    assert m == 5
    assert np.array_equal(caps[:m], np.array([rows[0], rows[2], rows[3], rows[4], rows[5]]))
    # a larger cap does not hold a smaller one whose axis it does not reach
    far = np.array([(0.0, 0.0, 1.0, 0.0), (0.0, 0.0, -1.0, 0.9)])
    assert drop_contained(far, 2, 1.0, tau) == 2


@pytest.mark.parametrize("seed", range(12))
def test_covers_agrees_with_the_free_arcs_and_its_cover_leaves_no_free_point(seed: int) -> None:
    from regopack.plugins.inserters.available_surface.spheres import covers

    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(3, 12))
    rows = rng.normal(size=(n, 3))
    caps = _caps([(*v, h) for v, h in zip(rows, rng.uniform(-0.5, 0.2, n), strict=True)])
    free = _free_points(caps + np.array([0.0, 0.0, 0.0, 1e-6]), 100_000, seed)
    shut = covers(caps, n, 1.0, 1e-6)
    if shut:
        assert len(free) == 0  # every point lies deeper than the margin in some cap
    if len(_free_points(caps, 100_000, seed)) == 0:
        assert free_arcs(caps, n, 1.0, 1e-12).shape[0] == 0
    # no free arc (beyond slivers) and no free point: covered with any small margin
    if free_arcs(caps, n, 1.0, 1e-12).shape[0] == 0 and len(free) == 0:
        assert covers(caps, n, 1.0, 1e-9)


def test_covers_needs_every_circle_covered_and_counts_a_shared_end_as_a_gap() -> None:
    from regopack.plugins.inserters.available_surface.spheres import covers

    h = 1.0 / math.sqrt(3.0)
    cube = [
        (s * (a == 0), s * (a == 1), s * (a == 2), h * 0.999) for a in range(3) for s in (-1, 1)
    ]
    assert covers(_caps(cube), 6, 1.0, 1e-9)
    assert not covers(_caps(cube), 6, 1.0, 1e-3 * h)  # shrunk by more than it overlaps
    assert not covers(_caps(cube[:5]), 5, 1.0, 1e-9)  # a face missing
    # two hemispheres meeting along the equator: the equator is a shared end
    assert not covers(_caps([(0, 0, 1, 0.0), (0, 0, -1, 0.0)]), 2, 1.0, 0.0)
    assert covers(_caps([(0, 0, 1, -1e-3), (0, 0, -1, -1e-3)]), 2, 1.0, 1e-6)
    assert covers(_caps([(1, 0, 0, -1.0 + 1e-12)]), 1, 1.0, -1e-9)  # one cap holds it all
    assert not covers(np.zeros((0, 4)), 0, 1.0, 0.0)


def _run_state(monkeypatch: pytest.MonkeyPatch, data: dict[str, Any], levels: bool) -> tuple:
    """Pack ``data``; return the packing and its insertion's :class:`SurfaceState`."""
    from regopack.plugins.inserters.available_surface import state as state_module

    seen: list[Any] = []
    real = state_module.SurfaceState.__init__

    def spy(self: Any, *args: Any, **kwargs: Any) -> None:
        real(self, *args, **kwargs)
        if not levels:
            self.levels = np.zeros(0)
        seen.append(self)

    with monkeypatch.context() as m:
        m.setattr(state_module.SurfaceState, "__init__", spy)
        packing = regopack.pack(data, verify=False)
    return packing, seen[-1]


@pytest.mark.parametrize(
    ("kind", "order", "count"),
    [("box", "sweep", 700), ("periodic-box", "sweep", 700), ("box", "paper", 200)],
)
def test_shutting_candidates_changes_no_packing_and_shut_ones_take_no_sphere(
    monkeypatch: pytest.MonkeyPatch, kind: str, order: str, count: int
) -> None:
    data = scene(
        count=count,
        domain={"kind": kind, "width": 12.0, "height": 12.0, "depth": 12.0},
        size={"kind": "uniform", "d_min": 1.0, "d_max": 4.0},
        insertion={"kind": "available-surface", "order": order},
    )
    plain, st0 = _run_state(monkeypatch, data, levels=False)
    packing, st = _run_state(monkeypatch, data, levels=True)
    assert np.array_equal(plain.centre, packing.centre, equal_nan=True)
    # the screening is that of the analyses themselves: a saved one counts as empty
    assert np.array_equal(st0.rmin, st.rmin)
    assert st0.shut_tests == 0 and st.saved > 0 and st.analyses + st.saved == st0.analyses
    # every candidate shut from a level takes no sphere of that radius now: directions
    # all about it, against every placed sphere and the walls
    placed = np.flatnonzero(np.isfinite(st.centre[:, 0]))
    c, r = st.centre[placed], st.circum[placed]
    level = st.shut_from[st.index[placed]]
    shut = np.flatnonzero(np.isfinite(level))
    assert len(shut) >= 20 and np.all(np.isin(level[shut], st.levels))
    rng = np.random.default_rng(0)
    u = rng.normal(size=(10_000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    for a in shut[:: max(1, len(shut) // 30)]:
        rf = float(level[a])
        x = c[a] + (r[a] + rf) * u
        d0 = c - c[a]
        if st.period is not None:
            d0 -= st.period * np.round(d0 / st.period)
        reach = np.linalg.norm(d0, axis=1) < r[a] + r + 2 * rf
        reach[a] = False
        d = x[:, None, :] - (c[a] + d0[reach])[None, :, :]
        slack = (np.linalg.norm(d, axis=2) - r[reach][None, :] - rf).min(axis=1, initial=np.inf)
        if st.period is None:
            slack = np.minimum(slack, (x - st.lo - rf).min(axis=1))
            slack = np.minimum(slack, (st.hi - rf - x).min(axis=1))
        assert slack.max() < 1e-9 * rf, (a, rf)


@pytest.mark.parametrize(
    ("seed", "kind", "t", "eta"),
    [(50, "box", 0.95, 0.0), (41, "periodic-box", 0.9, 0.0), (1, "box", 0.999, 0.5)],
)
def test_shutting_keeps_the_screening_and_the_random_numbers_of_the_analyses(
    monkeypatch: pytest.MonkeyPatch, seed: int, kind: str, t: float, eta: float
) -> None:
    # below t = 1, an analysis saved must still lower rmin as the empty one would (a
    # sphere a little smaller that the screening then refuses could fit); with eta > 0
    # it must still draw its xi
    data = scene(
        seed=seed,
        count=250,
        domain={"kind": kind, "width": 12.0, "height": 12.0, "depth": 12.0},
        size={"kind": "uniform", "d_min": 1.0, "d_max": 4.0},
        insertion={"kind": "available-surface", "t": t},
        density={"kind": "eta", "eta": eta},
    )
    plain, st0 = _run_state(monkeypatch, data, levels=False)
    packing, st = _run_state(monkeypatch, data, levels=True)
    assert np.array_equal(plain.centre, packing.centre, equal_nan=True)
    assert np.array_equal(st0.rmin, st.rmin)
    assert st.saved > 0
    assert st.analyses + st.saved == st0.analyses
