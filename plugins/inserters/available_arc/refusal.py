"""Certified refusals: an exact scan before a particle is recorded as not placed.

The paper's screening skips candidate ``k`` for a particle unless
``r < t * rmin_k``, although another shape of the same size might fit where
an earlier one did not. With ``screening = "exact"`` a particle that the
screened search refuses is analysed once more at every candidate, in
insertion order and without screening; it is placed at the first one with
an available arc left after the eta control, and recorded as not placed only
when there is none. The loop is otherwise :func:`kernel.pack_range`: the same
calls in the same order, so that a run in which no particle is rescued gives
the reference packing.
"""

from __future__ import annotations

import numba
import numpy as np

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack._compat import renamed_names
from regopack.plugins.common.borrowed import borrowed
from regopack.plugins.inserters.available_arc import kernel as K

I_RESCUED = 0
"""Index of the rescued-particle counter in the ``counts`` array."""


@numba.njit(cache=True)
def try_candidate(
    k: int,
    i: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    rounded: object,
) -> bool:
    """Analyse candidate ``k`` exactly for particle ``i`` and place it there if it fits."""
    s.ipar[K.I_ANALYSES] += 1
    pk = s.order[k]
    if K.shut_for(i, pk, g.rho, s.shut, rounded):
        s.ipar[K.I_EMPTY] += 1
        return False
    arcs = K.analyze_candidate(pk, i, mq, g, s, w, rounded)
    if arcs.shape[0] == 0:
        s.ipar[K.I_EMPTY] += 1
        return False
    eta = s.fpar[K.F_ETA]
    if eta != 0.0:
        arcs = K.eta_shrink(arcs, eta, g.req[i], g.req[s.order[k]], rng)
        if arcs.shape[0] == 0:
            return False
    angle = K.sample_angle(arcs, rng.random())
    x, y = K.locate(s.order[k], i, mq, angle, g, s, w, rounded)
    K.insert_particle(i, x, y, g, s)
    return True


@numba.njit(cache=True)
def pack_range_exact(
    begin: int,
    end: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    counts: np.ndarray,
    rounded: object = None,
) -> int:
    """Insert particles ``begin`` to ``end - 1`` as :func:`kernel.pack_range`, with exact refusals.

    ``counts[I_RESCUED]`` counts the particles placed by the exact scan.
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    g, s, w, counts = borrowed(g), borrowed(s), borrowed(w), borrowed(counts)
    placed = 0
    for i in range(begin, end):
        if s.ipar[K.I_COUNT] == 0:
            if K.place_first(i, g, s, rng):
                placed += 1
            continue
        mq = K.begin_particle(i, g, s, w)
        done = K.place_screened(i, mq, g, s, w, rng, rounded) >= 0
        if not done:
            for k in range(s.ipar[K.I_COUNT]):
                if try_candidate(k, i, mq, g, s, w, rng, rounded):
                    counts[I_RESCUED] += 1
                    done = True
                    break
        if done:
            placed += 1
    return placed


__getattr__ = renamed_names(
    __name__,
    {"place_screened": "regopack.plugins.inserters.available_arc.kernel:place_screened"},
)
"""The screened search that moved to the kernel beside the loop that calls it, for one release."""
