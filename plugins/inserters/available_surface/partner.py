"""A partner thread that analyses a polyhedron's next candidates ahead of its scan.

The 3D scan (:func:`.analysis.scan`) offers a polyhedron to its candidates
in order and stops at the first with a free surface; about nine analyses in
ten find none, and each costs hundreds of microseconds. With a partner, the
scan posts its next candidates (the screening's next :data:`SLOTS`) and a
second thread claims and analyses them while the calling thread analyses
the others, by the hand-off of the 2D search
(:mod:`~regopack.plugins.inserters.available_arc.partner`: state words
``id << 3 | tag``, claims by compare-and-swap, the caller takes back a slot
the partner holds too long).

The calling thread reads the answers strictly in the scan's order, exactly
as :func:`.analysis.scan` meets them: an empty candidate is counted and its
screening radius recorded. A candidate with a free surface is analysed
again by the calling thread, which then draws the centre from the run's
generator as the plain scan does (an answer of the partner, or of the
caller ahead of the order, carries no draw). Analyses read the packing and
write only their thread's scratch (the half-space cache), and the calling
thread makes each particle's edge arcs when it is placed
(:meth:`.state.SurfaceState.insert`), so the packing, the draws and the
counts are the same, bit for bit, with a partner or without one.

Only scans without a packing control margin (``eta = 0``) are shared: with a
margin, each analysis draws its own ``xi`` from the run's generator before
it runs, and an answer ahead of the order would need a draw the plain scan
has not made yet. Spheres, whose analyses cost tens of microseconds, scan
alone.
"""

from __future__ import annotations

import atexit
import threading
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.atomics import (
    compare_swap,
    load_acquire,
    store_release,
)
from regopack.plugins.common.borrowed import borrowed
from regopack.plugins.common.kernel_random import KernelSource
from regopack.plugins.inserters.available_arc.candidates import tree_set
from regopack.plugins.inserters.available_arc.partner import (
    ARCS,
    C_DEAD,
    C_DEFER,
    C_ID,
    C_ON,
    C_SERVED,
    C_STOP,
    CALLER,
    CANCELLED,
    EMPTY,
    N_CTL,
    PAD,
    PARTNER,
    POSTED,
    T_I,
    T_ID,
    T_PK,
    TAG,
    _idle,
    _wait,
    claim,
)
from regopack.plugins.inserters.available_surface.analysis import EMPTY as NOTHING
from regopack.plugins.inserters.available_surface.analysis import (
    FOUND,
    FULL,
    Arcs,
    Bounds,
    Grid,
    HalfspaceCache,
    Placed,
    Screening,
    Solids,
    analyse,
    grown,
    next_screened,
    solid,
)
from regopack.plugins.inserters.available_surface.envelope import EdgeArcs, edge_arcs

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

FREE = ARCS
"""Slot tag: the candidate has a free surface (the 2D hand-off's tag for arcs)."""
TAKEOVER = 60_000
"""Polls the caller waits for a slot the partner holds before it takes the slot back: some
milliseconds, several of the partner's analyses (a 2D analysis is a hundred times shorter:
its hand-off takes a slot back sooner). A partner without a processor (another process
runs) costs parallelism, not the run's time."""
SLOTS = 3
"""Candidates posted ahead of the one the scan reads: one for each thread to analyse and one
for the caller to take next. More slots analyse more candidates past the one that takes the
particle (eight: 25 % more analyses than one thread makes, three: 16 %), for no gain
measured."""
F_REACH, F_ADM = 0, 1
"""``fpar``: the largest circumradius placed; the admissible centres' box (six values)."""


class SurfacePartner(NamedTuple):
    """What a 3D scan and its partner thread share (slot words as in the 2D hand-off)."""

    ctl: IntArray
    state: IntArray
    task: IntArray
    k: IntArray
    """``k[slot]``: the posted candidate's position in the scan's list."""
    fpar: FloatArray
    """The scan's particle: :data:`F_REACH`, the admissible box from :data:`F_ADM`."""


