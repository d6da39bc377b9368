"""Neighbour lists: the same interferers, hence the same packing, as the grid search."""

from __future__ import annotations

import numpy as np
import pytest
from arc_helpers import change5_population, octagon_population, pack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.geometry.population import Population, ShapeBatch, concat_shapes
from regopack.plugins.inserters.available_arc import kernel, state
from regopack.plugins.inserters.available_arc.neighbours import GAP_SLACK
from regopack.plugins.inserters.available_arc.state import ArcState
from regopack.plugins.shapes.disk import Disk
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.testing import extreme_radii

HEXAGON = tuple((60.0 * np.cos(a), 60.0 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1])


def _run(
    pop: Population, domain: Domain, seed: int, lists: bool, tau: float | None = None
) -> tuple[ArcState, bytes]:
    """Pack ``pop`` with or without neighbour lists; return the state and its packing bytes."""
    st_ = ArcState(pop, domain, t=0.999, tau=tau, linear=False, neighbour_lists=lists)
    st_.pack_range(0, len(pop), np.random.default_rng(seed))
    p = st_.packed
    key = p.cx.tobytes() + p.cy.tobytes() + p.order.tobytes()
    return st_, key + bytes(str(st_.counter(kernel.I_ANALYSES)), "ascii")


def _same_with_and_without_lists(
    pop: Population, domain: Domain, seed: int, tau: float | None = None
) -> ArcState:
    with_lists, a = _run(pop, domain, seed, True, tau)
    _, b = _run(pop, domain, seed, False, tau)
    assert with_lists.counter(kernel.I_NBLISTS) == 1
    assert a == b
    return with_lists


@pytest.mark.parametrize(
    ("seed", "domain", "tau"),
    [
        (1, Rectangle.centred(110.0, 90.0, (3.0, -7.0)), None),
        (2, Rectangle.centred(110.0, 90.0), None),
        (3, Rectangle.centred(110.0, 90.0), 0.65),
        (4, Circle(1.0, 2.0, 55.0), None),
        (5, ConvexPolygon(HEXAGON), None),
        (6, PeriodicRectangle.centred(110.0, 90.0, (3.0, -7.0)), None),
        (7, PeriodicRectangle.centred(110.0, 90.0), 0.65),
    ],
)
def test_lists_and_grid_give_identical_packings(seed: int, domain: Domain, tau: float) -> None:
    pop, _ = change5_population(450, seed)
    st_ = _same_with_and_without_lists(pop, domain, seed, tau)
    assert st_.count > 200


def test_scene_option_turns_the_lists_off_and_keeps_the_packing() -> None:
    domain = Rectangle.centred(100.0, 80.0)
    out = []
    for lists in (True, False):
        pop, rng = change5_population(350, 12)
        out.append(pack(pop, domain, rng, eta=10.0, neighbour_lists=lists))
    assert out[0].centre.tobytes() == out[1].centre.tobytes()
    assert out[0].stats == {
        **out[1].stats,
        **{k: out[0].stats[k] for k in out[0].stats if "time" in k},
    }


def _rounded_population(n: int, seed: int, kind: str) -> Population:
    """Disks, disks among octagons, or octagons with rounded corners."""
    rng = np.random.default_rng(seed)
    radius = Change5(Change5Config()).sample(n, rng)
    octagons = RandomPolygon(OctagonConfig(psi=1.0)).generate(radius, rng)
    disks = Disk().generate(radius, rng)
    if kind == "disks":
        batch = disks
    elif kind == "mixed":
        disk = rng.random(n) < 0.5
        idx = np.flatnonzero(disk)
        rest = np.flatnonzero(~disk)
        batch = concat_shapes(
            [
                (idx, Disk().generate(radius[idx], rng)),
                (rest, RandomPolygon(OctagonConfig(psi=1.0)).generate(radius[rest], rng)),
            ],
            n,
        )
    else:  # cores shrunk to 70 %, grown back by a rounding of 30 % of the radius
        batch = ShapeBatch(
            vertices=0.7 * octagons.vertices,
            offsets=octagons.offsets,
            orientation=octagons.orientation,
            rounding=0.3 * radius,
        )
    return Population(radius, np.zeros(n, dtype=np.int64), ("m",), batch)


