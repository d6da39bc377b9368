"""The sweep order in three dimensions: available-surface insertion inside a rising zone.

The same order as the 2D sweep (:mod:`regopack.plugins.available_arc.sweep`),
with the height along ``z``: the first particle sits at the bottom of the box
below its centre; candidates are filed in horizontal bins by the height of
their centre (``ZONE_BINS`` bins per zone height); only the candidates of the
*zone*, bins ``lo..hi``, are searched, oldest first with the screening; bins
above are *frozen*, bins below *retired*. A particle that no zone candidate
takes raises the zone by one bin and is offered again; after a full zone
height of rises that did not help, the rises are undone (the zone keeps its
top once it has reached the top of the box) and the particle is analysed
exactly, without screening, at every candidate not retired; it is *refused*
when none has free area. The closings (``paced``, ``prompt``, ``tail``) are
those of 2D.

A candidate analysed for a particle keeps its answer while that particle is
being placed (nothing changes in between), so the exact pass skips the
candidates the screened passes already found without free area.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from regopack.plugins.available_surface.state import SurfaceState

FloatArray = NDArray[np.float64]

ZONE_BINS = 80
"""Bins per zone height: the zone rises by ``zone / ZONE_BINS`` at a time."""
MAX_BINS = 1 << 20
"""Most bins over the box's height."""
FROZEN, ACTIVE, RETIRED = 0, 1, 2
CLOSINGS = ("paced", "prompt", "tail")
STATUS_NOT_OFFERED, STATUS_PLACED, STATUS_REFUSED = 0, 1, 2


class SurfaceSweep:
    """State of one sweep run over a :class:`SurfaceState`.

    Parameters
    ----------
    state
        The run's placed particles.
    t
        Screening coefficient.
    zone
        Zone height (length units, > 0).
    closing
        ``"paced"``, ``"prompt"`` or ``"tail"``.
    """

    def __init__(self, state: SurfaceState, t: float, zone: float, closing: str) -> None:
        if closing not in CLOSINGS:
            raise ValueError(f"closing must be one of {CLOSINGS}, not {closing!r}")
        self.state = state
        self.t = t
        height = float(state.hi[2] - state.lo[2])
        self.z0 = float(state.lo[2])
        self.delta = max(min(zone, height) / ZONE_BINS, height / MAX_BINS)
        if not self.delta > 0:
            self.delta = 1.0
        self.nbins = max(1, math.ceil(height / self.delta)) + 1
        self.bins: list[list[int]] = [[] for _ in range(self.nbins)]
        n = max(state.n, 1)
        self.flag = np.full(n, FROZEN, dtype=np.int8)
        self.tried = np.full(n, -1, dtype=np.int64)  # particle last analysed at each candidate
        self.status = np.zeros(n, dtype=np.int8)
        self.nzone = max(1, round(zone / self.delta))
        self.closing = closing
        self.lo = self.hi = 0
        self.full = self.done = self.started = False
        self.raises = self.refused = self.offered = self.pace = self.since = 0

    # ------------------------------------------------------------------ bins

    def _bin_of(self, z: float) -> int:
        b = math.floor((z - self.z0) / self.delta)
        return min(max(b, 0), self.nbins - 1)

    def _register(self, k: int) -> None:
        b = self._bin_of(float(self.state.centre[self.state.order[k], 2]))
        self.bins[b].append(k)
        if b > self.hi:
            self.flag[k] = FROZEN
        elif b < self.lo:
            self.flag[k] = RETIRED
        else:
            self.flag[k] = ACTIVE

    def _retire_lowest(self) -> None:
        for k in self.bins[self.lo]:
            self.flag[k] = RETIRED
        self.lo += 1

    def _raise(self) -> bool:
        """Raise the zone by one bin; False when its top is the box's top already."""
        if self.hi + 1 >= self.nbins:
            return False
        self.hi += 1
        self.raises += 1
        for k in self.bins[self.hi]:
            if self.flag[k] == FROZEN:
                self.flag[k] = ACTIVE
        if self.hi - self.lo + 1 > self.nzone:
            self._retire_lowest()
        return True

    def _roll_back(self, lo0: int, hi0: int, raises: int) -> None:
        for b in range(hi0 + 1, self.hi + 1):
            for k in self.bins[b]:
                if self.flag[k] == ACTIVE:
                    self.flag[k] = FROZEN
        for b in range(lo0, self.lo):
            for k in self.bins[b]:
                self.flag[k] = ACTIVE
        self.lo = lo0
        self.hi = hi0
        self.raises -= raises

    # ---------------------------------------------------------------- search

    def _screened(self, i: int, rng: np.random.Generator) -> tuple[int, FloatArray | None]:
        st = self.state
        c = st.count
        open_ = (self.flag[:c] == ACTIVE) & (st.radius[i] < self.t * st.rmin[:c])
        return st.scan(np.flatnonzero(open_), rng, tried=self.tried)

    def _exhaustive(self, i: int, rng: np.random.Generator) -> FloatArray | None:
        st = self.state
        c = st.count
        todo = (self.flag[:c] != RETIRED) & (self.tried[:c] != i)
        return st.scan(np.flatnonzero(todo), rng, screened=False, tried=self.tried)[1]

    # ------------------------------------------------------------------ loop

    def offer(self, i: int, rng: np.random.Generator) -> None:
        """Offer particle ``i`` (after the run has closed it is not offered)."""
        st = self.state
        if self.done:
            return
        if not self.started:
            if st.begin(i):
                first = np.clip(0.5 * (st.lo + st.hi), st.adm_lo, st.adm_hi)
                first[2] = st.lo[2] if st.period is not None else st.adm_lo[2]
                if st.fits_at(first):
                    self.started = True
                    self.hi = self._bin_of(float(first[2]))
                    self._register(st.insert(i, first))
                    self.status[i] = STATUS_PLACED
                    return
            self.status[i] = STATUS_REFUSED
            self.refused += 1
            return
        if self.full and self.closing == "paced":
            # the lowest bin retires after as many offers as a bin took to pass before
            self.since += 1
            if self.since > self.pace:
                self.since = 0
                self._retire_lowest()
                if self.lo > self.hi:
                    self.done = True
                    return
        elif not self.full:
            self.offered += 1
        was_full = self.full
        x: FloatArray | None = None
        if st.begin(i):
            raises = 0
            lo0, hi0 = self.lo, self.hi
            while True:
                _, x = self._screened(i, rng)
                if x is not None:
                    break
                if not self.full and raises < self.nzone:
                    if self._raise():
                        raises += 1
                        continue
                    self.full = True
                    self.pace = max(1, self.offered // max(1, self.raises))
                if raises > 0:
                    # rising did not help: the bins it retired reopen, those it opened
                    # freeze again, unless the zone reached the top (the closing)
                    self._roll_back(lo0, self.hi if self.full else hi0, raises)
                x = self._exhaustive(i, rng)
                break
        if x is None:
            self.status[i] = STATUS_REFUSED
            self.refused += 1
            if self.full and self.closing == "prompt":
                self._retire_lowest()
                if self.lo > self.hi:
                    self.done = True
            elif was_full and self.closing == "tail":
                self.done = True
            return
        self._register(st.insert(i, x))
        self.status[i] = STATUS_PLACED

    def run(
        self,
        rng: np.random.Generator,
        progress: Callable[[int, int, int], None] | None = None,
        every: int = 500,
    ) -> None:
        """Offer every particle in population order."""
        n = self.state.n
        for i in range(n):
            if progress is not None and i % every == 0:
                progress(i, self.state.count, n)
            if self.done:
                break
            self.offer(i, rng)
