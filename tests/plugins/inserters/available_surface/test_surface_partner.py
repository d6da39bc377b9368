"""The partner thread of the 3D scans: the packing of one thread, bit for bit."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
import pytest
from numpy.typing import NDArray
from test_surface_inserter import scene, sweep_scene

import regopack
from regopack.plugins.common.atomics import compare_swap, load_acquire, spin_hint
from regopack.plugins.inserters.available_arc.partner import available
from regopack.plugins.inserters.available_surface import partner
from regopack.plugins.inserters.available_surface import state as state_module
from regopack.plugins.inserters.available_surface.analysis import cache_for

pytestmark = pytest.mark.skipif(not available(), reason="the partner needs POSIX")

SPHERES = [{"name": "glass", "fraction": 1.0, "shape": {"kind": "sphere"}}]
SCENES = {
    "paper": lambda: scene(count=120, domain={"kind": "box", "width": 16.0, "height": 16.0,
                                              "depth": 16.0}),
    "sweep": lambda: sweep_scene(),
    "periodic": lambda: sweep_scene(
        count=120, domain={"kind": "periodic-box", "width": 12.0, "height": 14.0, "depth": 12.0}
    ),
}  # fmt: skip


def _run(
    monkeypatch: pytest.MonkeyPatch, data: dict[str, Any], threads: int
) -> tuple[bytes, dict[str, Any], list[int]]:
    """Pack ``data`` as on ``threads`` threads; the key, the stats, the partners' analyses."""
    served: list[int] = []
    stop = partner.PartnerThread.stop

    def counted(self: partner.PartnerThread) -> BaseException | None:
        served.append(self.served)
        return stop(self)

    with monkeypatch.context() as m:
        m.setattr(numba, "get_num_threads", lambda: threads)
        m.setattr(partner.PartnerThread, "stop", counted)
        p = regopack.pack(data, verify=False)
    return p.centre.tobytes() + p.insertion_index.tobytes(), dict(p.stats), served


def _defer(m: pytest.MonkeyPatch) -> None:
    """Leave every analysis ahead of the order to the partner."""
    shared = partner.new_surface_partner

    def deferring() -> partner.SurfacePartner:
        p = shared()
        p.ctl[partner.C_DEFER] = 1
        return p

    m.setattr(partner, "new_surface_partner", deferring)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_a_partner_gives_the_packing_of_one_thread(
    monkeypatch: pytest.MonkeyPatch, name: str
) -> None:
    data = SCENES[name]()
    alone, alone_stats, none = _run(monkeypatch, data, 1)
    assert alone_stats["partner"] == 0 and none == []
    key, stats, served = _run(monkeypatch, data, 2)
    assert stats["partner"] == 1 and len(served) == 1
    assert key == alone
    for count in ("candidate_analyses", "empty_analyses"):
        assert stats[count] == alone_stats[count]
    with monkeypatch.context() as m:
        _defer(m)
        key, stats, served = _run(m, data, 2)
    assert key == alone
    assert stats["candidate_analyses"] == alone_stats["candidate_analyses"]
    # deferred to, the partner makes every analysis but the caller's own at a free surface
    assert served[0] >= alone_stats["empty_analyses"]


def test_caches_that_fill_grow_on_both_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    data = SCENES["paper"]()
    alone, alone_stats, _ = _run(monkeypatch, data, 1)
    with monkeypatch.context() as m:
        m.setattr(state_module, "cache_for", lambda n, rows: cache_for(n, 8))
        for defer in (False, True):
            with m.context() as inner:
                if defer:
                    _defer(inner)
                key, stats, _ = _run(inner, data, 2)
            assert key == alone
            assert stats["candidate_analyses"] == alone_stats["candidate_analyses"]


@numba.njit(nogil=True)
def _stalling(ctl: NDArray[np.int64], state: NDArray[np.int64], claims: int) -> None:
    """Claim ``claims`` posted slots and never analyse them (a partner without a processor).

    It waits until the caller takes each back, then claims the next; then it stops.
    """
    while claims > 0 and load_acquire(ctl, partner.C_STOP) == 0:
        for sl in range(partner.SLOTS):
            v = load_acquire(state, sl * partner.PAD)
            if v & partner.TAG == partner.POSTED:
                held = v - partner.POSTED + partner.PARTNER
                if compare_swap(state, sl * partner.PAD, v, held):
                    claims -= 1
                    while load_acquire(state, sl * partner.PAD) == held:
                        if load_acquire(ctl, partner.C_STOP) != 0:
                            return
                        spin_hint()
        spin_hint()