@pytest.mark.parametrize("kind", ["disks", "mixed", "rounded"])
@pytest.mark.parametrize(
    "domain",
    [
        Rectangle.centred(90.0, 80.0, (2.0, -1.0)),
        Circle(1.0, 2.0, 48.0),
        ConvexPolygon(HEXAGON),
        PeriodicRectangle.centred(90.0, 80.0, (2.0, -1.0)),
    ],
)
def test_lists_and_grid_give_identical_packings_with_rounded_particles(
    kind: str, domain: Domain
) -> None:
    pop = _rounded_population(300, 7, kind)
    st_ = _same_with_and_without_lists(pop, domain, 7)
    assert st_.count > 150


@pytest.mark.parametrize("closing", ["paced", "tail"])
@pytest.mark.parametrize("periodic", [False, True])
def test_the_sweep_packs_disks_the_same_with_and_without_lists(
    closing: str, periodic: bool
) -> None:
    out = []
    box = PeriodicRectangle.centred if periodic else Rectangle.centred
    for lists in (True, False):
        pop = _rounded_population(500, 11, "mixed")
        rng = np.random.default_rng(11)
        res = pack(
            pop, box(80.0, 110.0), rng, order="sweep", closing=closing, neighbour_lists=lists,
        )  # fmt: skip
        out.append(res.centre.tobytes() + res.insertion_index.tobytes())
    assert out[0] == out[1]


@pytest.mark.parametrize("scale", [1e-150, 1e40, 1e150])
def test_lists_and_grid_agree_far_beyond_the_usual_scales(scale: float) -> None:
    rng = np.random.default_rng(0)
    radius = scale * np.exp(rng.uniform(0.0, np.log(5.0), 150))
    pop = octagon_population(radius, rng, psi=0.5)
    side = 1.2 * np.sqrt(np.sum(np.pi * (radius / scale) ** 2)) * scale
    st_ = _same_with_and_without_lists(pop, Rectangle.centred(side, side), 0)
    assert st_.count > 100


