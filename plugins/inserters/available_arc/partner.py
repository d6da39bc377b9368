"""A partner thread that analyses the screened search's next candidates ahead of it.

The sweep's screened search (:func:`kernel.find_site`) analyses candidates
one after another in insertion order and stops at the first with an
available arc; about 95 % of the analyses find none. With a partner, the
search *posts* its next candidates (up to :data:`SLOTS` ahead, found by the
same screening walk) and a second thread, kept for the insertion, claims and
analyses them while the calling thread analyses the others. The calling
thread reads the results strictly in the search's order, exactly as the
sequential search meets them: an empty candidate is counted and its
screening radius recorded, and the first candidate with arcs takes the
particle with those arcs; the analyses posted after it are dropped.

An analysis reads the packing and writes only scratch space (the envelope
cache, the grid stamps and their counters), so the partner has its own
scratch; its analyses prove no bounds of disks (its copy of the parameters
has them off), so nothing they write reaches the packing. (In a scene of
disks alone the partner makes no analyses: it proves the bounds the search
posts, :func:`serve_bounds`, which only lets the search skip analyses that
would find no arc.) Records of screening radii
are written by the calling thread only, to the screening tree, which the
analyses do not read. The packing is therefore the same, bit for bit, with
a partner or without one, and so are the counts of analyses.

Hand-off: each slot has a state word ``id << 3 | tag`` (``id`` a post
counter, so a stale word never matches). The caller posts with a release
store; either thread claims a posted slot with a compare-and-swap; the
partner publishes its result with a compare-and-swap from its claim, so a
result for a slot the caller has taken back is dropped. The caller never
waits for a slot the partner has not claimed (it claims it itself), and
waits at most :data:`TAKEOVER` polls for one the partner holds: then it
takes the slot back and analyses it itself. A partner without a processor
(another process runs) thus costs parallelism, not a scheduler's time
slice. Before the search returns, and the packing changes, it waits the
same way for the partner's analysis in progress; an analysis it gave up on
may go on reading a packing that changes, but its result is dropped and it
writes only the partner's scratch.
"""

from __future__ import annotations

import atexit
import os
import threading
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.atomics import (
    compare_swap,
    load_acquire,
    sleep_us,
    spin_hint,
    store_release,
    yield_processor,
)
from regopack.plugins.common.borrowed import borrowed
from regopack.plugins.inserters.available_arc import kernel as K
from regopack.plugins.inserters.available_arc.batches import Helpers, new_helpers
from regopack.plugins.inserters.available_arc.bound_queue import prove_next
from regopack.plugins.inserters.available_arc.candidates import tree_set

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SLOTS = 4
"""Candidates posted ahead of the one the search reads."""
PAD = 8
"""``int64`` words per slot and per control word: one cache line each."""
ARC_CAP = 64
"""Arcs a partner's analysis hands back (``Partner.arcs.shape[1]``); a candidate with more
is analysed again by the caller (the same arcs)."""
TAKEOVER = 4000
"""Polls (some 50 to 200 microseconds, ten to forty analyses) the caller waits for a slot
the partner holds before it takes the slot back."""
SPINS = 2000
"""Empty polls (some 20 to 100 microseconds) before an idle partner yields its processor;
after twice as many it sleeps between polls (the caller is busy elsewhere, or compiling).
The caller, waiting for the partner, yields after as many."""
IDLE_SLEEP_US = 50
"""Sleep of a long-idle partner between polls (microseconds)."""
PARKED_SLEEP_US = 200
"""Sleep of a parked partner between polls (microseconds)."""

# slot tags (the low three bits of a state word)
POSTED, PARTNER, CALLER, EMPTY, ARCS, SHUT, CANCELLED = 1, 2, 3, 4, 5, 6, 7
TAG = 7

# control words (times PAD); C_DEFER: the caller leaves every posted slot to the partner
# (a test of the partner's path: then it analyses every candidate that is not shut);
# C_CUT: the partner drops an analysis of a post id up to this one between two envelope
# edges (the caller has found the particle's place before it and will not read it)
C_ON, C_STOP, C_PARK, C_DEAD, C_ID, C_SERVED, C_DEFER, C_CUT = (PAD * j for j in range(8))
N_CTL = 8 * PAD

# task words within a slot's block; T_ID: the post id (the caller's own)
T_PK, T_I, T_MQ, T_NARCS, T_ID = 0, 1, 2, 3, 4


