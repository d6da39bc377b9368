"""Compiled loop of the sweep order: available-arc insertion inside a rising zone.

The packing grows from the bottom of the domain upward. Candidates are binned
by the height of their centre (``ZONE_BINS`` bins per zone height). Only the
candidates of the *zone*, the bins ``lo..hi``, take part in the candidate
search; bins above it are *frozen* (not yet reachable) and bins below it
*retired* (left behind). Inside the zone the search is the paper's: the first
candidate in insertion order that passes the screening and has available arcs
takes the particle, on the free part of its envelope, with the eta control.

A particle that no zone candidate accepts raises the zone by one bin (its
frozen candidates join, the lowest bin retires once the zone is full height)
and is offered again. Every particle is thus placed near the front, where the
stream of particles happens to be: each height band receives the requested
mixture, and no old pore keeps collecting the small particles.

When the zone's top passes the domain's top, the packing is closing. A
particle that the screened search refuses is then analysed exactly, without
screening, at every candidate that is not retired; when none has an arc it
is *refused* (a certificate within the zone). The lowest bin retires after
every ``pace`` particles offered, ``pace`` being the mean number of particles
offered per rise of the zone before, so the last zone is fed as long as every
zone before it (the *paced* closing); in the *prompt* closing each refusal
retires the lowest bin instead, as the rise it would have caused. When the
zone has retired entirely, the remaining particles are *not offered*. In the
*tail* closing the first refusal under the top ends the run at once: every
particle offered before it was placed, the rest are not offered. The refusal
of the particle whose rises took the zone to the top does not end it.

The scalar state lives in ``zs`` (see the ``Z_*`` indices) so that the loop
can run in chunks between progress reports.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.available_arc import kernel as K
from regopack.plugins.available_arc.candidates import tree_set
from regopack.plugins.available_arc.refusal import place_screened, try_candidate
from regopack.plugins.walls import WALL_BOX, WALL_PERIODIC, point_fits

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

ZONE_BINS = 80
"""Bins per zone height: the zone rises by ``zone / ZONE_BINS`` at a time."""
MAX_BINS = 1 << 20
"""Most bins over the domain's height (a zone under ``height * ZONE_BINS / MAX_BINS``
has fewer than ``ZONE_BINS`` bins)."""

# zs: integer state of the sweep
(
    Z_LO,
    Z_HI,
    Z_FULL,
    Z_DONE,
    Z_RAISES,
    Z_REFUSED,
    Z_NZONE,
    Z_STARTED,
    Z_OFFERED,
    Z_PACE,
    Z_SINCE,
    Z_PROMPT,
) = range(12)
N_ZS = 12

# per-candidate zone flag
FROZEN, ACTIVE, RETIRED = 0, 1, 2


class Sweep:
    """Arrays of one sweep run: bins, flags and the stored screening radii."""

    def __init__(self, n: int, height: float, zone: float, closing: str = "paced") -> None:
        # bins of zone / ZONE_BINS, but at least ZONE_BINS of them over the domain's
        # height (a zone taller than the domain) and at most MAX_BINS (a tiny zone)
        self.delta = max(min(zone, height) / ZONE_BINS, height / MAX_BINS)
        if not self.delta > 0:
            self.delta = 1.0
        nbins = max(1, math.ceil(height / self.delta)) + 1
        self.bin_head = np.full(nbins, -1, dtype=np.int64)
        self.bin_next = np.full(max(n, 1), -1, dtype=np.int64)
        self.flag = np.full(max(n, 1), FROZEN, dtype=np.int64)
        self.status = np.zeros(max(n, 1), dtype=np.int64)
        self.zs = np.zeros(N_ZS, dtype=np.int64)
        self.zs[Z_NZONE] = max(1, round(zone / self.delta))
        self.zs[Z_PROMPT] = CLOSINGS[closing]


CLOSINGS: dict[str, int] = {"paced": 0, "prompt": 1, "tail": 2}
"""Code of each closing in ``zs[Z_PROMPT]``."""

STATUS_NOT_OFFERED, STATUS_PLACED, STATUS_REFUSED = 0, 1, 2
"""Values of ``Sweep.status`` per particle."""


@numba.njit(cache=True)
def _bin_of(y: float, y0: float, delta: float, nbins: int) -> int:
    b = math.floor((y - y0) / delta)
    if b < 0:
        return 0
    if b >= nbins:
        return nbins - 1
    return b


@numba.njit(cache=True)
def _lowest_centre(i: int, g: K.Outlines, s: K.Packed) -> tuple[bool, float, float]:
    """Lowest feasible centre of particle ``i`` on the vertical through the domain centre.

    In a walled or periodic rectangle it is the bottom of the particle's box of
    centres; in a polygon or circle a bisection between a centre that fits
    and the bottom of the domain's box (the feasible centres of a convex
    particle in a convex container form a convex set, so the vertical meets it
    in one interval).
    """
    fpar = s.fpar
    mode = s.ipar[K.I_WALLMODE]
    if mode == WALL_BOX or mode == WALL_PERIODIC:
        x0, x1, y0, y1 = K.centre_box(i, g, fpar)
        if mode == WALL_PERIODIC:
            return True, 0.5 * (fpar[K.F_XMIN] + fpar[K.F_XMAX]), fpar[K.F_YMIN]
        if x0 > x1 or y0 > y1:
            return False, 0.0, 0.0
        x = min(max(0.5 * (fpar[K.F_XMIN] + fpar[K.F_XMAX]), x0), x1)
        return True, x, y0
    a = g.offsets[i]
    b = g.offsets[i + 1]
    x = fpar[K.F_CX]
    y = fpar[K.F_CY]
    rho = g.rho[i]
    if not point_fits(x, y, g.vx, g.vy, a, b, mode, s.walls, rho):
        ok, x, y = K._inner_centre(i, g, s)
        if not ok:
            return False, 0.0, 0.0
    lo = fpar[K.F_YMIN] - g.box[i, 2]  # below this the particle leaves the domain's box
    hi = y
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if point_fits(x, mid, g.vx, g.vy, a, b, mode, s.walls, rho):
            hi = mid
        else:
            lo = mid
    return True, x, hi


@numba.njit(cache=True)
def _exhaustive(
    i: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    rounded: object,
    lo: int,
    bin_head: IntArray,
    bin_next: IntArray,
    flag: IntArray,
) -> int:
    """Exact analysis, without screening, at every candidate of bins ``lo`` and above."""
    for b in range(lo, bin_head.shape[0]):
        e = bin_head[b]
        while e >= 0:
            k = e
            e = bin_next[e]
            if flag[k] != RETIRED and try_candidate(k, i, mq, g, s, w, rng, rounded):
                return s.ipar[K.I_COUNT] - 1
    return -1


@numba.njit(cache=True)
def _retire_bin(
    b: int, s: K.Packed, bin_head: IntArray, bin_next: IntArray, flag: IntArray
) -> None:
    leaves = s.ipar[K.I_LEAVES]
    e = bin_head[b]
    while e >= 0:
        if flag[e] != RETIRED:
            flag[e] = RETIRED
            tree_set(s.tree, leaves, e, -np.inf)
        e = bin_next[e]


@numba.njit(cache=True)
def _raise(
    zs: IntArray, s: K.Packed, bin_head: IntArray, bin_next: IntArray, flag: IntArray
) -> bool:
    """Raise the zone by one bin; False when its top is already the domain's top."""
    hi = zs[Z_HI]
    if hi + 1 >= bin_head.shape[0]:
        return False
    hi += 1
    zs[Z_HI] = hi
    zs[Z_RAISES] += 1
    leaves = s.ipar[K.I_LEAVES]
    e = bin_head[hi]
    while e >= 0:
        if flag[e] == FROZEN:
            flag[e] = ACTIVE
            tree_set(s.tree, leaves, e, np.inf)
        e = bin_next[e]
    if hi - zs[Z_LO] + 1 > zs[Z_NZONE]:
        _retire_bin(zs[Z_LO], s, bin_head, bin_next, flag)
        zs[Z_LO] += 1
    return True


