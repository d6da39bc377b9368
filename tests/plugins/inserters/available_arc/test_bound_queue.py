"""The ring of disk bounds the partner proves: the same bounds as proved at once."""

from __future__ import annotations

import functools
import math
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_disk_bound import _ring
from test_disk_path import _disks

from regopack.geometry.domain import Rectangle
from regopack.plugins.inserters.available_arc import batches, kernel, partner
from regopack.plugins.inserters.available_arc import bound_queue as Q
from regopack.plugins.inserters.available_arc.disk_bound import disk_bound
from regopack.plugins.inserters.available_arc.state import ArcState


def _post(ctl: np.ndarray, rows: np.ndarray, pk: int, rk: float, r_fail: float,
          c: np.ndarray, rad: np.ndarray) -> bool:  # fmt: skip
    return bool(
        Q.post_bound(ctl, rows, pk, rk, r_fail, len(rad), c[:, 0].copy(), c[:, 1].copy(), rad)
    )


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    m=st.integers(2, Q.WIDTH),
    spread=st.sampled_from([0.0, 0.7, 2.3, 4.6]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_a_posted_bound_is_the_bound_proved_at_once(
    seed: int, m: int, spread: float, scale: float
) -> None:
    rng = np.random.default_rng(seed)
    c, rad = _ring(rng, scale, m, spread)
    r_fail = scale * float(np.exp(rng.uniform(-2.0, 2.0)))
    r_floor = 1e-2 * scale
    ctl, rows = Q.new_queue(True)
    shut = np.full(3, np.inf)
    shut[1] = 5.0 * r_fail  # a weaker bound known before
    scratch = np.empty((kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH))
    assert _post(ctl, rows, 1, scale, r_fail, c, rad)
    assert Q.prove_next(ctl, rows, shut, r_floor, scratch)
    assert not Q.prove_next(ctl, rows, shut, r_floor, scratch)  # nothing waits
    expected = disk_bound(scale, r_fail, r_floor, m, c[:, 0].copy(), c[:, 1].copy(), rad)
    assert shut[1] == min(expected, 5.0 * r_fail)
    assert math.isinf(shut[0]) and math.isinf(shut[2])
    assert ctl[Q.HEAD] == ctl[Q.TAIL] == 1


def test_the_ring_refuses_a_post_when_full_too_wide_or_absent() -> None:
    rng = np.random.default_rng(1)
    c, rad = _ring(rng, 1.0, 6, 0.7)
    ctl, rows = Q.new_queue(True)
    shut = np.full(Q.SLOTS + 1, np.inf)
    scratch = np.empty((kernel.SCRATCH_ROWS, kernel.SCRATCH_WIDTH))
    for pk in range(Q.SLOTS):
        assert _post(ctl, rows, pk, 1.0, 2.0, c, rad)
    assert not _post(ctl, rows, Q.SLOTS, 1.0, 2.0, c, rad)  # full: the caller proves it
    assert Q.prove_next(ctl, rows, shut, 0.01, scratch)
    assert _post(ctl, rows, Q.SLOTS, 1.0, 2.0, c, rad)  # a slot is free again
    while Q.prove_next(ctl, rows, shut, 0.01, scratch):
        pass
    expected = disk_bound(1.0, 2.0, 0.01, 6, c[:, 0].copy(), c[:, 1].copy(), rad)
    assert np.all(shut == expected)  # every slot, the reused one included
    wide_c, wide_rad = _ring(rng, 1.0, Q.WIDTH + 1, 0.7)
    assert not _post(ctl, rows, 0, 1.0, 2.0, wide_c, wide_rad)
    off_ctl, off_rows = Q.new_queue(False)  # a scene without bounds: no slots
    assert not _post(off_ctl, off_rows, 0, 1.0, 2.0, c, rad)


def _filled(post: bool) -> ArcState:
    """Disks around disk 0, then disk 7 analysed at 0 (it finds no arc)."""
    r = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.5])
    st_ = ArcState(
        _disks(r, np.random.default_rng(0)), Rectangle.centred(40.0, 40.0),
        t=0.999, tau=None, linear=False,
    )  # fmt: skip
    assert st_.counter(kernel.I_BOUND) == kernel.BOUND_PROVE
    if post:
        st_.packed.ipar[kernel.I_BOUND] = kernel.BOUND_POST
    st_.insert(0, 0.0, 0.0)
    for j in range(6):
        a = j * np.pi / 3.0
        st_.insert(j + 1, 2.0 * float(np.cos(a)), 2.0 * float(np.sin(a)))
    p = st_.packed
    arcs = kernel.analyze_candidate(0, 7, st_.begin_particle(7), st_.outlines, p, st_.work, True)
    assert arcs.shape[0] == 0
    return st_