class Partner(NamedTuple):
    """What the search and its partner thread share."""

    ctl: IntArray
    """Control words (``C_*``): whether a partner serves, stop, park, dead, counters."""
    state: IntArray
    """``state[slot * PAD]``: the slot's state word."""
    task: IntArray
    """``task[slot * PAD + T_*]``: the posted analysis and the number of arcs it found."""
    k: IntArray
    """``k[slot]``: the posted candidate's insertion index (the caller's own)."""
    arcs: FloatArray
    """``(SLOTS, ARC_CAP, 2)``: the arcs of the partner's analyses."""


def new_partner() -> Partner:
    """Shared arrays for a search and its partner; none serves yet."""
    return Partner(
        ctl=np.zeros(N_CTL, dtype=np.int64),
        state=np.zeros(SLOTS * PAD, dtype=np.int64),
        task=np.zeros(SLOTS * PAD, dtype=np.int64),
        k=np.zeros(SLOTS, dtype=np.int64),
        arcs=np.zeros((SLOTS, ARC_CAP, 2)),
    )


def available() -> bool:
    """Whether a partner thread can run here (POSIX: it sleeps and yields through libc)."""
    return os.name == "posix"


_RUNNING: set[PartnerThread] = set()
"""Partners whose thread runs (held until :meth:`PartnerThread.stop`; stopped at exit)."""


def stop_all() -> None:
    """Stop every partner thread still running; called at interpreter exit.

    A partner is a daemon thread, so it never keeps a process alive, but a
    compiled loop that goes on through the interpreter's shutdown would read
    arrays being freed; stopping it first lets the process end cleanly.
    """
    for partner in list(_RUNNING):
        partner.stop()


atexit.register(stop_all)


class PartnerThread:
    """A partner for the searches of one insertion: its shared arrays, scratch and thread.

    :meth:`attach` before each chunk of the sweep starts the thread, or keeps the
    running one when the packing's arrays are the same objects as before (the
    neighbour-list pool is replaced when it grows: the thread then restarts with
    the new arrays); :meth:`stop` when the insertion ends, also after an error,
    and at interpreter exit for any partner still running (:func:`stop_all`).
    """

    def __init__(self, work: K.Work, packed: K.Packed, bounds: bool = False) -> None:
        self.shared = new_partner()
        self.bounds = bounds
        """Whether the partner proves the bounds the caller posts (see
        :mod:`~regopack.plugins.inserters.available_arc.bound_queue`) instead of analysing
        candidates ahead of the search; it then needs only the bounds' scratch."""
        self.helpers = None if bounds else new_helpers(work, packed, 1)
        if self.helpers is not None:
            # the partner's analyses prove no bounds of disks: they would go to its own row,
            # and one proved by an analysis the caller gave up on could rest on a changing
            # packing
            self.helpers.ipar[0, K.I_BOUND] = K.BOUND_OFF
        self.scratch = np.empty((K.SCRATCH_ROWS, K.SCRATCH_WIDTH) if bounds else (1, 1))
        self._thread: threading.Thread | None = None
        self._arrays: tuple[K.Outlines, K.Packed] | None = None
        self._failure: list[BaseException] = []

    @property
    def served(self) -> int:
        """Analyses the partner has made (those the search then dropped included)."""
        return int(self.shared.ctl[C_SERVED])

    def attach(self, g: K.Outlines, s: K.Packed, rounded: object) -> Partner:
        """Have a thread serve the searches of ``s``; return the shared arrays to pass them."""
        if self._thread is not None and self._arrays is not None:
            if self._arrays[0] is g and self._arrays[1] is s and self._thread.is_alive():
                return self.shared
        failure = self.stop()
        if failure is not None:
            raise failure
        p = self.shared
        h = self.helpers
        scratch = self.scratch
        failures = self._failure

        def run() -> None:
            try:
                if h is None:
                    serve_bounds(s, scratch, p)
                else:
                    serve(g, s, h, p, rounded)
            except BaseException as exc:  # handed to the caller by stop
                failures.append(exc)
            finally:
                p.ctl[C_DEAD] = 1

        # the loop entered here first, told to stop at once: it compiles (or loads from the
        # cache) on the calling thread, so the search never runs alone while its partner
        # compiles, and a run's compile time is its own thread's
        p.ctl[C_STOP] = 1
        if h is None:
            serve_bounds(s, scratch, p)
        else:
            serve(g, s, h, p, rounded)
        p.ctl[C_STOP] = 0
        p.ctl[C_DEAD] = 0
        p.ctl[C_PARK] = 0
        # the search posts its candidates only to a partner that analyses them
        p.ctl[C_ON] = 0 if self.bounds else 1
        self._arrays = (g, s)
        thread = threading.Thread(target=run, name="regopack-partner", daemon=True)
        thread.start()
        self._thread = thread
        _RUNNING.add(self)
        if self.bounds and s.ipar[K.I_BOUND] != K.BOUND_OFF:
            s.ipar[K.I_BOUND] = K.BOUND_POST
        return p

    def stop(self) -> BaseException | None:
        """End the thread, if one runs; return the error that ended it, if any."""
        p = self.shared
        if self._arrays is not None and self._arrays[1].ipar[K.I_BOUND] == K.BOUND_POST:
            self._arrays[1].ipar[K.I_BOUND] = K.BOUND_PROVE  # no one left to prove them
        thread, self._thread = self._thread, None
        try:
            if thread is not None:
                p.ctl[C_STOP] = 1
                thread.join()
        finally:
            _RUNNING.discard(self)
        self._arrays = None
        p.ctl[C_ON] = 0
        return self._failure.pop() if self._failure else None


