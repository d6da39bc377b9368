"""Candidate analyses of the exact scans spread over several threads.

An exact scan (the sweep's certificate before a refusal) analyses every
candidate of a zone, one after another, and stops at the first that takes the
particle; most scans find none. :func:`exact_scan` analyses the candidates a
batch at a time on ``T`` threads and then reads the results in the scan's
order, exactly as the sequential scan meets them: an empty candidate counts
its analysis, a candidate with arcs is tried on the calling thread (its arcs
computed once more, then the eta control and the random angle, in the
sequential order), and the analyses after the one that takes the particle are
dropped.

An analysis on a thread reads the packing and writes only scratch space (the
envelope cache, the grid stamps and their counters), so each thread has its
own scratch, in :class:`Helpers`. The bounds that failed analyses of disks
prove (:mod:`~regopack.plugins.inserters.available_arc.disk_bound`) are read from the
packing and written to each thread's own row, which the calling thread
merges into the packing after the batch. The packing
is therefore the same, bit for bit, on any number of threads, and so are the
counts of analyses.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.inserters.available_arc import kernel as K
from regopack.plugins.inserters.available_arc.refusal import try_candidate

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

MAX_THREADS = 8
"""Most threads the batches use (each holds scratch of 24 bytes per particle)."""
PER_THREAD = 32
"""Candidates per thread in a batch: starting the threads costs about two analyses, and
the candidates after the one that takes the particle are analysed in vain."""


class Helpers(NamedTuple):
    """Per-thread scratch, stacked along the first axis (one row per thread).

    The first fields are those of :class:`kernel.Work`, flat rather than a
    nested ``Work``: numba's parallel loop does not lower a tuple within a tuple.
    """

    rx: FloatArray
    ry: FloatArray
    rex: FloatArray
    rey: FloatArray
    rang: FloatArray
    wx: FloatArray
    wy: FloatArray
    wex: FloatArray
    wey: FloatArray
    va: FloatArray
    ckey: IntArray
    cslot: IntArray
    cache_x: FloatArray
    cache_y: FloatArray
    cache_ex: FloatArray
    cache_ey: FloatArray
    cache_n: IntArray
    cache_rad: FloatArray
    woff: FloatArray
    found: IntArray
    found_q: IntArray
    fs: FloatArray
    ipar: IntArray
    """``(T, N_IPAR)``: each thread's copy of the parameters and its scratch counters."""
    stamp: IntArray
    """``(T, n)``: each thread's grid stamps."""
    last: IntArray
    """``last[t * PAD]``: the particle thread ``t``'s scratch is prepared for (-1: none)."""
    ks: IntArray
    """``(B,)``: the candidates of the current batch."""
    narcs: IntArray
    """``narcs[j * PAD]``: how many arcs the analysis of ``ks[j]`` found."""
    shut: FloatArray
    """``(T, n)``: the disk bounds each thread proved (see ``Packed.shut``), merged into the
    packing's by the calling thread after each batch."""
    before: IntArray
    """``before[j]``: candidates passed over before ``ks[j]`` (shut for the particle by a
    disk bound), counted as empty analyses when the scan reaches ``ks[j]``."""


PAD = 16
"""Elements added to each thread's row of the small scratch arrays (128 bytes), so that
no two threads write to the same cache line."""
PADDED = ("rx", "ry", "rex", "rey", "rang", "wx", "wy", "wex", "wey", "va")
"""Scratch arrays whose length the analysis does not read: their rows can be padded."""


def new_helpers(work: K.Work, packed: K.Packed, threads: int) -> Helpers:
    """Scratch for ``threads`` threads, shaped like ``work`` and ``packed``'s scratch.

    ``threads = 0`` gives helpers of no threads (every array empty along its first axis): a
    run on one thread passes them where it would pass none, so that one compiled variant
    of a loop serves both.
    """
    t = max(0, threads)

    def stack(a: NDArray[Any], pad: int = 0) -> NDArray[Any]:
        out = np.zeros((t, a.shape[0] + pad, *a.shape[1:]), dtype=a.dtype)
        out[:, : a.shape[0]] = a
        return out

    fields = {
        name: stack(getattr(work, name), PAD if name in PADDED else 0) for name in K.Work._fields
    }
    fields["ckey"][:] = -1
    bounds = packed.ipar[K.I_BOUND] != K.BOUND_OFF
    ipar = stack(packed.ipar, PAD)
    if bounds:  # a helper proves its bounds into its own row (the ring is the caller's)
        ipar[:, K.I_BOUND] = K.BOUND_PROVE
    return Helpers(
        **fields,
        ipar=ipar,
        stamp=np.zeros((t, packed.stamp.shape[0]), dtype=np.int64),
        last=np.full(t * PAD, -1, dtype=np.int64),
        ks=np.zeros(PER_THREAD * t, dtype=np.int64),
        narcs=np.zeros(PER_THREAD * t * PAD, dtype=np.int64),
        # a thread writes the bounds it proves here, not into the packing it reads
        shut=np.full((t, packed.shut.shape[0] if bounds else 1), np.inf),
        before=np.zeros(PER_THREAD * t + 1, dtype=np.int64),
    )


