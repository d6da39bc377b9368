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
import threading
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.limits import MAX_ZONE_BINS as MAX_BINS
from regopack.base.limits import zone_bins
from regopack.plugins.common import strips
from regopack.plugins.common.atomics import store_release
from regopack.plugins.common.borrowed import borrowed
from regopack.plugins.common.walls import WALL_BOX, WALL_PERIODIC, point_fits
from regopack.plugins.inserters.available_arc import kernel as K
from regopack.plugins.inserters.available_arc.batches import Helpers, new_helpers, try_batch
from regopack.plugins.inserters.available_arc.candidates import tree_set
from regopack.plugins.inserters.available_arc.neighbours import release_row
from regopack.plugins.inserters.available_arc.partner import (
    C_PARK,
    Partner,
    PartnerThread,
    new_partner,
    place_screened_shared,
)
from regopack.plugins.inserters.available_arc.refusal import try_candidate

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

ZONE_BINS = 80
"""Bins per zone height: the zone rises by ``zone / ZONE_BINS`` at a time."""
STAY_SHARE = 10
"""The zone top of the strip searched may stand a ``1 / STAY_SHARE`` of a zone (of at
most ``ZONE_BINS`` bins) above the lowest top before particles go to another strip
(``zs[Z_STAY]`` bins): a change of strip hides one zone's candidates and shows
another's, so the strips take turns in runs rather than after every few dozen particles."""


# zs: integer state of the whole sweep
(
    Z_DONE,
    Z_REFUSED,
    Z_STARTED,
    Z_PROMPT,
    Z_NZONE,
    Z_CUR,
    Z_QLEN,
    Z_FLUSH,
    Z_STAY,
) = range(9)
N_ZS = 9

# sz: integer state of each strip
(
    S_LO,
    S_HI,
    S_FULL,
    S_RAISES,
    S_OFFERED,
    S_PACE,
    S_SINCE,
    S_CLOSED,
    S_SEEDED,
    S_FREED,
    S_QBIN,
) = range(11)
N_SZ = 11

# per-candidate zone flag
FROZEN, ACTIVE, RETIRED = 0, 1, 2

MAX_STRIPS = K.STRIP_SLOTS
"""Most strips across the domain."""
MAX_CELLS = 1 << 24
"""Most bins over all strips (strips times bins per strip)."""


def strip_count(width: float, strip: float) -> int:
    """Return how many equal strips of about ``strip`` fit across ``width`` (at least one)."""
    return strips.strip_count(width, strip, MAX_STRIPS)


class Bins(NamedTuple):
    """Candidates filed by strip and bin, with their zone flags."""

    head: IntArray
    """``(strips, bins)``: the last candidate filed in each bin, -1 for none."""
    nxt: IntArray
    """Per candidate: the candidate filed before it in its bin, -1 for none."""
    flag: IntArray
    """Per candidate: ``FROZEN``, ``ACTIVE`` or ``RETIRED``."""


class Lags(NamedTuple):
    """Particles offered after a lag, and the queue of those waiting for it."""

    lag: IntArray
    """Per particle: bins the front rises between its turn in the stream and its
    offer (0: offered at its turn)."""
    top_at: IntArray
    """Per particle: the bin of its strip's zone top when it was placed with the
    zone at full height below the domain's top; -1 otherwise (or not placed)."""
    qhead: IntArray
    """``(strips, bins)``, bins up to a zone height and more above the domain's top:
    the first particle waiting until that strip's zone top reaches that bin, -1 for none."""
    qtail: IntArray
    """``(strips, bins)``: the last particle waiting for it."""
    qnext: IntArray
    """Per particle: the next particle waiting for the same strip and bin, -1 for none."""