def test_the_caller_takes_back_what_a_stalled_partner_holds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = SCENES["sweep"]()
    alone, alone_stats, _ = _run(monkeypatch, data, 1)

    def stalling(*args: Any) -> None:
        p = args[-2]
        _stalling(p.ctl, p.state, 0 if p.ctl[partner.C_STOP] else 5)

    with monkeypatch.context() as m:
        m.setattr(partner, "serve", stalling)
        key, stats, _ = _run(m, data, 2)
    assert key == alone
    assert stats["candidate_analyses"] == alone_stats["candidate_analyses"]


def test_a_failing_partner_leaves_the_scans_to_the_caller_and_is_reported(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = SCENES["paper"]()
    alone, _, _ = _run(monkeypatch, data, 1)

    def broken(*args: Any) -> None:
        if args[-2].ctl[partner.C_STOP] == 0:  # serving, not the entry that compiles the loop
            raise RuntimeError("partner failed")

    with monkeypatch.context() as m:
        m.setattr(partner, "serve", broken)
        _defer(m)  # deferring to a dead partner must not wait for it
        with pytest.raises(RuntimeError, match="partner failed"):
            _run(m, data, 2)
        # and the packing up to the report is the caller's own: the same one
        m.setattr(partner.PartnerThread, "stop", lambda self: None)
        m.setattr(numba, "get_num_threads", lambda: 2)
        p = regopack.pack(data, verify=False)
    assert p.centre.tobytes() + p.insertion_index.tobytes() == alone


@pytest.mark.parametrize(
    "changes",
    [{"density": {"kind": "eta", "eta": 0.9}}, {"phases": SPHERES}],
    ids=["eta", "spheres"],
)
def test_no_partner_for_spheres_nor_with_a_margin(
    monkeypatch: pytest.MonkeyPatch, changes: dict[str, Any]
) -> None:
    _, stats, served = _run(monkeypatch, scene(count=30, **changes), 2)
    assert stats["partner"] == 0 and served == []


def test_a_partner_left_running_is_stopped_at_exit(monkeypatch: pytest.MonkeyPatch) -> None:
    """stop_all (registered with atexit) ends a partner whose insertion never stopped it."""
    from regopack.plugins.inserters.available_surface.state import SurfaceState

    solids = regopack.pack(scene(count=5), verify=False).solids
    st = SurfaceState(solids, np.ones(len(solids)), np.zeros(3), np.full(3, 30.0))
    monkeypatch.setattr(numba, "get_num_threads", lambda: 2)
    assert st.start_partner()
    team = st._partner
    assert team is not None
    thread = team._thread
    assert thread is not None and thread.is_alive() and team in partner._RUNNING
    partner.stop_all()
    assert not thread.is_alive() and team._thread is None
    assert team not in partner._RUNNING


def test_a_candidate_listed_twice_is_screened_as_by_one_thread(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A candidate posted ahead before its earlier copy was found empty is screened out when
    the scan reaches it, as one thread screens it (the same counts)."""
    from regopack.plugins.inserters.available_surface.state import SurfaceState

    box = {"kind": "box", "width": 16.0, "height": 16.0, "depth": 16.0}
    packing = regopack.pack(scene(count=80, seed=5, domain=box), verify=False)
    radius = np.cbrt(3.0 * packing.solids.volume / (4.0 * np.pi))
    lo, hi = np.zeros(3) - 8.0, np.zeros(3) + 8.0
    order = packing.placed_in_order()
    results = []
    for threads in (1, 2):
        monkeypatch.setattr(numba, "get_num_threads", lambda threads=threads: threads)
        st = SurfaceState(packing.solids, radius, lo, hi)
        assert st.start_partner() == (threads == 2)
        try:
            for j in order[:20]:
                st.begin(int(j))
                st.insert(int(j), packing.centre[j])
            st.begin(int(order[20]))
            k, x = st.scan(np.repeat(np.arange(20), 2), np.random.default_rng(1))
        finally:
            assert st.stop_partner() is None
        assert x is not None
        results.append((k, x.tobytes(), st.analyses, st.empty))
    assert results[0] == results[1]
    assert results[0][2] > results[0][3] > 0


def test_deferring_to_a_partner_that_ends_mid_scan_does_not_hang(tmp_path: Any) -> None:
    """The scan releases Python's lock, so a partner's wrapper can mark it dead while the
    scan waits for a slot it holds; the error is then reported. (The partner answers
    its first fifty posts 'free' at once, which has the scan analyse them itself in its
    order, then holds one and ends.)"""
    import subprocess
    import sys
    from pathlib import Path

    script = tmp_path / "ending.py"
    script.write_text(
        "import numba\n"
        "import regopack\n"
        "from test_surface_inserter import scene\n"
        "from regopack.plugins.common.atomics import compare_swap, load_acquire, spin_hint\n"
        "from regopack.plugins.inserters.available_surface import partner\n"
        "numba.get_num_threads = lambda: 2\n"
        "@numba.njit(nogil=True)\n"
        "def claim_one(ctl, state):\n"
        "    while load_acquire(ctl, partner.C_STOP) == 0:\n"
        "        for sl in range(partner.SLOTS):\n"
        "            v = load_acquire(state, sl * partner.PAD)\n"
        "            if v & partner.TAG == partner.POSTED:\n"
        "                if compare_swap(state, sl * partner.PAD, v, v + 1):\n"
        "                    if v >> 3 > 50:\n"
        "                        return\n"
        "                    # answers 'free': the scan then analyses it in its order\n"
        "                    compare_swap(state, sl * partner.PAD, v + 1, v + 4)\n"
        "        spin_hint()\n"
        "serve = partner.serve\n"
        "def ending(*args):\n"
        "    p = args[-2]\n"
        "    if p.ctl[partner.C_STOP]:\n"
        "        return serve(*args)\n"
        "    claim_one(p.ctl, p.state)\n"
        "    raise RuntimeError('partner ended')\n"
        "shared = partner.new_surface_partner\n"
        "def deferring():\n"
        "    p = shared()\n"
        "    p.ctl[partner.C_DEFER] = 1\n"
        "    return p\n"
        "partner.serve = ending\n"
        "partner.new_surface_partner = deferring\n"
        "try:\n"
        "    regopack.pack(scene(count=60), verify=False)\n"
        "    print('no error')\n"
        "except RuntimeError as exc:\n"
        "    print('reported:', exc)\n"
    )
    import os

    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parent)}
    done = subprocess.run(
        [sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=240
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "reported: partner ended" in done.stdout


@pytest.mark.parametrize("layer", ["omp", "workqueue"])
def test_a_process_that_leaves_a_partner_running_exits(tmp_path: Any, layer: str) -> None:
    """A script that never stops its partner still ends at once after its last line,
    whichever threading layer numba runs (the partner is a daemon thread of its own)."""
    import os
    import subprocess
    import sys
    import time
    from pathlib import Path

    script = tmp_path / "leave.py"
    script.write_text(
        "import numpy as np\n"
        "import regopack\n"
        "from test_surface_inserter import scene\n"
        "from regopack.plugins.inserters.available_surface.state import SurfaceState\n"
        "solids = regopack.pack(scene(count=5), verify=False).solids\n"
        "st = SurfaceState(solids, np.ones(len(solids)), np.zeros(3), np.full(3, 30.0))\n"
        "assert st.start_partner() and st._partner._thread.is_alive()\n"
        "print('last line', flush=True)\n"
    )
    env = {
        **os.environ,
        "PYTHONPATH": str(Path(__file__).parent),
        "NUMBA_NUM_THREADS": "2",
        "NUMBA_THREADING_LAYER": layer,
    }
    proc = subprocess.Popen(
        [sys.executable, str(script)], stdout=subprocess.PIPE, text=True, env=env
    )
    assert proc.stdout is not None
    assert proc.stdout.readline() == "last line\n"
    last = time.monotonic()
    assert proc.wait(timeout=60) == 0
    assert time.monotonic() - last < 10.0
