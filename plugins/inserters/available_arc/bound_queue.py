"""A queue of disk bounds for the partner thread to prove, off the search's path.

A disk bound (:mod:`~regopack.plugins.inserters.available_arc.disk_bound`) rests only
on the interferers of the analysis that found no arc: their offsets and
radii. The calling thread copies them into a slot of this ring and goes on;
the partner thread (:func:`~regopack.plugins.inserters.available_arc.partner.serve`)
proves the bound from the copy and lowers the candidate's ``shut`` radius.
The bound is the same number as one proved at once, only later: until it
arrives, the analyses it would skip are made, and they find no arc. Skipping
an analysis never changes the packing, nor the counts of analyses (a skipped
one is counted as made), so the packing and the counts are the same whenever
the bounds arrive, or if they never do.

The caller proves a bound itself when the ring is full (the partner is
behind, or has no processor) or when the analysis had more than
:data:`WIDTH` interferers.

Ring: ``ctl[TAIL]`` counts the slots posted (written by the caller, release),
``ctl[HEAD]`` those proved (written by the partner, release); slot
``n % SLOTS`` of ``rows`` holds the ``n``-th post: candidate, interferer
count, the two radii, then the offsets and radii of the interferers.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.atomics import load_acquire, store_release
from regopack.plugins.inserters.available_arc.disk_bound import disk_bound

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

SLOTS = 256
"""Bounds waiting at most; the caller proves the next one itself when all are taken."""
WIDTH = 64
"""Most interferers a posted bound rests on."""
PAD = 8
"""``int64`` words between the two counters: one cache line each."""
TAIL, HEAD = 0, PAD
N_CTL = 2 * PAD
# columns of a slot
R_PK, R_NF, R_RK, R_FAIL, R_DATA = 0, 1, 2, 3, 4
ROW = R_DATA + 3 * WIDTH


def new_queue(enabled: bool) -> tuple[IntArray, FloatArray]:
    """Counters and slots of an empty ring (a single slot when no bounds are proved)."""
    return np.zeros(N_CTL, dtype=np.int64), np.zeros((SLOTS if enabled else 1, ROW))


@numba.njit(cache=True)
def post_bound(
    ctl: IntArray,
    rows: FloatArray,
    pk: int,
    rk: float,
    r_fail: float,
    nf: int,
    ocx: FloatArray,
    ocy: FloatArray,
    orad: FloatArray,
) -> bool:
    """Copy the data of ``pk``'s bound into the next free slot; False when none is free."""
    if nf > WIDTH or rows.shape[0] < SLOTS:
        return False
    tail = ctl[TAIL]
    if tail - load_acquire(ctl, HEAD) >= SLOTS:
        return False
    row = rows[tail % SLOTS]
    row[R_PK] = pk
    row[R_NF] = nf
    row[R_RK] = rk
    row[R_FAIL] = r_fail
    for f in range(nf):
        row[R_DATA + f] = ocx[f]
        row[R_DATA + WIDTH + f] = ocy[f]
        row[R_DATA + 2 * WIDTH + f] = orad[f]
    store_release(ctl, TAIL, tail + 1)
    return True


@numba.njit(cache=True)
def prove_next(
    ctl: IntArray, rows: FloatArray, shut: FloatArray, r_floor: float, scratch: FloatArray
) -> bool:
    """Prove the oldest posted bound into ``shut``; False when none waits (the partner's side)."""
    head = ctl[HEAD]
    if head >= load_acquire(ctl, TAIL):
        return False
    row = rows[head % SLOTS]
    pk = int(row[R_PK])
    nf = int(row[R_NF])
    bound = disk_bound(
        row[R_RK], row[R_FAIL], r_floor, nf,
        row[R_DATA : R_DATA + nf],
        row[R_DATA + WIDTH : R_DATA + WIDTH + nf],
        row[R_DATA + 2 * WIDTH : R_DATA + 2 * WIDTH + nf],
        scratch,
    )  # fmt: skip
    # the caller may lower it meanwhile (a bound of its own): each value is proved, so
    # the one that stays is a bound too
    if bound < shut[pk]:
        shut[pk] = bound
    store_release(ctl, HEAD, head + 1)
    return True