def new_surface_partner() -> SurfacePartner:
    """Shared arrays for a scan and its partner; none serves yet."""
    return SurfacePartner(
        ctl=np.zeros(N_CTL, dtype=np.int64),
        state=np.zeros(SLOTS * PAD, dtype=np.int64),
        task=np.zeros(SLOTS * PAD, dtype=np.int64),
        k=np.zeros(SLOTS, dtype=np.int64),
        fpar=np.zeros(PAD),
    )


@numba.njit(cache=True, nogil=True)
def serve(
    s: Solids,
    a: Arcs,
    g: Grid,
    own: HalfspaceCache,
    order: IntArray,
    centre: FloatArray,
    circum: FloatArray,
    period: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    wall: FloatArray,
    p: SurfacePartner,
    rng: KernelSource,
) -> None:
    """Claim posted slots and analyse them until asked to stop (the partner's loop).

    ``wall`` is a cylinder's side wall (:attr:`.analysis.Bounds.wall`; empty: none).

    ``own`` is the partner's half-space cache (grown here when full); ``rng``
    is never drawn from (the analyses give their answer alone).
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    s, a, g, order, centre, circum = (
        borrowed(s), borrowed(a), borrowed(g), borrowed(order), borrowed(centre),
        borrowed(circum),
    )  # fmt: skip
    period, lo, hi, p = borrowed(period), borrowed(lo), borrowed(hi), borrowed(p)
    wall = borrowed(wall)
    cache = own
    nothing = np.empty(0)  # the answer alone: no centre drawn
    last = -1
    q_arcs = EdgeArcs(
        np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((0, 3)),
        np.zeros((0, 6)),
    )  # fmt: skip
    idle = 0
    while load_acquire(p.ctl, C_STOP) == 0:
        best, word = claim(p.state, SLOTS)
        if best < 0:
            idle += 1
            _idle(p.ctl, idle)
            continue
        idle = 0
        base = best * PAD
        i = p.task[base + T_I]
        if i != last:
            q_arcs = edge_arcs(solid(s, i), -1.0)
            cache.fill[0] = 0
            last = i
        placed = Placed(order, centre, circum, p.fpar[F_REACH])
        bounds = Bounds(
            period, lo, hi, p.fpar[F_ADM : F_ADM + 3].copy(), p.fpar[F_ADM + 3 : F_ADM + 6].copy(),
            wall,
        )  # fmt: skip
        k = p.task[base + T_PK]  # the candidate's insertion index
        code = analyse(k, i, q_arcs, s, a, g, cache, placed, bounds, 0.0, rng, nothing)
        while code == FULL:
            cache = grown(cache)
            code = analyse(k, i, q_arcs, s, a, g, cache, placed, bounds, 0.0, rng, nothing)
        p.ctl[C_SERVED] += 1
        # published only if the caller has not taken the slot back meanwhile
        claimed = word - POSTED + PARTNER
        tag = FREE if code == FOUND else EMPTY
        compare_swap(p.state, base, claimed, claimed - PARTNER + tag)


@numba.njit(cache=True)
def _cancel(p: SurfacePartner, head: int, tail: int) -> None:
    """Cancel the slots ``head .. tail - 1``: posted or held by the partner, at once.

    The partner's analysis in progress goes on, on a packing that may change;
    its answer is dropped (it writes only the partner's own cache).
    """
    for q in range(head, tail):
        sl = q % SLOTS
        while True:
            v = load_acquire(p.state, sl * PAD)
            tag = v & TAG
            if tag != POSTED and tag != PARTNER:
                break
            if compare_swap(p.state, sl * PAD, v, v - tag + CANCELLED):
                break


@numba.njit(cache=True, nogil=True)
def scan_shared(
    candidates: IntArray,
    begin: int,
    i: int,
    screen: Screening,
    q_arcs: EdgeArcs,
    s: Solids,
    a: Arcs,
    g: Grid,
    cache: HalfspaceCache,
    placed: Placed,
    bounds: Bounds,
    rng: KernelSource,
    out: FloatArray,
    tree: FloatArray,
    p: SurfacePartner,
) -> tuple[int, int]:
    """:func:`.analysis.scan` of a polyhedron without a margin, with the partner (same result).

    Returns ``(code, position)`` as :func:`.analysis.scan` does. It releases
    Python's lock: a partner thread that ends (its wrapper marks it dead) is
    seen while the scan waits for it.
    """
    t, radius, rmin, tried, counters, _, _ = screen
    r = radius[i]
    leaves = tree.shape[0] // 2
    defer = p.ctl[C_DEFER] != 0
    p.fpar[F_REACH] = placed.reach_max
    for ax in range(3):
        p.fpar[F_ADM + ax] = bounds.adm_lo[ax]
        p.fpar[F_ADM + 3 + ax] = bounds.adm_hi[ax]
    waits = 0  # polls in a row that found nothing to do
    nxt = next_screened(candidates, begin, r, t, rmin, tree, leaves)
    head = 0  # the next posted slot to read (in the scan's order)
    tail = 0  # slots posted
    found = -1  # the first slot known to have a free surface
    while True:
        if found >= 0 and found < head:
            found = -1  # read (and screened out) in the order: post on
        for q in range(head + 1, tail):  # a free surface found ahead: post nothing beyond
            if found >= 0:
                break
            if load_acquire(p.state, (q % SLOTS) * PAD) & TAG == FREE:
                found = q
        while found < 0 and nxt >= 0 and tail - head < SLOTS:
            sl = tail % SLOTS
            base = sl * PAD
            p.k[sl] = nxt
            pid = p.ctl[C_ID] + 1
            p.ctl[C_ID] = pid
            p.task[base + T_ID] = pid
            p.task[base + T_PK] = candidates[nxt]
            p.task[base + T_I] = i
            store_release(p.state, base, pid * 8 + POSTED)
            tail += 1
            nxt = next_screened(candidates, nxt + 1, r, t, rmin, tree, leaves)
        if head == tail:
            return NOTHING, candidates.shape[0]
        sl = head % SLOTS
        base = sl * PAD
        v = load_acquire(p.state, base)
        if v >> 3 != p.task[base + T_ID]:
            raise AssertionError("partner: a slot holds the state of another post")
        tag = v & TAG
        m = p.k[sl]
        k = candidates[m]
        if not r < t * rmin[k]:
            # listed again after an earlier position found it empty: screened out now, as
            # the plain scan screens it when it comes to it
            _cancel(p, head, head + 1)
            head += 1
            continue
        if tag == POSTED and not defer:
            if not compare_swap(p.state, base, v, v - POSTED + CALLER):
                continue  # the partner has just claimed it
            tag = CALLER
        elif tag == PARTNER or tag == POSTED:
            # the partner holds it (or, deferred to, has yet to claim it): take it back when
            # the partner has died, or has held it too long (it has no processor)
            if load_acquire(p.ctl, C_DEAD) != 0 or (waits >= TAKEOVER and not defer):
                if not compare_swap(p.state, base, v, v - tag + CALLER):
                    continue  # it has just changed: read it again
                tag = CALLER
            else:
                waits = _steal(candidates, head, tail, found, i, q_arcs, s, a, g, cache,
                               placed, bounds, rng, out, p, defer, waits)  # fmt: skip
                continue
        waits = 0
        if tag == CALLER or tag == FREE:
            # in the scan's order: the plain scan's own analysis (it draws the centre)
            code = analyse(k, i, q_arcs, s, a, g, cache, placed, bounds, 0.0, rng, out)
            if code == FULL:
                _cancel(p, head, tail)
                return FULL, m
            counters[0] += 1
            if code == NOTHING:
                counters[1] += 1
        elif tag == EMPTY:
            code = NOTHING
            counters[0] += 1
            counters[1] += 1
        else:
            raise AssertionError("partner: the slot the scan reads was cancelled")
        if tried.shape[0] > 0:
            tried[k] = i
        if code == FOUND:
            _cancel(p, head + 1, tail)
            return FOUND, m
        rmin[k] = r
        if leaves > 0:
            tree_set(tree, leaves, m, r)
        head += 1


@numba.njit(cache=True)
def _steal(
    candidates: IntArray,
    head: int,
    tail: int,
    found: int,
    i: int,
    q_arcs: EdgeArcs,
    s: Solids,
    a: Arcs,
    g: Grid,
    cache: HalfspaceCache,
    placed: Placed,
    bounds: Bounds,
    rng: KernelSource,
    out: FloatArray,
    p: SurfacePartner,
    defer: bool,
    waits: int,
) -> int:
    """While the partner holds slot ``head``: analyse a later posted one (no draw).

    Returns 0 after an analysis, ``waits + 1`` after a wait (nothing to take). A slot
    whose analysis finds the cache full stays the caller's: the scan analyses it again
    in its order, and returns :data:`FULL` there.
    """
    for q in range(head + 1, tail):
        if defer or (found >= 0 and q >= found):
            break
        sq = q % SLOTS
        u = load_acquire(p.state, sq * PAD)
        if u & TAG == FREE:
            break
        if u & TAG == POSTED and compare_swap(p.state, sq * PAD, u, u - POSTED + CALLER):
            k = candidates[p.k[sq]]
            nothing = out[:0]  # the answer alone: no centre drawn
            code = analyse(k, i, q_arcs, s, a, g, cache, placed, bounds, 0.0, rng, nothing)
            if code == FULL:
                return 0
            store_release(p.state, sq * PAD, u - POSTED + (FREE if code == FOUND else EMPTY))
            return 0
    _wait(waits + 1)
    return waits + 1


class PartnerThread:
    """A partner for the scans of one :class:`.state.SurfaceState`: shared arrays, thread.

    :meth:`start` before the insertion, :meth:`stop` after it (also after an
    error, and at interpreter exit for a partner still running). The thread is
    a daemon: it never keeps a process alive.
    """

    def __init__(
        self,
        solids: Solids,
        arcs: Arcs,
        grid: Grid,
        cache: HalfspaceCache,
        order: IntArray,
        centre: FloatArray,
        circum: FloatArray,
        period: FloatArray,
        lo: FloatArray,
        hi: FloatArray,
        wall: FloatArray,
    ) -> None:
        self.shared = new_surface_partner()
        self._args = (
            solids, arcs, grid, cache, order, centre, circum, period, lo, hi, wall, self.shared,
            np.zeros(4, dtype=np.uint64),  # a source never drawn from
        )  # fmt: skip
        self._thread: threading.Thread | None = None
        self._failure: list[BaseException] = []

    @property
    def served(self) -> int:
        """Analyses the partner has made (those the scans then dropped included)."""
        return int(self.shared.ctl[C_SERVED])

    def start(self) -> SurfacePartner:
        """Start the thread; return the shared arrays to pass the scans."""
        if self._thread is not None:
            return self.shared
        p = self.shared
        args = self._args
        failures = self._failure

        def run() -> None:
            try:
                serve(*args)
            except BaseException as exc:  # handed to the caller by stop
                failures.append(exc)
            finally:
                p.ctl[C_DEAD] = 1

        # entered first on the calling thread, told to stop at once: it compiles (or loads
        # from the cache) here, so the scans never wait for a partner that compiles
        p.ctl[C_STOP] = 1
        serve(*args)
        p.ctl[C_STOP] = 0
        p.ctl[C_DEAD] = 0
        p.ctl[C_ON] = 1
        thread = threading.Thread(target=run, name="regopack-partner-3d", daemon=True)
        thread.start()
        self._thread = thread
        _RUNNING.add(self)
        return p

    def stop(self) -> BaseException | None:
        """End the thread, if one runs; return the error that ended it, if any."""
        p = self.shared
        thread, self._thread = self._thread, None
        try:
            if thread is not None:
                p.ctl[C_STOP] = 1
                thread.join()
        finally:
            _RUNNING.discard(self)
        p.ctl[C_ON] = 0
        return self._failure.pop() if self._failure else None


_RUNNING: set[PartnerThread] = set()
"""Partners whose thread runs (held until :meth:`PartnerThread.stop`; stopped at exit)."""


def stop_all() -> None:
    """Stop every partner thread still running; called at interpreter exit."""
    for partner in list(_RUNNING):
        partner.stop()


atexit.register(stop_all)