@numba.njit(cache=True)
def _roll_back(
    zs: IntArray,
    lo0: int,
    hi0: int,
    full: int,
    raises: int,
    s: K.Packed,
    bin_head: IntArray,
    bin_next: IntArray,
    flag: IntArray,
) -> None:
    """Undo one particle's rises: refreeze the bins above ``hi0``, reopen those from ``lo0``."""
    leaves = s.ipar[K.I_LEAVES]
    for b in range(hi0 + 1, zs[Z_HI] + 1):
        e = bin_head[b]
        while e >= 0:
            if flag[e] == ACTIVE:
                flag[e] = FROZEN
                tree_set(s.tree, leaves, e, -np.inf)
            e = bin_next[e]
    for b in range(lo0, zs[Z_LO]):
        e = bin_head[b]
        while e >= 0:
            flag[e] = ACTIVE
            tree_set(s.tree, leaves, e, np.inf)
            e = bin_next[e]
    zs[Z_LO] = lo0
    zs[Z_HI] = hi0
    zs[Z_FULL] = full
    zs[Z_RAISES] -= raises


@numba.njit(cache=True)
def _register(
    k: int,
    zs: IntArray,
    s: K.Packed,
    delta: float,
    bin_head: IntArray,
    bin_next: IntArray,
    flag: IntArray,
) -> None:
    """File new candidate ``k`` in its bin; it is frozen above the zone, retired below."""
    q = s.order[k]
    b = _bin_of(s.cy[q], s.fpar[K.F_YMIN], delta, bin_head.shape[0])
    bin_next[k] = bin_head[b]
    bin_head[b] = k
    if b > zs[Z_HI] or b < zs[Z_LO]:
        flag[k] = FROZEN if b > zs[Z_HI] else RETIRED
        tree_set(s.tree, s.ipar[K.I_LEAVES], k, -np.inf)
    else:
        flag[k] = ACTIVE