def test_full_lists_fall_back_to_the_grid(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(state, "LIST_CAPACITY", 6)
    pop, _ = change5_population(400, 8)
    st_ = _same_with_and_without_lists(pop, Rectangle.centred(100.0, 100.0), 8)
    placed = st_.packed.order[: st_.count]
    rows = st_.packed.nb_row[placed]
    dropped = np.sum(st_.packed.nb_n[rows] < 0)
    assert 0 < dropped < st_.count


def _checked_lists(p: kernel.Packed, placed: np.ndarray, among: np.ndarray) -> int:
    """Check the list of every particle of ``among`` that has one; return how many."""
    cap = p.fpar[kernel.F_NBCAP]
    assert cap > 0
    checked = 0
    for q in among:
        r = p.nb_row[q]
        if r < 0 or p.nb_n[r] < 0:
            continue
        cnt = p.nb_n[r]
        others = placed[placed != q]
        d = np.hypot(p.cx[others] - p.cx[q], p.cy[others] - p.cy[q])
        lim = p.nb_reach[q] + p.nb_reach[others] + 2.0 * cap
        must = set(others[d < lim].tolist())
        may = set(others[d < lim * (1 + 2 * GAP_SLACK)].tolist())
        got = p.nb_o[r, :cnt].astype(np.int64)
        assert must <= set(got.tolist()) <= may
        assert len(set(got.tolist())) == cnt
        assert np.all(np.diff(p.nb_gap[r, :cnt]) >= 0)
        # offsets are the same floats the grid search computes
        assert np.array_equal(p.nb_dx[r, :cnt], p.cx[got] - p.cx[q])
        assert np.array_equal(p.nb_dy[r, :cnt], p.cy[got] - p.cy[q])
        checked += 1
    return checked


def test_lists_hold_every_near_particle_sorted_by_gap() -> None:
    pop, _ = change5_population(500, 9)
    st_, _ = _run(pop, Rectangle.centred(110.0, 110.0), 9, True)
    placed = st_.packed.order[: st_.count]
    assert _checked_lists(st_.packed, placed, placed) > 0.9 * len(placed)


def _checked_periodic_lists(p: kernel.Packed, placed: np.ndarray) -> int:
    """As :func:`_checked_lists` in a periodic box: one entry per image in reach."""
    cap = p.fpar[kernel.F_NBCAP]
    lx = p.fpar[kernel.F_XMAX] - p.fpar[kernel.F_XMIN]
    ly = p.fpar[kernel.F_YMAX] - p.fpar[kernel.F_YMIN]
    checked = images = 0
    for q in placed:
        r = p.nb_row[q]
        if r < 0 or p.nb_n[r] < 0:
            continue
        cnt = p.nb_n[r]
        must, may, want = set(), set(), {}
        for ix in (0.0, lx, -lx):
            for iy in (0.0, ly, -ly):
                # q's image shifted by (ix, iy), as the grid search places its query
                qcx = p.cx[q]
                qcy = p.cy[q]
                if ix != 0.0 or iy != 0.0:
                    qcx += ix
                    qcy += iy
                code = (0 if ix == 0 else 1 if ix > 0 else 2) + 3 * (
                    0 if iy == 0 else 1 if iy > 0 else 2
                )
                dx = p.cx[placed] - qcx
                dy = p.cy[placed] - qcy
                d = np.hypot(dx, dy)
                lim = p.nb_reach[q] + p.nb_reach[placed] + 2.0 * cap
                for j in np.flatnonzero(d < lim * (1 + 2 * GAP_SLACK)):
                    key = (int(placed[j]), code)
                    if placed[j] == q and code == 0:
                        continue
                    may.add(key)
                    want[key] = (dx[j], dy[j])
                    if d[j] < lim[j]:
                        must.add(key)
        got = {
            (int(p.nb_o[r, e]), int(p.nb_img[r, e])): (p.nb_dx[r, e], p.nb_dy[r, e])
            for e in range(cnt)
        }
        assert len(got) == cnt
        assert must <= set(got) <= may
        for key, offset in got.items():
            assert offset == want[key]  # the same floats as the grid search's
        assert np.all(np.diff(p.nb_gap[r, :cnt]) >= 0)
        images += sum(1 for _, code in got if code != 0)
        checked += 1
    assert images > 0
    return checked


@pytest.mark.parametrize(("small", "tau"), [(True, None), (True, 0.5), (False, None)])
def test_periodic_lists_hold_every_image_in_reach_at_the_grid_searchs_offsets(
    small: bool, tau: float | None
) -> None:
    pop, _ = change5_population((30 if tau else 60) if small else 400, 9)
    # the small box: just over the shortest period allowed, where most lists hold
    # images, and with a small tau (a long reach) a particle's own images
    side = 4.2 * pop.circumradius.max() / 0.9 if small else 110.0
    st_, _ = _run(pop, PeriodicRectangle.centred(side, 0.9 * side, (3.0, -2.0)), 9, True, tau)
    placed = st_.packed.order[: st_.count]
    assert _checked_periodic_lists(st_.packed, placed) > 0.9 * len(placed)
    if tau is not None:
        p = st_.packed
        own = [
            q
            for q in placed
            if p.nb_row[q] >= 0 and q in p.nb_o[p.nb_row[q], : p.nb_n[p.nb_row[q]]]
        ]
        assert own


def test_lists_are_kept_in_every_kind_of_domain_unless_turned_off() -> None:
    pop, _ = change5_population(50, 1)
    periodic = ArcState(pop, PeriodicRectangle.centred(80.0, 80.0), t=0.999, tau=None, linear=False)
    assert periodic.counter(kernel.I_NBLISTS) == 1
    off = ArcState(
        pop, Rectangle.centred(80.0, 80.0), t=0.999, tau=None, linear=False, neighbour_lists=False
    )
    assert off.counter(kernel.I_NBLISTS) == 0


@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 80),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    psi=st.sampled_from([0.01, 0.5, 15.0, 1000.0]),
    tau=st.sampled_from([None, None, 0.65]),
    periodic=st.booleans(),
)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_lists_and_grid_agree_in_random_scenes(seed, n, ratio, scale, psi, tau, periodic) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)
    pop = octagon_population(radius, rng, psi=psi)
    side = max(scale * 4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2)), 2.6 * pop.circumradius.max())
    if periodic:  # down to the shortest period allowed: images of images, a particle's own
        side = max(side * rng.uniform(0.3, 1.0), 4.0 * pop.circumradius.max() / 0.79)
        domain: Domain = PeriodicRectangle.centred(side, 0.8 * side, (3.0 * scale, -2.0 * scale))
    else:
        domain = Rectangle.centred(side, 0.8 * side, (3.0 * scale, -2.0 * scale))
    _same_with_and_without_lists(pop, domain, seed, tau)