@numba.njit(parallel=True, cache=True)
def _analyse_batch(
    nb: int, i: int, mq: int, g: K.Outlines, s: K.Packed, h: Helpers, rounded: object
) -> None:
    """Analyse candidates ``h.ks[:nb]`` for particle ``i``, candidate ``j`` on thread ``j % T``."""
    threads = h.ipar.shape[0]
    # the arrays a thread writes are taken out of the tuple first: written
    # through the tuple inside the parallel loop, their values were lost
    last = h.last
    ks = h.ks
    narcs = h.narcs
    shut = h.shut
    for t in numba.prange(threads):
        w = K.Work(
            h.rx[t], h.ry[t], h.rex[t], h.rey[t], h.rang[t],
            h.wx[t], h.wy[t], h.wex[t], h.wey[t], h.va[t],
            h.ckey[t], h.cslot[t],
            h.cache_x[t], h.cache_y[t], h.cache_ex[t], h.cache_ey[t],
            h.cache_n[t], h.cache_rad[t], h.woff[t], h.found[t], h.found_q[t], h.fs[t],
        )  # fmt: skip
        st = K.Packed(
            s.cx, s.cy, s.order, s.tree, s.head, s.nxt, s.item, h.stamp[t],
            s.fpar, h.ipar[t], s.walls,
            s.nb_o, s.nb_gap, s.nb_dx, s.nb_dy, s.nb_n, s.nb_reach, s.nb_row, s.nb_free,
            s.nb_img, shut[t], s.bq, s.bqf, s.home, s.hnext, s.hhead,
        )  # fmt: skip
        if last[t * PAD] != i:
            K.begin_particle(i, g, st, w)
            last[t * PAD] = i
        for j in range(t, nb, threads):
            # the scan batches no candidate a bound already shuts (sweep._exhaustive)
            arcs = K.analyze_candidate(s.order[ks[j]], i, mq, g, st, w, rounded)
            narcs[j * PAD] = arcs.shape[0]


@numba.njit(cache=True)
def try_batch(
    nb: int,
    i: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    h: Helpers,
    rounded: object,
) -> int:
    """Try candidates ``h.ks[:nb]`` in order for particle ``i``, as ``try_candidate`` one by one.

    The ``h.before[j]`` shut candidates passed over before ``ks[j]`` count as
    empty analyses as the scan reaches ``ks[j]``, and ``h.before[nb]`` after
    the last when none takes the particle. Returns the new insertion index,
    or -1 when none takes the particle.
    """
    if nb > 1:
        _analyse_batch(nb, i, mq, g, s, h, rounded)
        if s.ipar[K.I_BOUND] != K.BOUND_OFF:
            # the bounds the threads proved, in the batch's order (any order gives the same)
            threads = h.ipar.shape[0]
            for j in range(nb):
                if h.narcs[j * PAD] == 0:
                    pk = s.order[h.ks[j]]
                    b = h.shut[j % threads, pk]
                    if b < s.shut[pk]:
                        s.shut[pk] = b
    for j in range(nb):
        s.ipar[K.I_ANALYSES] += h.before[j]
        s.ipar[K.I_EMPTY] += h.before[j]
        if nb > 1 and h.narcs[j * PAD] == 0:
            s.ipar[K.I_ANALYSES] += 1
            s.ipar[K.I_EMPTY] += 1
            continue
        if try_candidate(h.ks[j], i, mq, g, s, w, rng, rounded):
            return int(s.ipar[K.I_COUNT]) - 1
    s.ipar[K.I_ANALYSES] += h.before[nb]
    s.ipar[K.I_EMPTY] += h.before[nb]
    return -1