@numba.njit(cache=True)
def sweep_range(
    begin: int,
    end: int,
    delta: float,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    zs: IntArray,
    bin_head: IntArray,
    bin_next: IntArray,
    flag: IntArray,
    status: IntArray,
    rounded: object = None,
) -> int:
    """Offer particles ``begin`` to ``end - 1`` in the sweep order; return how many were placed.

    ``status`` records each particle offered (placed or refused); particles
    after the run has closed keep ``STATUS_NOT_OFFERED``.
    """
    placed = 0
    nbins = bin_head.shape[0]
    for i in range(begin, end):
        if zs[Z_DONE] == 1:
            break
        if zs[Z_STARTED] == 0:
            ok, x, y = _lowest_centre(i, g, s)
            if not ok:
                status[i] = STATUS_REFUSED
                zs[Z_REFUSED] += 1
                continue
            zs[Z_STARTED] = 1
            zs[Z_LO] = 0
            zs[Z_HI] = _bin_of(y, s.fpar[K.F_YMIN], delta, nbins)
            k = K.insert_particle(i, x, y, g, s)
            _register(k, zs, s, delta, bin_head, bin_next, flag)
            status[i] = STATUS_PLACED
            placed += 1
            continue
        if zs[Z_FULL] == 1 and zs[Z_PROMPT] == 0:
            # paced closing: the lowest bin retires after as many offers as a bin took to
            # pass before, so the last zone sees the stream for as long as any other
            zs[Z_SINCE] += 1
            if zs[Z_SINCE] > zs[Z_PACE]:
                zs[Z_SINCE] = 0
                _retire_bin(zs[Z_LO], s, bin_head, bin_next, flag)
                zs[Z_LO] += 1
                if zs[Z_LO] > zs[Z_HI]:
                    zs[Z_DONE] = 1
                    break
        elif zs[Z_FULL] == 0:
            zs[Z_OFFERED] += 1
        mq = K.begin_particle(i, g, s, w)
        was_full = zs[Z_FULL]
        raises = 0
        lo0 = zs[Z_LO]
        hi0 = zs[Z_HI]
        k = -1
        while True:
            k = place_screened(i, mq, g, s, w, rng, rounded)
            if k >= 0:
                break
            if zs[Z_FULL] == 0 and raises < zs[Z_NZONE]:
                if _raise(zs, s, bin_head, bin_next, flag):
                    raises += 1
                    continue
                zs[Z_FULL] = 1
                zs[Z_PACE] = max(1, zs[Z_OFFERED] // max(1, zs[Z_RAISES]))
            if raises > 0:
                # rising did not help: a particle too large for the front must not
                # carry the zone away with it. The bins it retired reopen; the bins it
                # opened freeze again, unless the zone reached the top (the closing)
                keep_hi = zs[Z_HI] if zs[Z_FULL] == 1 else hi0
                _roll_back(zs, lo0, keep_hi, zs[Z_FULL], raises, s, bin_head, bin_next, flag)
            k = _exhaustive(i, mq, g, s, w, rng, rounded, zs[Z_LO], bin_head, bin_next, flag)
            break
        if k < 0:
            status[i] = STATUS_REFUSED
            zs[Z_REFUSED] += 1
            if zs[Z_FULL] == 1 and zs[Z_PROMPT] == 1:
                # prompt closing: the refusal stands for the rise the zone would have made
                _retire_bin(zs[Z_LO], s, bin_head, bin_next, flag)
                zs[Z_LO] += 1
                if zs[Z_LO] > zs[Z_HI]:
                    zs[Z_DONE] = 1
            elif was_full == 1 and zs[Z_PROMPT] == 2:
                # tail closing: the first refusal under the top ends the run, so the
                # particles left out are the rest of the stream, a random tail. The
                # particle whose rises took the zone to the top does not count: it
                # fits nowhere, while the top bins have just opened for the others
                zs[Z_DONE] = 1
            continue
        _register(k, zs, s, delta, bin_head, bin_next, flag)
        status[i] = STATUS_PLACED
        placed += 1
    return placed