def test_the_option_from_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    import tomllib

    from regopack.cli import main

    assert main(["config", "--set", "insertion.neighbour_lists=false"]) == 0
    assert tomllib.loads(capsys.readouterr().out)["insertion"]["neighbour_lists"] is False
    assert main(["config", "--set", "insertion.neighbour_lists=3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "regopack: error: --set: insertion.neighbour_lists = 3: Input should be a valid boolean"
    ]


class _Spy:
    """Capture the state and the sweep of the next available-arc run."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, pool_rows: int) -> None:
        import regopack.plugins.inserters.available_arc as arc
        from regopack.plugins.inserters.available_arc import sweep

        self.state: ArcState | None = None
        self.sweep: sweep.Sweep | None = None
        pack_sweep = arc._pack_sweep
        spy = self

        def capture(st_: ArcState, *args: object, **kwargs: object) -> object:
            spy.state = st_
            return pack_sweep(st_, *args, **kwargs)  # type: ignore[arg-type]

        class Recorded(sweep.Sweep):
            def __init__(self, *args: object, **kwargs: object) -> None:
                super().__init__(*args, **kwargs)  # type: ignore[arg-type]
                spy.sweep = self

        monkeypatch.setattr(arc, "SWEEP_POOL_ROWS", pool_rows)
        monkeypatch.setattr(arc, "_pack_sweep", capture)
        monkeypatch.setattr(sweep, "Sweep", Recorded)


def _sweep_run(
    monkeypatch: pytest.MonkeyPatch, pool_rows: int, seed: int, **cfg: object
) -> tuple[_Spy, bytes, dict[str, object]]:
    spy = _Spy(monkeypatch, pool_rows)
    pop, rng = change5_population(700, seed)
    res = pack(pop, Rectangle.centred(70.0, 260.0), rng, order="sweep", **cfg)
    stats = {k: v for k, v in res.stats.items() if "time" not in k}
    return spy, res.centre.tobytes() + res.insertion_index.tobytes(), stats


@pytest.mark.parametrize(
    ("closing", "strip"), [("paced", 0.0), ("prompt", 0.0), ("tail", 0.0), ("paced", 30.0)]
)
def test_the_sweep_reuses_list_rows_and_packs_as_with_one_row_per_particle(
    monkeypatch: pytest.MonkeyPatch, closing: str, strip: float
) -> None:
    small, key, stats = _sweep_run(monkeypatch, 1, 3, closing=closing, strip=strip)
    _, whole_key, whole_stats = _sweep_run(monkeypatch, 10**9, 3, closing=closing, strip=strip)
    assert key == whole_key
    assert stats == whole_stats
    assert small.state is not None
    p = small.state.packed
    placed = int(np.sum(~np.isnan(p.cx)))
    # the rows of the candidates left behind went back to the pool
    assert np.sum(p.nb_row >= 0) < placed / 2


def test_lists_of_the_candidates_still_in_reach_are_whole_after_rows_are_reused(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from regopack.plugins.inserters.available_arc.sweep import RETIRED

    spy, _, _ = _sweep_run(monkeypatch, 1, 5, closing="tail")
    assert spy.state is not None and spy.sweep is not None
    p = spy.state.packed
    count = spy.state.count
    placed = p.order[:count]
    live = placed[spy.sweep.flag[:count] != RETIRED]
    assert len(live) > 20
    # every candidate that can still be analysed kept its row, and no row is shared
    assert np.all(p.nb_row[live] >= 0)
    rows = p.nb_row[placed]
    assert len(set(rows[rows >= 0].tolist())) == np.sum(rows >= 0)
    assert _checked_lists(p, placed, placed[rows >= 0]) >= 0.9 * len(live)


def test_a_periodic_entry_is_kept_by_the_distance_the_grid_search_computes() -> None:
    """Far from the origin, p's distance to o's image and o's to p's round apart."""
    radius = np.full(3, 1.00003)
    pop = Population(
        radius,
        np.zeros(3, dtype=np.int64),
        ("m",),
        Disk().generate(radius, np.random.default_rng(0)),
    )
    domain = PeriodicRectangle.centred(20.0, 20.0, (2.0**40, 0.0))
    st_ = ArcState(pop, domain, t=0.999, tau=None, linear=False)
    f = st_.packed.fpar
    lx = f[kernel.F_XMAX] - f[kernel.F_XMIN]
    lim = 4.0 * radius[0]
    # o at the left side, p at the right where the two distances fall either side of lim
    xo = f[kernel.F_XMIN] + 1.0
    pair = None
    for _ in range(16):
        xo = np.nextafter(xo, np.inf)
        xp = xo + lx - lim - 3e-3
        for _ in range(60):
            from_p = abs(xo - (xp + (-lx)))
            from_o = abs(xp - (xo + lx))
            if from_p >= lim * (1 + GAP_SLACK) and from_o < lim:
                pair = (xo, xp)
                break
            xp = np.nextafter(xp, np.inf)
        if pair:
            break
    assert pair is not None
    st_.insert(0, pair[0], 0.0)
    st_.insert(1, pair[1], 0.0)
    p = st_.packed
    r = p.nb_row[0]
    entries = [(int(p.nb_o[r, e]), p.nb_dx[r, e]) for e in range(p.nb_n[r])]
    qcx = pair[0]
    qcx += lx  # the grid search about 0's image on the right finds 1 there
    assert entries == [(1, pair[1] - qcx)]


@pytest.mark.parametrize("x", [0.5, 5.0, 9.5])
@pytest.mark.parametrize("y", [0.5, 5.0, 9.5])
@pytest.mark.parametrize("span", [1.0, 6.0])
def test_each_image_code_maps_to_the_query_that_looks_for_it(
    x: float, y: float, span: float
) -> None:
    from regopack.plugins.inserters.available_arc.neighbours import (
        image_code,
        image_query,
        image_shift,
        image_shifts,
    )

    nsx, sx1, sx2 = image_shifts(x, span, 0.0, 10.0)
    nsy, sy1, sy2 = image_shifts(y, span, 0.0, 10.0)
    queried = {}
    for qs in range(nsx * nsy):
        ix = image_shift(qs % nsx, sx1, sx2)
        iy = image_shift(qs // nsx, sy1, sy2)
        queried[image_code(ix, iy)] = qs
    for code in range(9):
        assert image_query(code, nsx, sx1, sx2, nsy, sy1, sy2) == queried.get(code, -1)


def test_a_disk_shut_for_every_particle_gives_its_list_back_when_a_neighbour_comes() -> None:
    from test_disk_path import _disks

    st_ = ArcState(
        _disks(np.ones(4), np.random.default_rng(0)), Rectangle.centred(40.0, 40.0),
        t=0.999, tau=None, linear=False,
    )  # fmt: skip
    p = st_.packed
    st_.insert(0, 0.0, 0.0)
    st_.insert(1, 2.0, 0.0)
    assert p.nb_row[0] >= 0 and p.nb_row[1] >= 0
    free = st_.counter(kernel.I_NBTOP)
    p.shut[0] = p.fpar[kernel.F_RMIN]  # no disk of the scene fits against 0 any more
    p.shut[1] = 1.5 * p.fpar[kernel.F_RMIN]  # only disks below 1.5 fit against 1
    st_.insert(2, 0.0, 2.0)  # a neighbour of both
    assert p.nb_row[0] == -1 and p.nb_row[1] >= 0
    # the row of 0 went back to the pool, the new disk took one
    assert st_.counter(kernel.I_NBTOP) == free
    n1 = p.nb_n[p.nb_row[1]]
    assert 2 in p.nb_o[p.nb_row[1], :n1]
