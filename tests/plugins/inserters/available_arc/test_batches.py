"""Exact scans on threads: the packing of the sequential scan, bit for bit."""

from __future__ import annotations

from collections.abc import Iterator

import numba
import numpy as np
import pytest
from arc_helpers import change5_population, pack
from test_sweep import disks_and_octagons

from regopack.geometry.domain import Circle, ConvexPolygon, Domain, Rectangle
from regopack.geometry.population import Population
from regopack.plugins.inserters.available_arc import batches
from regopack.plugins.sizes.change5 import Change5, Change5Config

HEXAGON = tuple((52.0 * np.cos(a), 52.0 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1])
DOMAINS: dict[str, Domain] = {
    "rectangle": Rectangle.centred(90.0, 80.0, (3.0, -2.0)),
    "polygon": ConvexPolygon(HEXAGON),
    "circle": Circle(5.0, -3.0, 47.0),
}
"""Domains that 600 Chang'e-5 particles overfill, so that the exact scans run."""


@pytest.fixture
def one_thread() -> Iterator[None]:
    """Run the sweep on one thread: no helpers, the sequential scans."""
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(before)


def _force_threads(monkeypatch: pytest.MonkeyPatch, threads: int) -> None:
    """Give the sweep helpers for ``threads`` threads, whatever the machine has."""
    make = batches.new_helpers
    monkeypatch.setattr(
        batches, "new_helpers", lambda work, packed, _threads: make(work, packed, threads)
    )
    monkeypatch.setattr(numba, "get_num_threads", lambda: max(threads, 2))


def _run(
    pop: Population, domain: Domain, seed: int, **cfg: object
) -> tuple[bytes, dict[str, object]]:
    res = pack(pop, domain, np.random.default_rng(seed), order="sweep", **cfg)
    stats = {
        k: v for k, v in res.stats.items() if "time" not in k and k not in ("threads", "partner")
    }
    return res.centre.tobytes() + res.insertion_index.tobytes(), stats


def _compare(
    monkeypatch: pytest.MonkeyPatch, pop: Population, domain: Domain, seed: int, **cfg: object
) -> dict[str, object]:
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        alone, alone_stats = _run(pop, domain, seed, **cfg)
    finally:
        numba.set_num_threads(before)
    assert isinstance(alone_stats["refused"], int) and alone_stats["refused"] > 0  # exact scans ran
    for threads in (2, 3, 5):
        with monkeypatch.context() as m:
            _force_threads(m, threads)
            key, stats = _run(pop, domain, seed, **cfg)
        assert key == alone
        assert stats == alone_stats
    return alone_stats


@pytest.mark.parametrize("closing", ["paced", "prompt"])
@pytest.mark.parametrize("kind", ["rectangle", "polygon", "circle"])
def test_exact_scans_on_threads_give_the_sequential_packing(
    monkeypatch: pytest.MonkeyPatch, kind: str, closing: str
) -> None:
    pop, _ = change5_population(600, 4)
    _compare(monkeypatch, pop, DOMAINS[kind], 4, closing=closing, eta=0.0)


def test_exact_scans_on_threads_with_disks_strips_and_eta(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(6)
    pop = disks_and_octagons(Change5(Change5Config()).sample(700, rng), rng, 0.5)
    stats = _compare(monkeypatch, pop, Rectangle.centred(110.0, 70.0), 6, strip=40.0)
    assert isinstance(stats["strips"], int) and stats["strips"] > 1
    pop, _ = change5_population(500, 8)
    res_stats = _compare(monkeypatch, pop, Rectangle.centred(70.0, 70.0), 8)
    assert isinstance(res_stats["candidate_analyses"], int) and res_stats["candidate_analyses"] > 0


def test_eta_draws_stay_in_the_sequential_order(monkeypatch: pytest.MonkeyPatch) -> None:
    pop, _ = change5_population(500, 9)
    before = numba.get_num_threads()
    out = []
    for threads in (1, 2):
        with monkeypatch.context() as m:
            if threads == 1:
                numba.set_num_threads(1)
            else:
                _force_threads(m, threads)
            try:
                res = pack(
                    pop, Rectangle.centred(70.0, 70.0), np.random.default_rng(9), eta=20.0,
                    order="sweep",
                )  # fmt: skip
            finally:
                numba.set_num_threads(before)
        out.append(res.centre.tobytes())
    assert out[0] == out[1]


def test_one_thread_keeps_no_helpers(one_thread: None) -> None:
    pop, rng = change5_population(200, 2)
    res = pack(pop, Rectangle.centred(50.0, 50.0), rng, order="sweep")
    assert res.stats["threads"] == 1


def test_helpers_keep_every_thread_on_its_own_cache_lines() -> None:
    pop, _ = change5_population(50, 1)
    from regopack.plugins.inserters.available_arc.state import ArcState

    st_ = ArcState(pop, Rectangle.centred(40.0, 40.0), t=0.999, tau=None, linear=False)
    h = batches.new_helpers(st_.work, st_.packed, 3)
    for name in batches.PADDED:
        assert getattr(h, name).shape[1] == getattr(st_.work, name).shape[0] + batches.PAD
    assert h.ks.shape == (3 * batches.PER_THREAD,)
    assert np.all(h.ckey == -1)