def test_an_analysis_posts_its_bound_and_the_partner_proves_it() -> None:
    inline = _filled(False).packed.shut[0]
    assert inline <= 1.05  # the six disks shut disk 0 from about radius 1 on
    st_ = _filled(True)
    p = st_.packed
    assert p.bq[Q.TAIL] == 1 and math.isinf(p.shut[0])  # posted, not proved yet
    team = partner.PartnerThread(st_.work, p, bounds=True)
    try:
        shared = team.attach(st_.outlines, p, st_.rounded)
        assert shared.ctl[partner.C_ON] == 0  # it analyses no candidates
        deadline = time.monotonic() + 60.0
        while p.bq[Q.HEAD] < 1 and time.monotonic() < deadline:
            time.sleep(0.001)
        assert p.bq[Q.HEAD] == 1, "the partner proved no bound in a minute"
        assert p.shut[0] == inline
    finally:
        assert team.stop() is None


def test_the_partner_has_the_search_post_its_bounds_while_it_runs() -> None:
    st_ = _filled(False)  # proved at once so far
    p = st_.packed
    assert st_.counter(kernel.I_BOUND) == kernel.BOUND_PROVE and p.bq[Q.TAIL] == 0
    team = partner.PartnerThread(st_.work, p, bounds=True)
    try:
        team.attach(st_.outlines, p, st_.rounded)
        assert st_.counter(kernel.I_BOUND) == kernel.BOUND_POST
        st_.reserve_rows(10 * p.nb_o.shape[0])  # new arrays: the thread restarts
        team.attach(st_.outlines, st_.packed, st_.rounded)
        assert st_.counter(kernel.I_BOUND) == kernel.BOUND_POST
    finally:
        assert team.stop() is None
    # no one proves posted bounds once the partner has stopped
    assert st_.counter(kernel.I_BOUND) == kernel.BOUND_PROVE
    # nor does a helper of the exact scans: its bounds go to its own row
    st_.packed.ipar[kernel.I_BOUND] = kernel.BOUND_POST
    helpers = batches.new_helpers(st_.work, st_.packed, 2)
    assert np.all(helpers.ipar[:, kernel.I_BOUND] == kernel.BOUND_PROVE)
    assert helpers.shut.shape == (2, st_.packed.shut.shape[0])


def _packed(bounds: int) -> tuple[bytes, int, int]:
    """400 disks of a size ratio 8 in the paper's order: the packing, its analyses, posts."""
    rng = np.random.default_rng(4)
    r = np.exp(rng.uniform(np.log(0.5), np.log(4.0), 400))
    st_ = ArcState(_disks(r, rng), Rectangle.centred(50.0, 50.0), t=0.999, tau=None, linear=False)
    st_.packed.ipar[kernel.I_BOUND] = bounds
    st_.pack_range(0, len(r), np.random.default_rng(5))
    p = st_.packed
    key = p.cx.tobytes() + p.cy.tobytes() + p.order.tobytes()
    return key, st_.counter(kernel.I_ANALYSES), int(p.bq[Q.TAIL])


@functools.cache
def _without_bounds() -> tuple[bytes, int, int]:
    return _packed(kernel.BOUND_OFF)


@pytest.mark.parametrize("bounds", [kernel.BOUND_PROVE, kernel.BOUND_POST])
def test_every_way_of_proving_bounds_packs_the_same(bounds: int) -> None:
    key, analyses, posted = _packed(bounds)
    # with no partner, posted bounds wait in the ring (the first SLOTS of them)
    assert (posted > 0) == (bounds == kernel.BOUND_POST)
    assert (key, analyses) == _without_bounds()[:2]