@numba.njit(cache=True, inline="always")
def _idle(ctl: IntArray, polls: int) -> None:
    """Wait after ``polls`` empty polls in a row.

    Sleep when parked; else spin, then yield, then sleep (the caller is busy
    elsewhere, or compiling).
    """
    if load_acquire(ctl, C_PARK) != 0:
        sleep_us(PARKED_SLEEP_US)
    elif polls < SPINS:
        spin_hint()
    elif polls < 2 * SPINS:
        yield_processor()
    else:
        sleep_us(IDLE_SLEEP_US)


@numba.njit(cache=True, inline="always")
def claim(state: IntArray, slots: int) -> tuple[int, int]:
    """Claim the oldest of ``slots`` posted slots for the partner: ``(slot, its word)``.

    ``(-1, 0)`` when none is posted, or when the caller claimed it first.
    """
    best = -1
    word = 0
    for sl in range(slots):
        v = load_acquire(state, sl * PAD)
        if v & TAG == POSTED and (best < 0 or v < word):
            best = sl
            word = v
    if best < 0 or not compare_swap(state, best * PAD, word, word - POSTED + PARTNER):
        return -1, 0
    return best, word


@numba.njit(cache=True, nogil=True)
def serve(g: K.Outlines, s: K.Packed, h: Helpers, p: Partner, rounded: object) -> None:
    """Claim posted slots and analyse them until asked to stop (the partner's loop)."""
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    g, s, h, p = borrowed(g), borrowed(s), borrowed(h), borrowed(p)
    w = K.Work(
        h.rx[0], h.ry[0], h.rex[0], h.rey[0], h.rang[0],
        h.wx[0], h.wy[0], h.wex[0], h.wey[0], h.va[0],
        h.ckey[0], h.cslot[0],
        h.cache_x[0], h.cache_y[0], h.cache_ex[0], h.cache_ey[0],
        h.cache_n[0], h.cache_rad[0], h.woff[0], h.found[0], h.found_q[0], h.fs[0],
    )  # fmt: skip
    own = K.Packed(
        s.cx, s.cy, s.order, s.tree, s.head, s.nxt, s.item, h.stamp[0],
        s.fpar, h.ipar[0], s.walls,
        s.nb_o, s.nb_gap, s.nb_dx, s.nb_dy, s.nb_n, s.nb_reach, s.nb_row, s.nb_free,
        s.nb_img, h.shut[0], s.bq, s.bqf, s.home, s.hnext, s.hhead,
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
        if h.last[0] != i:
            K.begin_particle(i, g, own, w)
            h.last[0] = i
        pk = p.task[base + T_PK]
        mq = p.task[base + T_MQ]
        if rounded is None:
            # the index as a plain integer: the specialisation the tests compile too
            cut = (p.ctl, int(np.int64(C_CUT)), word >> 3)
            arcs = K.analyze_candidate(pk, i, mq, g, own, w, rounded, cut)
        else:  # rounded envelopes are analysed before the edge loop that reads a cut
            arcs = K.analyze_candidate(pk, i, mq, g, own, w, rounded)
        na = arcs.shape[0]
        if na <= p.arcs.shape[1]:
            for a in range(na):
                p.arcs[best, a, 0] = arcs[a, 0]
                p.arcs[best, a, 1] = arcs[a, 1]
        p.task[base + T_NARCS] = na
        p.ctl[C_SERVED] += 1
        # published only if the caller has not taken the slot back meanwhile
        claimed = word - POSTED + PARTNER
        compare_swap(p.state, base, claimed, claimed - PARTNER + (ARCS if na > 0 else EMPTY))


@numba.njit(cache=True, nogil=True)
def serve_bounds(s: K.Packed, scratch: FloatArray, p: Partner) -> None:
    """Prove the disk bounds the caller posts until asked to stop (disks alone).

    See :mod:`~regopack.plugins.inserters.available_arc.bound_queue`. It proves them while
    parked too: the exact scans, which park it, skip the candidates that bounds
    shut, and the ring holds a few hundred at most.
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    s, p = borrowed(s), borrowed(p)
    r_floor = s.fpar[K.F_RMIN]
    idle = 0
    while load_acquire(p.ctl, C_STOP) == 0:
        if prove_next(s.bq, s.bqf, s.shut, r_floor, scratch):
            idle = 0
            continue
        idle += 1
        _idle(p.ctl, idle)


@numba.njit(cache=True, inline="always")
def _wait(polls: int) -> None:
    """Wait for the partner: spin briefly, then give the processor away.

    The partner may be waiting for a processor, when another process runs.
    """
    if polls < SPINS:
        spin_hint()
    else:
        yield_processor()


@numba.njit(cache=True)
def _settle(p: Partner, head: int, tail: int) -> None:
    """Cancel the slots ``head .. tail - 1``.

    Posted ones at once; the partner's when it has left its analysis (cut
    short at the next envelope edge in a scene of sharp polygons), or after
    :data:`TAKEOVER` polls (its result is then dropped).
    """
    if tail > head:  # the posts' ids grow: the last one's cuts them all
        store_release(p.ctl, C_CUT, p.task[((tail - 1) % SLOTS) * PAD + T_ID])
    for q in range(head, tail):
        sl = q % SLOTS
        polls = 0
        while True:
            v = load_acquire(p.state, sl * PAD)
            tag = v & TAG
            if tag == POSTED:
                if compare_swap(p.state, sl * PAD, v, v - POSTED + CANCELLED):
                    break
            elif tag == PARTNER:
                polls += 1
                if polls >= TAKEOVER or load_acquire(p.ctl, C_DEAD) != 0:
                    if compare_swap(p.state, sl * PAD, v, v - PARTNER + CANCELLED):
                        break
                else:
                    spin_hint()
            else:
                break


@numba.njit(cache=True)
def _arcs_of(p: Partner, sl: int) -> FloatArray:
    """Return the arcs the partner found in slot ``sl`` (it found few enough to hand back)."""
    na = p.task[sl * PAD + T_NARCS]
    out = np.empty((na, 2))
    for a in range(na):
        out[a, 0] = p.arcs[sl, a, 0]
        out[a, 1] = p.arcs[sl, a, 1]
    return out


@numba.njit(cache=True)
def find_site_shared(
    i: int,
    start: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rounded: object,
    p: Partner,
) -> tuple[int, FloatArray]:
    """:func:`kernel.find_site` with the partner analysing candidates ahead (same result)."""
    if p.ctl[C_ON] == 0:
        return K.find_site(i, start, mq, g, s, w, rounded)
    empty = np.empty((0, 2))
    r = g.req[i]
    t = s.fpar[K.F_T]
    ipar = s.ipar
    leaves = ipar[K.I_LEAVES]
    count = ipar[K.I_COUNT]
    linear = ipar[K.I_LINEAR] == 1
    defer = p.ctl[C_DEFER] != 0
    waits = 0  # polls in a row that found nothing to do
    c = K.screen(s)
    nxt = K.next_candidate(c, start, count, r, t, linear)
    head = 0  # the next position of the search to read
    tail = 0  # positions posted
    found = -1  # the first position known to have arcs
    kept = -1  # the position whose arcs the caller found (in `keep`)
    keep = empty
    while True:
        while found < 0 and nxt >= 0 and tail - head < SLOTS:
            sl = tail % SLOTS
            base = sl * PAD
            pk = s.order[nxt]
            p.k[sl] = nxt
            pid = p.ctl[C_ID] + 1
            p.ctl[C_ID] = pid
            p.task[base + T_ID] = pid
            if K.shut_for(i, pk, g.rho, s.shut, rounded):
                store_release(p.state, base, pid * 8 + SHUT)
            else:
                p.task[base + T_PK] = pk
                p.task[base + T_I] = i
                p.task[base + T_MQ] = mq
                store_release(p.state, base, pid * 8 + POSTED)
            tail += 1
            nxt = K.next_candidate(c, nxt + 1, count, r, t, linear)
        if head == tail:
            return -1, empty
        sl = head % SLOTS
        v = load_acquire(p.state, sl * PAD)
        if v >> 3 != p.task[sl * PAD + T_ID]:
            raise AssertionError("partner: a slot holds the state of another post")
        tag = v & TAG
        mine = False  # the caller analyses the next position itself
        if tag == POSTED and not defer:
            mine = compare_swap(p.state, sl * PAD, v, v - POSTED + CALLER)
            if not mine:
                continue  # the partner has just claimed it
        elif tag == PARTNER or tag == POSTED:
            # the partner holds it (or, deferred to, has yet to claim it): take it back when
            # the partner has died, or has held it too long (it has no processor)
            if load_acquire(p.ctl, C_DEAD) != 0 or (waits >= TAKEOVER and not defer):
                mine = compare_swap(p.state, sl * PAD, v, v - tag + CALLER)
                if not mine:
                    continue  # it has just changed: read it again
        if mine:
            waits = 0
            arcs = K.analyze_candidate(s.order[p.k[sl]], i, mq, g, s, w, rounded)
            if arcs.shape[0] > 0:
                keep = arcs
                kept = head
                tag = ARCS
            else:
                tag = EMPTY
            v = v - (v & TAG) + tag
            store_release(p.state, sl * PAD, v)
        elif tag == PARTNER or tag == POSTED:
            # the partner holds the next position: analyse a later one meanwhile
            stole = False
            for q in range(head + 1, tail):
                if defer or (found >= 0 and q >= found):
                    break
                sq = q % SLOTS
                u = load_acquire(p.state, sq * PAD)
                if u & TAG == ARCS:
                    found = q
                    break
                if u & TAG == POSTED and compare_swap(p.state, sq * PAD, u, u - POSTED + CALLER):
                    arcs = K.analyze_candidate(s.order[p.k[sq]], i, mq, g, s, w, rounded)
                    if arcs.shape[0] > 0:
                        keep = arcs
                        kept = q
                        found = q
                        store_release(p.state, sq * PAD, u - POSTED + ARCS)
                    else:
                        store_release(p.state, sq * PAD, u - POSTED + EMPTY)
                    stole = True
                    break
            if stole:
                waits = 0
            else:
                waits += 1
                _wait(waits)
            continue
        # the next position is read: in the search's order, as find_site
        waits = 0
        ipar[K.I_ANALYSES] += 1
        k = p.k[sl]
        if tag == ARCS:
            if kept == head:
                arcs = keep
            elif p.task[sl * PAD + T_NARCS] <= p.arcs.shape[1]:
                arcs = _arcs_of(p, sl)
            else:
                arcs = K.analyze_candidate(s.order[k], i, mq, g, s, w, rounded)
            _settle(p, head + 1, tail)
            return k, arcs
        ipar[K.I_EMPTY] += 1
        tree_set(s.tree, leaves, k, r)
        head += 1


@numba.njit(cache=True)
def place_screened_shared(
    i: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    rounded: object,
    p: Partner,
) -> int:
    """:func:`kernel.place_screened` with the partner analysing ahead (same result)."""
    start = int(np.int64(0))
    while True:
        k, arcs = find_site_shared(i, start, mq, g, s, w, rounded, p)
        if k < 0:
            return -1
        placed = K.place_on_arcs(k, arcs, i, mq, g, s, w, rng, rounded)
        if placed >= 0:
            return placed
        start = k + 1


@numba.njit(cache=True, nogil=True)
def pack_range_shared(
    begin: int,
    end: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    rounded: object,
    p: Partner,
) -> int:
    """:func:`kernel.pack_range` (the paper's order) with the partner analysing ahead.

    The same particles in the same order through the same calls; the search
    of each is :func:`find_site_shared`, so the packing is the same bit for bit.
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    g, s, w, p = borrowed(g), borrowed(s), borrowed(w), borrowed(p)
    placed = 0
    for i in range(begin, end):
        if s.ipar[K.I_COUNT] == 0:
            if K.place_first(i, g, s, rng):
                placed += 1
            continue
        mq = K.begin_particle(i, g, s, w)
        if place_screened_shared(i, mq, g, s, w, rng, rounded, p) >= 0:
            placed += 1
    return placed
