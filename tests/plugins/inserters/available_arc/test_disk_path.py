"""The analysis of a scene of disks only: no envelopes built, the same arcs bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from arc_helpers import octagon_population, pack
from hypothesis import given, settings
from hypothesis import strategies as st
from test_neighbours import HEXAGON, _rounded_population

from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.geometry.population import Population, ShapeBatch
from regopack.plugins.inserters.available_arc import kernel
from regopack.plugins.inserters.available_arc.state import ArcState
from regopack.plugins.shapes.disk import Disk
from regopack.testing import extreme_radii


def _disks(radius: np.ndarray, rng: np.random.Generator) -> Population:
    n = len(radius)
    return Population(radius, np.zeros(n, dtype=np.int64), ("m",), Disk().generate(radius, rng))


def _packed(pop: Population, domain: Domain, seed: int, closed_form: bool) -> tuple[int, bytes]:
    """Pack with the disks' own analysis on or off; return the flag and the packing's bytes."""
    st_ = ArcState(pop, domain, t=0.999, tau=None, linear=False)
    flag = st_.counter(kernel.I_DISKS)
    if not closed_form:
        st_.packed.ipar[kernel.I_DISKS] = 0
    st_.pack_range(0, len(pop), np.random.default_rng(seed))
    p = st_.packed
    key = p.cx.tobytes() + p.cy.tobytes() + p.order.tobytes()
    return flag, key + bytes(str(st_.counter(kernel.I_ANALYSES)), "ascii")


@pytest.mark.parametrize("kind", ["disks", "mixed", "rounded"])
def test_only_a_scene_of_disks_takes_the_disks_own_analysis(kind: str) -> None:
    st_ = ArcState(
        _rounded_population(50, 3, kind),
        Rectangle.centred(60.0, 60.0),
        t=0.999,
        tau=None,
        linear=False,
    )
    assert st_.counter(kernel.I_DISKS) == (1 if kind == "disks" else 0)


def test_octagons_do_not_take_the_disks_own_analysis() -> None:
    rng = np.random.default_rng(1)
    pop = octagon_population(rng.uniform(1.0, 3.0, 30), rng)
    st_ = ArcState(pop, Rectangle.centred(60.0, 60.0), t=0.999, tau=None, linear=False)
    assert st_.counter(kernel.I_DISKS) == 0


@pytest.mark.parametrize("change", ["core off its centre", "no rounding", "two-vertex core"])
def test_a_population_that_is_not_all_centred_disks_takes_the_general_path(change: str) -> None:
    rng = np.random.default_rng(4)
    radius = rng.uniform(1.0, 3.0, 40)
    batch = Disk().generate(radius, rng)
    vertices = batch.vertices.copy()
    offsets = batch.offsets.copy()
    rounding = np.asarray(batch.rounding).copy()
    if change == "core off its centre":
        vertices[offsets[7]] = (0.25 * rounding[7], 0.0)
    elif change == "no rounding":
        rounding[7] = 0.0
    else:  # particle 7 gets a second vertex where its first is
        vertices = np.insert(vertices, offsets[8], vertices[offsets[7]], axis=0)
        offsets[8:] += 1
    shapes = ShapeBatch(vertices, offsets, batch.orientation, rounding)
    pop = Population(radius, np.zeros(40, dtype=np.int64), ("m",), shapes)
    st_ = ArcState(pop, Rectangle.centred(60.0, 60.0), t=0.999, tau=None, linear=False)
    assert st_.counter(kernel.I_DISKS) == 0


@pytest.mark.parametrize(
    "domain",
    [
        Rectangle.centred(90.0, 80.0, (2.0, -1.0)),
        Circle(1.0, 2.0, 48.0),
        ConvexPolygon(HEXAGON),
        PeriodicRectangle(-40.0, 45.0, -35.0, 40.0),
    ],
)
def test_disks_pack_the_same_with_and_without_their_own_analysis(domain: Domain) -> None:
    pop = _rounded_population(300, 5, "disks")
    flag, fast = _packed(pop, domain, 5, True)
    _, general = _packed(pop, domain, 5, False)
    assert flag == 1
    assert fast == general


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    ratio=st.sampled_from([1.0, 10.0, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_the_same_at_extreme_sizes_and_scales(seed: int, ratio: float, scale: float) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(120, ratio, scale, rng)
    pop = _disks(radius, rng)
    side = 30.0 * scale * (1.0 if ratio < 1e4 else 40.0)
    domain = Rectangle.centred(side, side)
    assert _packed(pop, domain, seed, True) == _packed(pop, domain, seed, False)


@pytest.mark.parametrize("closing", ["paced", "tail"])
def test_the_sweep_packs_disks_the_same_with_and_without_their_own_analysis(
    closing: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    original = ArcState.__init__

    def no_disks(self: ArcState, *args: object, **kwargs: object) -> None:
        original(self, *args, **kwargs)  # type: ignore[arg-type]
        self.packed.ipar[kernel.I_DISKS] = 0

    out = []
    for closed_form in (True, False):
        pop = _rounded_population(500, 11, "disks")
        if not closed_form:
            # the state is built inside pack(): switch the flag off as it is set
            monkeypatch.setattr(ArcState, "__init__", no_disks)
        rng = np.random.default_rng(11)
        res = pack(pop, Rectangle.centred(80.0, 110.0), rng, order="sweep", closing=closing)
        out.append(res.centre.tobytes() + res.insertion_index.tobytes())
    assert out[0] == out[1]


@given(
    nf=st.integers(0, 90),
    seed=st.integers(0, 10_000),
    mode=st.sampled_from(["box", "circle"]),
)
@settings(max_examples=60, deadline=None)
def test_the_scratch_rows_give_what_fresh_arrays_give(nf: int, seed: int, mode: str) -> None:
    """disk_arcs and disk_bound on the rows of Work.fs, laid out as the analysis lays them
    out (interferers in rows 0-2, the box in row 3), give the same arcs and bound as on
    arrays of their own, also past the rows' width (nf > 68: they allocate)."""
    from regopack.plugins.common.walls import WALL_BOX, WALL_CIRCLE
    from regopack.plugins.inserters.available_arc.disk_bound import disk_bound
    from regopack.plugins.inserters.available_arc.rounded import disk_arcs

    rng = np.random.default_rng(seed)
    rho = 1.0
    ang = rng.uniform(0, 2 * np.pi, nf)
    dist = rng.uniform(0.8, 3.0, nf)
    ocx, ocy = dist * np.cos(ang), dist * np.sin(ang)
    orho = rng.uniform(0.2, 1.5, nf)
    box = np.array([-2.5, 2.5, -2.0, 2.0])
    walls = np.array([[0.0, 0.0, 2.2]]) if mode == "circle" else np.zeros((1, 3))
    code = WALL_CIRCLE if mode == "circle" else WALL_BOX
    q = np.zeros(1)
    fs = np.full((kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH), np.nan)
    if nf <= fs.shape[1]:
        fs[0, :nf], fs[1, :nf], fs[2, :nf] = ocx, ocy, orho
        fs[3, :4] = box
        args = (fs[0], fs[1], fs[2], code, walls, fs[3])
    else:
        args = (ocx.copy(), ocy.copy(), orho.copy(), code, walls, box.copy())
    fresh = disk_arcs(rho, 0.1, -0.2, nf, ocx, ocy, orho, code, walls, box, q, q, q, 2.2 - 0.5)
    inner = 2.2 - 0.5
    rows = disk_arcs(rho, 0.1, -0.2, nf, *args, q, q, q, inner, fs)
    np.testing.assert_array_equal(rows, fresh)
    radii = orho * 0.5
    expected = disk_bound(0.5, 0.5, 0.05, nf, ocx, ocy, radii)
    if nf <= fs.shape[1]:
        fs[2, :nf] = radii
    got = disk_bound(
        0.5, 0.5, 0.05, nf, args[0], args[1], fs[2] if nf <= fs.shape[1] else radii, fs
    )
    assert got == expected


