"""The partner thread of the sweep's search: the packing of one thread, bit for bit."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
import pytest
from arc_helpers import change5_population, pack
from numpy.typing import NDArray
from test_batches import DOMAINS as OVERFILLED
from test_sweep import DOMAINS, disks_and_octagons

from regopack.geometry.domain import Domain, Rectangle
from regopack.geometry.population import Population
from regopack.plugins.common.atomics import compare_swap, load_acquire, spin_hint
from regopack.plugins.inserters.available_arc import batches, bound_queue, partner
from regopack.plugins.sizes.change5 import Change5, Change5Config

pytestmark = pytest.mark.skipif(not partner.available(), reason="the partner needs POSIX")


def _threads(monkeypatch: pytest.MonkeyPatch, threads: int, defer: bool = False) -> None:
    """Run the sweep as on ``threads`` threads; ``defer``: leave every analysis to the partner."""
    make = batches.new_helpers
    # helpers of ``threads`` threads; none (the sequential scans) where a run on one thread
    # asks for none
    monkeypatch.setattr(
        batches, "new_helpers", lambda work, packed, n: make(work, packed, threads if n else 0)
    )
    monkeypatch.setattr(numba, "get_num_threads", lambda: threads)
    if defer:
        shared = partner.new_partner

        def deferring() -> partner.Partner:
            p = shared()
            p.ctl[partner.C_DEFER] = 1
            return p

        monkeypatch.setattr(partner, "new_partner", deferring)


def _run(
    monkeypatch: pytest.MonkeyPatch,
    pop: Population,
    domain: Domain,
    seed: int,
    threads: int,
    defer: bool = False,
    **cfg: object,
) -> tuple[bytes, dict[str, object]]:
    served: list[int] = []
    posted: list[int] = []
    with monkeypatch.context() as m:
        _threads(m, threads, defer)
        stop = partner.PartnerThread.stop

        def counted(self: partner.PartnerThread) -> BaseException | None:
            served.append(self.served)
            if self._arrays is not None:
                posted.append(int(self._arrays[1].bq[bound_queue.TAIL]))
            return stop(self)

        m.setattr(partner.PartnerThread, "stop", counted)
        res = pack(pop, domain, np.random.default_rng(seed), **{"order": "sweep", **cfg})
    stats = dict(res.stats)
    if served:
        stats["served"] = served[-1]
    if posted:
        stats["posted"] = posted[-1]
    return res.centre.tobytes() + res.insertion_index.tobytes(), stats


def _counts(stats: dict[str, object]) -> dict[str, object]:
    """A run's statistics other than its times and the partner's own count."""
    return {k: v for k, v in stats.items() if "time" not in k and k not in ("served", "posted")}


def _same(
    monkeypatch: pytest.MonkeyPatch,
    pop: Population,
    domain: Domain,
    seed: int,
    share: float = 0.5,
    **cfg: object,
) -> dict[str, object]:
    """One thread, two with a partner, and two with the partner analysing everything.

    ``share``: the least share of the analyses that the searches made (the others are
    the exact scans', which the partner does not make).
    """
    alone, alone_stats = _run(monkeypatch, pop, domain, seed, 1, **cfg)
    assert alone_stats["partner"] == 0 and "served" not in alone_stats
    for defer in (False, True):
        key, stats = _run(monkeypatch, pop, domain, seed, 2, defer, **cfg)
        assert key == alone
        for name in ("candidate_analyses", "empty_analyses", "refused", "not_offered"):
            assert stats[name] == alone_stats[name], name
        assert stats["partner"] == 1
        served = stats["served"]
        assert isinstance(served, int)
        if defer:  # every analysis the search read was made by the partner
            analyses = alone_stats["candidate_analyses"]
            assert isinstance(analyses, int)
            assert served >= share * analyses
    return alone_stats


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_partner_gives_the_packing_of_one_thread(
    monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    domain = DOMAINS[kind]
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, _ = change5_population(n, 3)
    _same(monkeypatch, pop, domain, 3, closing="tail")


@pytest.mark.parametrize("closing", ["paced", "prompt"])
def test_partner_with_exact_scans_eta_and_strips(
    monkeypatch: pytest.MonkeyPatch, closing: str
) -> None:
    pop, _ = change5_population(600, 4)
    stats = _same(monkeypatch, pop, OVERFILLED["polygon"], 4, 0.1, closing=closing)
    assert isinstance(stats["refused"], int) and stats["refused"] > 0  # the scans ran
    pop, _ = change5_population(700, 5)
    stats = _same(monkeypatch, pop, Rectangle.centred(110.0, 70.0), 5, 0.1, eta=20.0, strip=40.0)
    assert isinstance(stats["strips"], int) and stats["strips"] > 1


def test_partner_with_disks_among_octagons(monkeypatch: pytest.MonkeyPatch) -> None:
    # rounded envelopes (the disks' bounds are for scenes of disks alone)
    rng = np.random.default_rng(6)
    pop = disks_and_octagons(Change5(Change5Config()).sample(700, rng), rng, 0.5)
    _same(monkeypatch, pop, Rectangle.centred(110.0, 70.0), 6, closing="tail")


def test_disks_alone_have_a_partner_that_proves_bounds(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(7)
    pop = disks_and_octagons(Change5(Change5Config()).sample(300, rng), rng, 1.0)
    domain = Rectangle.centred(60.0, 60.0)
    for order in ("sweep", "paper"):
        alone, alone_stats = _run(monkeypatch, pop, domain, 7, 1, order=order)
        assert "served" not in alone_stats
        key, stats = _run(monkeypatch, pop, domain, 7, 2, order=order)
        assert stats["served"] == 0  # a partner that proves bounds, not analyses
        assert isinstance(stats["posted"], int) and stats["posted"] > 0
        assert key == alone
        same = {"partner": 1, "threads": 2} if order == "sweep" else {}
        assert _counts(stats) == _counts(alone_stats) | same


def test_no_partner_on_one_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    pop, _ = change5_population(300, 7)
    _, stats = _run(monkeypatch, pop, Rectangle.centred(60.0, 60.0), 7, 1)
    assert stats["partner"] == 0 and "served" not in stats


def test_a_failing_partner_leaves_the_search_to_the_caller_and_is_reported(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pop, _ = change5_population(300, 8)
    alone, _ = _run(monkeypatch, pop, Rectangle.centred(60.0, 60.0), 8, 1)

    def broken(g: object, s: object, h: object, p: partner.Partner, rounded: object) -> None:
        if p.ctl[partner.C_STOP] == 0:  # serving, not the entry that compiles the loop
            raise RuntimeError("partner failed")

    with monkeypatch.context() as m:
        m.setattr(partner, "serve", broken)
        # deferring to a dead partner must not wait for it
        _threads(m, 2, defer=True)
        with pytest.raises(RuntimeError, match="partner failed"):
            pack(pop, Rectangle.centred(60.0, 60.0), np.random.default_rng(8), order="sweep")
        # and the packing up to the report is the caller's own: the same one
        m.setattr(partner.PartnerThread, "stop", lambda self: None)  # no report
        res = pack(pop, Rectangle.centred(60.0, 60.0), np.random.default_rng(8), order="sweep")
    assert res.centre.tobytes() + res.insertion_index.tobytes() == alone


@pytest.mark.parametrize("bounds", [False, True])
def test_the_partners_loop_is_first_entered_on_the_calling_thread(
    monkeypatch: pytest.MonkeyPatch, bounds: bool
) -> None:
    """attach enters the loop once on its own thread, told to stop at once, so that it
    compiles there; then the thread runs it."""
    import threading

    from regopack.plugins.inserters.available_arc.state import ArcState

    entries: list[tuple[bool, int]] = []
    served = threading.Event()

    def loop(*args: Any) -> None:
        p = args[-2] if not bounds else args[-1]
        on_main = threading.current_thread() is threading.main_thread()
        entries.append((on_main, int(p.ctl[partner.C_STOP])))
        if not on_main:
            served.set()

    monkeypatch.setattr(partner, "serve_bounds" if bounds else "serve", loop)
    pop, _ = change5_population(50, 1)
    st_ = ArcState(pop, Rectangle.centred(40.0, 40.0), t=0.999, tau=None, linear=False)
    team = partner.PartnerThread(st_.work, st_.packed, bounds=bounds)
    try:
        team.attach(st_.outlines, st_.packed, st_.rounded)
        assert served.wait(timeout=60.0)  # the thread's entry, before stop sets the word
    finally:
        team.stop()
    assert entries == [(True, 1), (False, 0)]


def test_partner_thread_restarts_when_the_arrays_change() -> None:
    from regopack.plugins.inserters.available_arc.state import ArcState

    pop, _ = change5_population(50, 1)
    st_ = ArcState(pop, Rectangle.centred(40.0, 40.0), t=0.999, tau=None, linear=False)
    team = partner.PartnerThread(st_.work, st_.packed)
    try:
        first = team.attach(st_.outlines, st_.packed, st_.rounded)
        thread = team._thread
        assert team.attach(st_.outlines, st_.packed, st_.rounded) is first
        assert team._thread is thread  # the same arrays: the same thread
        st_.reserve_rows(10 * st_.packed.nb_o.shape[0])  # a new pool: new arrays
        team.attach(st_.outlines, st_.packed, st_.rounded)
        assert team._thread is not thread and thread is not None and not thread.is_alive()
    finally:
        assert team.stop() is None
    assert team._thread is None and team.shared.ctl[partner.C_ON] == 0


def test_arcs_too_many_to_hand_back_are_found_again_by_the_caller(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pop, _ = change5_population(300, 9)
    domain = Rectangle.centred(60.0, 60.0)
    alone, alone_stats = _run(monkeypatch, pop, domain, 9, 1)
    shared = partner.new_partner

    def one_arc() -> partner.Partner:
        p = shared()
        p.ctl[partner.C_DEFER] = 1  # the partner analyses everything, hands back one arc
        return p._replace(arcs=np.zeros((partner.SLOTS, 1, 2)))

    with monkeypatch.context() as m:
        _threads(m, 2)
        m.setattr(partner, "new_partner", one_arc)
        res = pack(pop, domain, np.random.default_rng(9), order="sweep")
    assert res.centre.tobytes() + res.insertion_index.tobytes() == alone
    assert res.stats["candidate_analyses"] == alone_stats["candidate_analyses"]


@numba.njit(nogil=True)
def _stalling(ctl: NDArray[np.int64], state: NDArray[np.int64]) -> None:
    """Claim posted slots and never analyse them (a partner without a processor).

    It waits until the caller takes each back, then claims the next.
    """
    while load_acquire(ctl, partner.C_STOP) == 0:
        for sl in range(partner.SLOTS):
            v = load_acquire(state, sl * partner.PAD)
            if v & partner.TAG == partner.POSTED:
                held = v - partner.POSTED + partner.PARTNER
                if compare_swap(state, sl * partner.PAD, v, held):
                    while load_acquire(state, sl * partner.PAD) == held:
                        if load_acquire(ctl, partner.C_STOP) != 0:
                            return
                        spin_hint()
        spin_hint()


def test_the_caller_takes_back_what_a_stalled_partner_holds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pop, _ = change5_population(300, 10)
    domain = Rectangle.centred(60.0, 60.0)
    alone, alone_stats = _run(monkeypatch, pop, domain, 10, 1)

    def stalling(g: Any, s: Any, h: Any, p: partner.Partner, rounded: Any) -> None:
        _stalling(p.ctl, p.state)

    with monkeypatch.context() as m:
        _threads(m, 2)
        m.setattr(partner, "serve", stalling)
        key, stats = _run(m, pop, domain, 10, 2)
    assert key == alone
    assert stats["candidate_analyses"] == alone_stats["candidate_analyses"]


def test_settling_cancels_the_later_slots_and_cuts_their_analyses() -> None:
    """After a success the later slots are cancelled, and the cut reaches their last post id
    (the partner's analysis of any of them stops at its next envelope edge)."""
    p = partner.new_partner()
    pad = partner.PAD
    for q, tag in enumerate([partner.ARCS, partner.POSTED, partner.EMPTY, partner.POSTED]):
        pid = 11 + q
        p.task[q * pad + partner.T_ID] = pid
        p.state[q * pad] = pid * 8 + tag
    partner._settle(p, 1, 4)
    assert p.ctl[partner.C_CUT] == 14
    tags = [int(p.state[q * pad]) & partner.TAG for q in range(4)]
    assert tags == [partner.ARCS, partner.CANCELLED, partner.EMPTY, partner.CANCELLED]
    partner._settle(p, 1, 1)  # nothing to settle: the cut stays
    assert p.ctl[partner.C_CUT] == 14


def test_sweeps_from_two_python_threads_give_their_own_packings(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from concurrent.futures import ThreadPoolExecutor

    pops = [change5_population(400, seed)[0] for seed in (11, 12)]
    domain = Rectangle.centred(70.0, 70.0)
    alone = [_run(monkeypatch, pop, domain, 11, 2)[0] for pop in pops]
    with monkeypatch.context() as m:
        _threads(m, 2)
        with ThreadPoolExecutor(2) as pool:
            jobs = [
                pool.submit(pack, pop, domain, np.random.default_rng(11), order="sweep")
                for pop in pops
            ]
            results = [job.result() for job in jobs]
    assert [r.centre.tobytes() + r.insertion_index.tobytes() for r in results] == alone


@pytest.mark.parametrize("eta", [0.0, 20.0])
def test_partner_in_the_papers_order_gives_the_reference_packing(
    monkeypatch: pytest.MonkeyPatch, eta: float
) -> None:
    pop, _ = change5_population(500, 13)
    domain = DOMAINS["periodic"] if eta else DOMAINS["circle"]
    alone, alone_stats = _run(monkeypatch, pop, domain, 13, 1, order="paper", eta=eta)
    assert "served" not in alone_stats
    for defer in (False, True):
        key, stats = _run(monkeypatch, pop, domain, 13, 2, defer, order="paper", eta=eta)
        assert key == alone
        assert stats["candidate_analyses"] == alone_stats["candidate_analyses"]
        assert isinstance(stats["served"], int)
        if defer:
            assert stats["served"] >= 0.5 * stats["candidate_analyses"]


def test_a_partner_left_running_is_stopped_at_exit() -> None:
    """stop_all (registered with atexit) ends a partner whose insertion never stopped it."""
    from regopack.plugins.inserters.available_arc.state import ArcState

    pop, _ = change5_population(50, 1)
    st_ = ArcState(pop, Rectangle.centred(40.0, 40.0), t=0.999, tau=None, linear=False)
    team = partner.PartnerThread(st_.work, st_.packed)
    team.attach(st_.outlines, st_.packed, st_.rounded)
    thread = team._thread
    assert thread is not None and thread.is_alive() and team in partner._RUNNING
    partner.stop_all()
    assert not thread.is_alive() and team._thread is None
    assert team not in partner._RUNNING


def test_a_process_that_leaves_a_partner_running_exits(tmp_path: Any) -> None:
    """A script that never stops its partner still ends at once after its last line."""
    import subprocess
    import sys
    import time

    script = tmp_path / "leave.py"
    script.write_text(
        "from arc_helpers import change5_population\n"
        "from regopack.geometry.domain import Rectangle\n"
        "from regopack.plugins.inserters.available_arc import partner\n"
        "from regopack.plugins.inserters.available_arc.state import ArcState\n"
        "pop, _ = change5_population(50, 1)\n"
        "st = ArcState(pop, Rectangle.centred(40.0, 40.0), t=0.999, tau=None, linear=False)\n"
        "team = partner.PartnerThread(st.work, st.packed)\n"
        "team.attach(st.outlines, st.packed, st.rounded)\n"
        "assert team._thread.is_alive()\n"
        "print('last line', flush=True)\n"
    )
    import os
    from pathlib import Path

    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parent)}
    proc = subprocess.Popen(
        [sys.executable, str(script)], stdout=subprocess.PIPE, text=True, env=env
    )
    assert proc.stdout is not None
    assert proc.stdout.readline() == "last line\n"
    last = time.monotonic()
    assert proc.wait(timeout=60) == 0
    assert time.monotonic() - last < 10.0