class Sweep:
    """Arrays of one sweep run: bins per strip, flags and the stored screening radii.

    ``strip`` is the requested strip width (0: one strip across ``width``); the
    domain's width is cut into ``nstrip`` equal strips of width ``swidth``.
    """

    def __init__(
        self,
        n: int,
        height: float,
        zone: float,
        closing: str = "paced",
        width: float = 0.0,
        strip: float = 0.0,
    ) -> None:
        # bins of zone / ZONE_BINS, but at least ZONE_BINS of them over the domain's
        # height (a zone taller than the domain) and at most MAX_BINS (a tiny zone)
        self.delta = max(min(zone, height) / ZONE_BINS, height / MAX_BINS)
        if not self.delta > 0:
            self.delta = 1.0
        nbins = max(1, math.ceil(height / self.delta)) + 1
        # at most MAX_CELLS bins over all strips
        self.nstrip = max(1, min(strip_count(width, strip), MAX_CELLS // nbins))
        self.swidth = width / self.nstrip if width > 0 else 1.0
        self.bin_head = np.full((self.nstrip, nbins), -1, dtype=np.int64)
        self.bin_next = np.full(max(n, 1), -1, dtype=np.int64)
        self.flag = np.full(max(n, 1), FROZEN, dtype=np.int64)
        self.status = np.zeros(max(n, 1), dtype=np.int64)
        self.zs = np.zeros(N_ZS, dtype=np.int64)
        self.zs[Z_NZONE] = max(1, zone_bins(zone, self.delta, height, ZONE_BINS))
        # a zone taller than the domain has more than ZONE_BINS bins: the band stays a
        # tenth of ZONE_BINS, or a strip would keep the turn up to the top
        self.zs[Z_STAY] = min(int(self.zs[Z_NZONE]), ZONE_BINS) // STAY_SHARE
        self.zs[Z_PROMPT] = CLOSINGS[closing]
        self.zs[Z_CUR] = -1
        self.sz = np.zeros((self.nstrip, N_SZ), dtype=np.int64)
        self.bins = Bins(self.bin_head, self.bin_next, self.flag)
        self.tried = np.full(self.nstrip, -2, dtype=np.int64)  # last particle offered
        self._alone: Partner | None = None  # the shared arrays of a run without a partner
        self._no_helpers: Helpers | None = None  # the helpers of a run on one thread
        # waiting particles by the bin of the front they wait for; a full zone's front
        # rises on for a zone height while its bins retire (see _top)
        nwait = nbins + 2 * int(self.zs[Z_NZONE]) + 1
        self.lags = Lags(
            np.zeros(max(n, 1), dtype=np.int64),
            np.full(max(n, 1), -1, dtype=np.int64),
            np.full((self.nstrip, nwait), -1, dtype=np.int64),
            np.full((self.nstrip, nwait), -1, dtype=np.int64),
            np.full(max(n, 1), -1, dtype=np.int64),
        )

    def set_lags(self, lag: IntArray) -> None:
        """Offer each particle ``lag[i]`` bins of the front's rise after its turn.

        See :func:`sweep_range`; all zeros (the default) offers every particle at its turn.
        """
        self.lags.lag[: lag.shape[0]] = lag

    def run(
        self,
        begin: int,
        end: int,
        g: K.Outlines,
        s: K.Packed,
        w: K.Work,
        rng: np.random.Generator,
        rounded: object = None,
        helpers: Helpers | None = None,
        partner: PartnerThread | None = None,
    ) -> int:
        """Offer particles ``begin`` to ``end - 1``; return how many were placed.

        ``helpers``: per-thread scratch that spreads the exact scans over threads
        (see :mod:`~regopack.plugins.inserters.available_arc.batches`); ``partner``: a thread
        that analyses the screened search's next candidates ahead of it (see
        :mod:`~regopack.plugins.inserters.available_arc.partner`). The packing is the same.
        """
        if helpers is None:
            # a run on one thread: helpers of no threads, one compiled variant of the sweep
            # for both (checked at run time in _exhaustive); empty, so made once
            if self._no_helpers is None:
                self._no_helpers = new_helpers(w, s, 0)
            helpers = self._no_helpers
        if partner is not None:
            shared = partner.attach(g, s, rounded)
        else:
            if self._alone is None:
                self._alone = new_partner()
            shared = self._alone
        return self._sweep(begin, end, g, s, w, rng, rounded, helpers, shared)

    def _sweep(
        self,
        begin: int,
        end: int,
        g: K.Outlines,
        s: K.Packed,
        w: K.Work,
        rng: np.random.Generator,
        rounded: object,
        helpers: Helpers,
        shared: Partner,
    ) -> int:
        # sweep_range releases the GIL (for the partner thread); sweeps run from several
        # Python threads still take turns chunk by chunk, as they did holding it: numba's
        # workqueue threading layer aborts on parallel regions entered concurrently
        with _RUN_LOCK:
            return int(
                sweep_range(
                    begin, end, self.delta, self.swidth, g, s, w, rng, self.zs, self.sz,
                    self.bins, self.status, self.tried, self.lags, rounded, helpers, shared,
                )
            )  # fmt: skip

    @property
    def raises(self) -> int:
        """Rises of the zones, over all strips."""
        return int(self.sz[:, S_RAISES].sum())

    @property
    def waiting(self) -> int:
        """Particles waiting for their lag."""
        return int(self.zs[Z_QLEN])

    @property
    def refused(self) -> int:
        """Particles refused."""
        return int(self.zs[Z_REFUSED])


_RUN_LOCK = threading.Lock()
"""Held while a chunk of a sweep runs (see ``Sweep._sweep``)."""

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
def _strip_of(x: float, x0: float, swidth: float, nstrip: int) -> int:
    if nstrip == 1:
        return 0
    b = math.floor((x - x0) / swidth)
    if b < 0:
        return 0
    if b >= nstrip:
        return nstrip - 1
    return b


@numba.njit(cache=True)
def _exhaustive(
    i: int,
    mq: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    rounded: object,
    st: int,
    lo: int,
    bn: Bins,
    helpers: Helpers,
) -> int:
    """Analyse exactly, unscreened, every candidate of strip ``st`` in bins ``lo`` and up.

    With ``helpers`` of some threads the candidates go a batch at a time to them (see
    :mod:`~regopack.plugins.inserters.available_arc.batches`), with the same result.
    """
    if helpers.ks.shape[0] == 0:
        for b in range(lo, bn.head.shape[1]):
            e = bn.head[st, b]
            while e >= 0:
                k = e
                e = bn.nxt[e]
                if bn.flag[k] != RETIRED and try_candidate(k, i, mq, g, s, w, rng, rounded):
                    return s.ipar[K.I_COUNT] - 1
        return -1
    # candidates a disk bound already shuts for this particle take no place in a batch:
    # they are counted where the scan passes them (see try_batch)
    nb = int(np.int64(0))
    helpers.before[0] = 0
    for b in range(lo, bn.head.shape[1]):
        e = bn.head[st, b]
        while e >= 0:
            k = e
            e = bn.nxt[e]
            if bn.flag[k] != RETIRED:
                if K.shut_for(i, s.order[k], g.rho, s.shut, rounded):
                    helpers.before[nb] += 1
                    continue
                helpers.ks[nb] = k
                nb += 1
                helpers.before[nb] = 0
                if nb == helpers.ks.shape[0]:
                    placed = try_batch(nb, i, mq, g, s, w, rng, helpers, rounded)
                    if placed >= 0:
                        return placed
                    nb = int(np.int64(0))
                    helpers.before[0] = 0
    return try_batch(nb, i, mq, g, s, w, rng, helpers, rounded)


@numba.njit(cache=True)
def _retire_bin(st: int, b: int, s: K.Packed, bn: Bins) -> None:
    leaves = s.ipar[K.I_LEAVES]
    e = bn.head[st, b]
    while e >= 0:
        if bn.flag[e] != RETIRED:
            bn.flag[e] = RETIRED
            tree_set(s.tree, leaves, e, -np.inf)
        e = bn.nxt[e]


@numba.njit(cache=True)
def _retire_lowest(st: int, sz: IntArray, s: K.Packed, bn: Bins) -> bool:
    """Retire the lowest bin of strip ``st``'s full zone; return True when none is left.

    A strip with no bin left is closed.
    """
    _retire_bin(st, sz[st, S_LO], s, bn)
    sz[st, S_LO] += 1
    if sz[st, S_LO] > sz[st, S_HI]:
        sz[st, S_CLOSED] = 1
        return True
    return False


@numba.njit(cache=True)
def _release(st: int, sz: IntArray, s: K.Packed, bn: Bins) -> None:
    """Give back the neighbour-list rows of strip ``st``'s bins below its zone.

    Call between particles: bins below the zone then stay behind for good (only
    a particle's own rises are rolled back), so their candidates are never
    analysed again.
    """
    if s.ipar[K.I_NBLISTS] == 0:
        return
    top = s.ipar[K.I_NBTOP]
    for b in range(sz[st, S_FREED], sz[st, S_LO]):
        e = bn.head[st, b]
        while e >= 0:
            top = release_row(s.order[e], s.nb_row, s.nb_free, top)
            e = bn.nxt[e]
    if sz[st, S_LO] > sz[st, S_FREED]:
        sz[st, S_FREED] = sz[st, S_LO]
    s.ipar[K.I_NBTOP] = top


@numba.njit(cache=True)
def _raise(
    st: int,
    zs: IntArray,
    sz: IntArray,
    s: K.Packed,
    bn: Bins,
) -> bool:
    """Raise strip ``st``'s zone by one bin; False when its top is already the domain's top."""
    hi = sz[st, S_HI]
    if hi + 1 >= bn.head.shape[1]:
        return False
    hi += 1
    sz[st, S_HI] = hi
    sz[st, S_RAISES] += 1
    _thaw(st, hi, hi, bool(np.bool_(True)), s, bn)  # a plain bool: one compilation of _thaw
    if hi - sz[st, S_LO] + 1 > zs[Z_NZONE]:
        _retire_bin(st, sz[st, S_LO], s, bn)
        sz[st, S_LO] += 1
    return True


@numba.njit(cache=True)
def _roll_back(
    st: int,
    sz: IntArray,
    lo0: int,
    hi0: int,
    full: int,
    raises: int,
    s: K.Packed,
    bn: Bins,
) -> None:
    """Undo one particle's rises: refreeze the bins above ``hi0``, reopen those from ``lo0``."""
    leaves = s.ipar[K.I_LEAVES]
    for b in range(hi0 + 1, sz[st, S_HI] + 1):
        e = bn.head[st, b]
        while e >= 0:
            if bn.flag[e] == ACTIVE:
                bn.flag[e] = FROZEN
                tree_set(s.tree, leaves, e, -np.inf)
            e = bn.nxt[e]
    for b in range(lo0, sz[st, S_LO]):
        e = bn.head[st, b]
        while e >= 0:
            bn.flag[e] = ACTIVE
            tree_set(s.tree, leaves, e, np.inf)
            e = bn.nxt[e]
    sz[st, S_LO] = lo0
    sz[st, S_HI] = hi0
    sz[st, S_FULL] = full
    sz[st, S_RAISES] -= raises


@numba.njit(cache=True)
def _hide_zone(st: int, sz: IntArray, s: K.Packed, bn: Bins) -> None:
    """Hide every candidate of strip ``st``'s zone still visible (see ``_switch``)."""
    leaves = s.ipar[K.I_LEAVES]
    for b in range(sz[st, S_LO], sz[st, S_HI] + 1):
        e = bn.head[st, b]
        while e >= 0:
            if bn.flag[e] == ACTIVE and s.tree[leaves + e] > 0.0:
                K.hide_candidate(e, -s.tree[leaves + e], s)
            e = bn.nxt[e]


@numba.njit(cache=True)
def _show(st: int, s: K.Packed, bn: Bins) -> None:
    """Show the search strip ``st``'s hidden candidates again (see ``kernel.next_candidate``).

    A hidden candidate's screening radius is the negated one; those retired while
    hidden stay hidden.
    """
    leaves = s.ipar[K.I_LEAVES]
    e = s.hhead[st]
    while e >= 0:
        if bn.flag[e] == ACTIVE:
            tree_set(s.tree, leaves, e, -s.tree[leaves + e])
        nxt = s.hnext[e]
        s.hnext[e] = K.NOT_LISTED
        e = nxt
    s.hhead[st] = -1


@numba.njit(cache=True)
def _choose(sz: IntArray, tried: IntArray, i: int, cur: int, stay: int) -> int:
    """Return the strip to offer particle ``i`` to next; -1 when no open strip is left.

    The open strip whose zone top is lowest, the first such one, among those
    not yet tried for ``i``; but the strip searched, ``cur``, keeps the turn
    while it is open, not full, not tried for ``i`` and its top stands at most
    ``stay`` bins above that lowest one (``stay = -1``: always the lowest, the
    first such one). Among full strips (whose tops cannot rise) the turn passes
    on after ``cur``, so that they close together.
    """
    nstrip = sz.shape[0]
    best = -1
    for st in range(nstrip):
        if sz[st, S_SEEDED] == 1 and sz[st, S_CLOSED] == 0 and tried[st] != i:
            if best < 0 or sz[st, S_HI] < sz[best, S_HI]:
                best = st
    if (
        best >= 0
        and cur >= 0
        and cur != best
        and tried[cur] != i
        and sz[cur, S_SEEDED] == 1
        and sz[cur, S_CLOSED] == 0
        and sz[cur, S_FULL] == 0
        and sz[cur, S_HI] - sz[best, S_HI] <= stay
    ):
        return cur
    if best >= 0 and nstrip > 1 and sz[best, S_FULL] == 1 and cur >= 0:
        for d in range(1, nstrip + 1):
            st = (cur + d) % nstrip
            if (
                sz[st, S_SEEDED] == 1
                and sz[st, S_CLOSED] == 0
                and tried[st] != i
                and sz[st, S_FULL] == 1
                and sz[st, S_HI] == sz[best, S_HI]
            ):
                return st
    return best


@numba.njit(cache=True)
def _switch(
    st: int,
    zs: IntArray,
    sz: IntArray,
    s: K.Packed,
    bn: Bins,
) -> None:
    """Offer the next particles to strip ``st``: show its hidden candidates, search only it.

    The candidates of the strip searched before are all hidden now. (Hiding them only
    as a search meets them, ``kernel.next_candidate``, measured slower once the strips
    took turns in runs; see docs/benchmarks.md. The search meets the same candidates
    either way.)
    """
    cur = zs[Z_CUR]
    if cur == st:
        return
    if cur >= 0:
        _hide_zone(cur, sz, s, bn)
    _show(st, s, bn)
    zs[Z_CUR] = st
    s.ipar[K.I_STRIP] = st


@numba.njit(cache=True)
def _thaw(st: int, lo: int, hi: int, visible: bool, s: K.Packed, bn: Bins) -> None:
    """Make the frozen candidates of strip ``st``'s bins ``lo..hi`` active (with rmin = inf).

    Not ``visible``: hidden until the strip is searched.
    """
    leaves = s.ipar[K.I_LEAVES]
    for b in range(lo, hi + 1):
        e = bn.head[st, b]
        while e >= 0:
            if bn.flag[e] == FROZEN:
                bn.flag[e] = ACTIVE
                if visible:
                    tree_set(s.tree, leaves, e, np.inf)
                else:
                    K.hide_candidate(e, -np.inf, s)
            e = bn.nxt[e]


@numba.njit(cache=True)
def _register(
    k: int,
    zs: IntArray,
    sz: IntArray,
    s: K.Packed,
    delta: float,
    swidth: float,
    bn: Bins,
) -> None:
    """File new candidate ``k`` in its strip and bin: frozen above the zone, retired below.

    The first candidate of a strip starts that strip's zone at its bin. A
    candidate of a strip other than the current one stays hidden from the
    search until its strip is offered particles.
    """
    q = s.order[k]
    st = _strip_of(s.cx[q], s.fpar[K.F_XMIN], swidth, bn.head.shape[0])
    b = _bin_of(s.cy[q], s.fpar[K.F_YMIN], delta, bn.head.shape[1])
    s.home[k] = st
    bn.nxt[k] = bn.head[st, b]
    bn.head[st, b] = k
    cur = zs[Z_CUR]
    if sz[st, S_SEEDED] == 0 and (cur < 0 or b <= sz[cur, S_HI] + zs[Z_NZONE]):
        # a strip starts at its first candidate near the front (not at one that a
        # periodic domain wrapped to the top: that one is filed frozen)
        sz[st, S_SEEDED] = 1
        sz[st, S_HI] = b
        sz[st, S_LO] = max(0, b - zs[Z_NZONE] + 1)
        # candidates filed in the strip before it was seeded join its zone
        _thaw(st, sz[st, S_LO], b, st == cur, s, bn)
    leaves = s.ipar[K.I_LEAVES]
    if b > sz[st, S_HI] or b < sz[st, S_LO]:
        bn.flag[k] = FROZEN if b > sz[st, S_HI] else RETIRED
        tree_set(s.tree, leaves, k, -np.inf)
        if b < sz[st, S_FREED]:  # behind the zone for good: its list is not needed
            s.ipar[K.I_NBTOP] = release_row(q, s.nb_row, s.nb_free, s.ipar[K.I_NBTOP])
    elif bn.flag[k] != ACTIVE:  # (not thawed with its strip above)
        bn.flag[k] = ACTIVE
        if st != zs[Z_CUR]:
            K.hide_candidate(k, -np.inf, s)


@numba.njit(cache=True)
def _offer(
    i: int,
    st: int,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    zs: IntArray,
    sz: IntArray,
    bn: Bins,
    rounded: object,
    helpers: Helpers,
    partner: Partner,
) -> int:
    """Offer particle ``i`` to strip ``st``: the screened zone search, rising, then exact.

    Returns the new insertion index, or -1 when the strip refuses it.
    """
    mq = K.begin_particle(i, g, s, w)
    raises = int(np.int64(0))  # not a literal 0 (a second compilation of _roll_back)
    lo0 = sz[st, S_LO]
    hi0 = sz[st, S_HI]
    while True:
        k = place_screened_shared(i, mq, g, s, w, rng, rounded, partner)
        if k >= 0:
            return k
        if sz[st, S_FULL] == 0 and raises < zs[Z_NZONE]:
            if _raise(st, zs, sz, s, bn):
                raises += 1
                continue
            sz[st, S_FULL] = 1
            sz[st, S_PACE] = max(1, sz[st, S_OFFERED] // max(1, sz[st, S_RAISES]))
        if raises > 0:
            # rising did not help: a particle too large for the front must not
            # carry the zone away with it. The bins it retired reopen; the bins it
            # opened freeze again, unless the zone reached the top (the closing)
            keep_hi = sz[st, S_HI] if sz[st, S_FULL] == 1 else hi0
            _roll_back(st, sz, lo0, keep_hi, sz[st, S_FULL], raises, s, bn)
        # the exact scan's batches take every thread: the partner sleeps meanwhile
        store_release(partner.ctl, C_PARK, 1)
        k = _exhaustive(i, mq, g, s, w, rng, rounded, st, sz[st, S_LO], bn, helpers)
        store_release(partner.ctl, C_PARK, 0)
        return k


@numba.njit(cache=True)
def _step(
    i: int,
    queued: bool,
    prefer: int,
    delta: float,
    swidth: float,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    zs: IntArray,
    sz: IntArray,
    bn: Bins,
    status: IntArray,
    tried: IntArray,
    lags: Lags,
    rounded: object,
    helpers: Helpers,
    partner: Partner,
) -> int:
    """Offer particle ``i`` to the strips; return 1 when it is placed, else 0.

    ``queued``: ``i`` waited for its lag, so an earlier particle of the stream;
    its refusal does not end the tail closing. ``prefer``: a strip to offer it
    to first, if open (-1: the one :func:`_choose` picks, as for every particle).
    """
    nbins = bn.head.shape[1]
    if zs[Z_STARTED] == 0:
        ok, x, y = _lowest_centre(i, g, s)
        if not ok:
            status[i] = STATUS_REFUSED
            zs[Z_REFUSED] += 1
            return 0
        zs[Z_STARTED] = 1
        st = _strip_of(x, s.fpar[K.F_XMIN], swidth, bn.head.shape[0])
        sz[st, S_SEEDED] = 1
        sz[st, S_LO] = 0
        sz[st, S_HI] = _bin_of(y, s.fpar[K.F_YMIN], delta, nbins)
        zs[Z_CUR] = st
        s.ipar[K.I_STRIP] = st
        k = K.insert_particle(i, x, y, g, s)
        _register(k, zs, sz, s, delta, swidth, bn)
        status[i] = STATUS_PLACED
        return 1
    k = -1
    offered = -1  # the first strip particle i is offered to
    st = -1
    while True:
        st = _choose(sz, tried, i, zs[Z_CUR], zs[Z_STAY])
        if prefer >= 0 and tried[prefer] != i and _open(prefer, sz):
            st = prefer
        if st < 0:
            break
        _switch(st, zs, sz, s, bn)
        tried[st] = i
        if sz[st, S_FULL] == 1 and zs[Z_PROMPT] == 0:
            # paced closing: the lowest bin retires after as many offers as a bin took to
            # pass before, so the last zone sees the stream for as long as any other
            sz[st, S_SINCE] += 1
            if sz[st, S_SINCE] > sz[st, S_PACE]:
                sz[st, S_SINCE] = 0
                if _retire_lowest(st, sz, s, bn):
                    continue
        elif sz[st, S_FULL] == 0:
            sz[st, S_OFFERED] += 1
        was_full = sz[st, S_FULL]
        if offered < 0:
            offered = st
        k = _offer(i, st, g, s, w, rng, zs, sz, bn, rounded, helpers, partner)
        if k >= 0:
            break
        if zs[Z_PROMPT] == 2 and was_full == 1 and not queued:
            # tail closing: the first refusal under the top closes the strip; when no
            # strip is left the run ends, so the particles left out are the rest of
            # the stream, a random tail. The particle whose rises took the zone to
            # the top does not count: it fits nowhere, while the top bins have just
            # opened for the others
            sz[st, S_CLOSED] = 1
        # a particle one strip refuses goes on to the other open strips
    if offered < 0:
        # every strip closed before this particle could be offered
        zs[Z_DONE] = 1
        return 0
    if k >= 0:
        _register(k, zs, sz, s, delta, swidth, bn)
        if sz[st, S_FULL] == 0 and sz[st, S_HI] - sz[st, S_LO] + 1 >= zs[Z_NZONE]:
            lags.top_at[i] = sz[st, S_HI]
    for t in range(sz.shape[0]):
        if tried[t] == i:
            _release(t, sz, s, bn)
    if k < 0:
        status[i] = STATUS_REFUSED
        zs[Z_REFUSED] += 1
        # no particle and no strip searched (-1), no stay (0), as plain integers: numba
        # would compile a second specialization of _choose for literal ones
        unset, zero = int(np.int64(-1)), int(np.int64(0))
        if zs[Z_PROMPT] == 2:
            if _choose(sz, tried, unset, unset, zero) < 0:
                # tail closing: the last open strip has just closed
                zs[Z_DONE] = 1
        elif zs[Z_PROMPT] == 1 and not queued:
            # prompt closing: the refusal stands for the rise each full strip that
            # refused it would have made (a hidden strip's bin retires as well); a
            # waiting particle's does not, or the run could close while particles
            # drawn before it still wait
            for t in range(sz.shape[0]):
                if tried[t] == i and sz[t, S_CLOSED] == 0 and sz[t, S_FULL] == 1:
                    _retire_lowest(t, sz, s, bn)
            if _choose(sz, tried, unset, unset, zero) < 0:
                zs[Z_DONE] = 1
        return 0
    status[i] = STATUS_PLACED
    return 1


@numba.njit(cache=True)
def _open(st: int, sz: IntArray) -> bool:
    """Return whether strip ``st`` has started and not closed."""
    return sz[st, S_SEEDED] == 1 and sz[st, S_CLOSED] == 0


@numba.njit(cache=True)
def _top(st: int, zs: IntArray, sz: IntArray) -> int:
    """Return the bin of strip ``st``'s zone top, rising on as its full zone's bins retire.

    A full zone's top stays under the domain's top while its lowest bins retire
    (the paced and prompt closings); here it goes on rising with them, as the
    top of a zone of full height would.
    """
    if sz[st, S_FULL] == 1:
        return max(sz[st, S_HI], sz[st, S_LO] + zs[Z_NZONE] - 1)
    return sz[st, S_HI]


@numba.njit(cache=True)
def _full(sz: IntArray) -> bool:
    """Return whether every open strip's zone is at the domain's top (False for none)."""
    seen = False
    for st in range(sz.shape[0]):
        if _open(st, sz):
            seen = True
            if sz[st, S_FULL] == 0:
                return False
    return seen


@numba.njit(cache=True)
def _wait(i: int, home: int, zs: IntArray, sz: IntArray, lags: Lags) -> bool:
    """Queue particle ``i`` until strip ``home``'s zone top has risen by its lag.

    ``home`` is the strip ``i`` would be offered to now. Returns False when
    ``i`` is to be offered now: no lag, before the first particle, no open
    strip, or once the waiting particles have been let go.
    """
    if lags.lag[i] <= 0 or zs[Z_STARTED] == 0 or zs[Z_FLUSH] != 0 or home < 0:
        return False
    nbins = lags.qhead.shape[1]
    # not below the lowest bin still waited for, which the release has passed
    b = min(max(_top(home, zs, sz) + lags.lag[i], sz[home, S_QBIN]), nbins - 1)
    if lags.qtail[home, b] < 0:
        lags.qhead[home, b] = i
    else:
        lags.qnext[lags.qtail[home, b]] = i
    lags.qtail[home, b] = i
    lags.qnext[i] = -1
    zs[Z_QLEN] += 1
    return True


@numba.njit(cache=True)
def _due(zs: IntArray, sz: IntArray, lags: Lags) -> tuple[int, int]:
    """Return the strip and bin of the next waiting particle to offer, (-1, -1) for none.

    The first started strip, in index order, whose lowest waiting bin its zone
    top has reached (any waiting bin once they are let go, ``zs[Z_FLUSH] != 0``,
    or once the strip has closed).
    """
    nbins = lags.qhead.shape[1]
    for st in range(sz.shape[0]):
        if sz[st, S_SEEDED] == 0:
            continue  # no particle waits for a strip that has not started
        if zs[Z_FLUSH] != 0 or sz[st, S_CLOSED] == 1:
            limit = nbins - 1
        else:
            limit = min(_top(st, zs, sz), nbins - 1)
        # the release passes only bins up to the top, so a particle queued later
        # never lands below it
        b = sz[st, S_QBIN]
        while b <= limit and lags.qhead[st, b] < 0:
            b += 1
        sz[st, S_QBIN] = b
        if b <= limit:
            return st, b
    return -1, -1


@numba.njit(cache=True, nogil=True)
def sweep_range(
    begin: int,
    end: int,
    delta: float,
    swidth: float,
    g: K.Outlines,
    s: K.Packed,
    w: K.Work,
    rng: np.random.Generator,
    zs: IntArray,
    sz: IntArray,
    bn: Bins,
    status: IntArray,
    tried: IntArray,
    lags: Lags,
    rounded: object,
    helpers: Helpers,
    partner: Partner,
) -> int:
    """Offer particles ``begin`` to ``end - 1`` in the sweep order; return how many were placed.

    A particle with a lag waits until the zone top of the strip it would be
    offered to (its *home*) has risen by that many bins (see :func:`_top`);
    waiting particles are offered, to their home strip first, in the order
    they became due, before the next particle of the stream. In the prompt
    and tail closings no particle waits once every zone is at the domain's
    top, and every waiting particle is offered at once then (they leave out
    a random tail of the stream); so is every waiting particle in any closing
    when the stream ends below the top (but for those of a strip that has
    closed, in the paced closing). In the paced closing the lags go on
    as before, by the zone top that keeps rising as the lowest bins retire;
    when the stream ends, each strip's top rises on to its waiting particles'
    bins in turn, retiring the bins below as the stream would have. A waiting
    particle whose strip has closed before it was due is not offered.

    ``status`` records each particle offered (placed or refused); particles
    after the run has closed keep ``STATUS_NOT_OFFERED``.
    """
    # the arrays stay alive in the caller: no reference counts below (common.borrowed)
    g, s, w, zs, sz = borrowed(g), borrowed(s), borrowed(w), borrowed(zs), borrowed(sz)
    bn, status, tried, lags = borrowed(bn), borrowed(status), borrowed(tried), borrowed(lags)
    helpers, partner = borrowed(helpers), borrowed(partner)
    placed = 0
    last = end >= status.shape[0]
    for i in range(begin, end + 1 if last else end):
        if zs[Z_DONE] == 1:
            break
        # the waiting particles that are due (see the docstring for when all are)
        while zs[Z_QLEN] > 0 and zs[Z_DONE] == 0:
            full = _full(sz)
            if zs[Z_FLUSH] == 0:
                if full and zs[Z_PROMPT] == 0:
                    # in the paced closing the lags go on: the zone top keeps rising as
                    # the lowest bins retire (see _top), and a particle is due when it
                    # has risen by its lag, as in every zone before; when the stream
                    # ends, the tops rise on without it (below)
                    if i == end:
                        zs[Z_FLUSH] = 2
                elif full or i == end:
                    # the prompt and tail closings leave out a random tail of the
                    # stream: every particle drawn before it is offered once every
                    # zone is at the top; so is every particle when the stream ends
                    # below the top
                    zs[Z_FLUSH] = 1
            st, b = _due(zs, sz, lags)
            if st < 0:
                break
            q = lags.qhead[st, b]
            lags.qhead[st, b] = lags.qnext[q]
            if lags.qhead[st, b] < 0:
                lags.qtail[st, b] = -1
            zs[Z_QLEN] -= 1
            if zs[Z_PROMPT] == 0 and zs[Z_FLUSH] != 1:
                if zs[Z_FLUSH] == 2:
                    # the stream has ended: the strip's top rises on to the particle's
                    # bin, as the stream would have raised it, retiring the bins below
                    while sz[st, S_CLOSED] == 0 and _top(st, zs, sz) < b:
                        _retire_lowest(st, sz, s, bn)
                if sz[st, S_CLOSED] == 1:
                    continue  # its strip closed before it was due: not offered
            # (no literal flags or strips in these calls: see kernel.analyze_candidate's nf)
            placed += _step(
                q, bool(np.bool_(True)), st, delta, swidth, g, s, w, rng, zs, sz, bn, status,
                tried, lags, rounded, helpers, partner,
            )  # fmt: skip
        if i == end or zs[Z_DONE] == 1:
            break
        # no particle waits once every zone is at the top, except in the paced closing
        waits = zs[Z_PROMPT] == 0 or not _full(sz)
        if waits and _wait(i, _choose(sz, tried, i, zs[Z_CUR], zs[Z_STAY]), zs, sz, lags):
            continue
        placed += _step(
            i, bool(np.bool_(False)), int(np.int64(-1)), delta, swidth, g, s, w, rng, zs, sz, bn,
            status, tried, lags, rounded, helpers, partner,
        )  # fmt: skip
    return placed