@pytest.mark.parametrize("k_walls", [3, 40, 71, 72, 100])
@pytest.mark.parametrize("nf", [0, 2, 64, 70, 73, 145])
def test_scratch_rows_with_many_walls_give_what_fresh_arrays_give(k_walls: int, nf: int) -> None:
    """A polygon domain of many sides: ``2 (nf + walls)`` covers cross the rows' width at
    some point; on both sides of it the rows, full of stale values, give what fresh arrays
    give, and ``disk_arcs`` leaves the interferers' rows as they were for ``disk_bound``."""
    from regopack.plugins.common.walls import WALL_HALFPLANES
    from regopack.plugins.inserters.available_arc.disk_bound import disk_bound
    from regopack.plugins.inserters.available_arc.rounded import disk_arcs

    rng = np.random.default_rng(1000 * k_walls + nf)
    a = 0.3 + 2 * np.pi * np.arange(k_walls) / k_walls
    walls = np.zeros((k_walls, 3))
    walls[:, 0], walls[:, 1] = np.cos(a), np.sin(a)
    woff = 1.2 + rng.uniform(0, 0.5, k_walls)  # some walls cut the circle of centres
    ang = rng.uniform(0, 2 * np.pi, nf)
    dist = rng.uniform(0.8, 3.0, nf)
    ocx, ocy = dist * np.cos(ang), dist * np.sin(ang)
    orho = rng.uniform(0.05, 0.6, nf)
    box = np.zeros(4)
    q = np.zeros(1)
    code = WALL_HALFPLANES
    fresh = disk_arcs(1.0, 0.05, -0.1, nf, ocx, ocy, orho, code, walls, box, woff, q, q, 0.0)
    fs = np.full((kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH), np.nan)
    fits = nf <= fs.shape[1]
    if fits:  # laid out as analyze_candidate lays them out
        fs[0, :nf], fs[1, :nf], fs[2, :nf] = ocx, ocy, orho
        fs[3, :4] = box
        args = (fs[0], fs[1], fs[2], code, walls, fs[3])
    else:
        args = (ocx.copy(), ocy.copy(), orho.copy(), code, walls, box.copy())
    rows = disk_arcs(1.0, 0.05, -0.1, nf, *args, woff, q, q, 0.0, fs)
    np.testing.assert_array_equal(rows, fresh)
    radii = orho * 0.5
    if fits:
        np.testing.assert_array_equal(fs[0, :nf], ocx)
        np.testing.assert_array_equal(fs[1, :nf], ocy)
        fs[2, :nf] = radii
    got = disk_bound(0.5, 0.5, 0.05, nf, args[0], args[1], fs[2] if fits else radii, fs)
    assert got == disk_bound(0.5, 0.5, 0.05, nf, ocx, ocy, radii)


def test_every_thread_and_the_partner_have_scratch_rows_of_their_own() -> None:
    """The batches' threads, the partner and the calling thread write their analyses'
    scratch rows at the same time: no two may share memory."""
    from regopack.plugins.inserters.available_arc import batches, partner

    rng = np.random.default_rng(3)
    pop = _disks(rng.uniform(1.0, 2.0, 30), rng)
    st_ = ArcState(pop, Rectangle(0.0, 40.0, 0.0, 40.0), t=0.999, tau=None, linear=False)
    h = batches.new_helpers(st_.work, st_.packed, 4)
    mate = partner.PartnerThread(st_.work, st_.packed)
    assert h.fs.shape == (4, kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH)
    for field in ("fs", "found_q", "va"):  # an analysis of polygons writes all three
        rows = [getattr(h, field)[t] for t in range(4)]
        rows += [getattr(mate.helpers, field)[0], getattr(st_.work, field)]
        for a in range(len(rows)):
            for b in range(a + 1, len(rows)):
                assert not np.shares_memory(rows[a], rows[b]), field
