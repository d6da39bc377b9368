"""The sweep order in three dimensions: available-surface insertion inside a rising zone.

The same order as the 2D sweep (:mod:`regopack.plugins.inserters.available_arc.sweep`),
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
those of 2D; ``even`` is the paced closing that, once a column's zone has
reached the top, holds back a particle whose size class (:func:`size_classes`)
has been placed in a larger share of the particles offered than the least
placed class (:func:`held_back`): the coarse particles refused under the top
are matched by finer ones left out, so that the placed sizes stay a sample of
the drawn ones.

A candidate analysed for a particle keeps its answer while that particle is
being placed (nothing changes in between), so the exact pass skips the
candidates the screened passes already found without free area.

Each column lists its candidates in insertion order with a screening max-tree
over them (:class:`Zone`): the leaf of an active candidate is its ``rmin``,
that of a frozen or retired one ``-inf``, so the screened search descends the
tree to the candidates that pass instead of listing the whole packing for
every particle: its cost does not grow with the number placed.

Particles may be offered after a *lag* (:meth:`SurfaceSweep.set_lags`, learned
by the pilot of :mod:`regopack.plugins.inserters.available_arc.lag`), by the
rules of the 2D sweep: a particle with a lag waits until the zone top of the
column it would be offered to (its *home*) has risen by that many bins (a
full zone's top rising on as its lowest bins retire, :meth:`SurfaceSweep._top`);
the waiting particles that are due are offered, to their home column first,
before the next particle of the stream. In the prompt and tail closings no
particle waits once every zone is at the top, and all waiting ones are
offered then; so is every waiting particle when the stream ends below the
top (in the even closing too, so that every particle left out is one it held
back by its class counts). In the paced closing the lags go on by the rising
tops, and when the stream ends each column's top rises on to its waiting
particles' bins in turn, retiring the bins below; a waiting particle whose
column closed before it was due is not offered.

The *faceted* front (``front = "faceted"``) measures a candidate's height
along a field of square pyramids instead of along ``z``: over squares of
side ``facet`` on the floor, the height of a centre is ``(z + sqrt(2) g) /
sqrt(3)``, with ``g`` the larger of its distances along ``x`` and ``y`` from
the middle of its square. The front is then a field of pyramids whose faces
slope at ``sqrt(2)`` (the angle of a cube's corner) and move along their
normals ``(±sqrt(2), 0, 1) / sqrt(3)`` and ``(0, ±sqrt(2), 1) / sqrt(3)``,
whose second moment is isotropic: each face deposits a layer whose fabric
leans along its normal, and the four faces' fabrics average to an isotropic
one, while the front keeps its shape and area as it rises (the sample stays
homogeneous). The first particle still goes to the floor below the box's
centre, the apex of a pyramid. Polyhedra gather their contact normals more
tightly about the front's normals than spheres do and keep a vertical lean
at that slope; ``slope`` sets another angle between the faces' normals and
``z`` (the height is then ``z cos(slope) + g sin(slope)``).
"""

from __future__ import annotations

import heapq
import math
from bisect import bisect_right, insort
from collections import deque
from collections.abc import Callable

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.base.limits import MAX_ZONE_BINS as MAX_BINS
from regopack.base.limits import zone_bins
from regopack.plugins.common.strips import strip_count
from regopack.plugins.inserters.available_arc.candidates import tree_set
from regopack.plugins.inserters.available_surface.state import SurfaceState

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

ZONE_BINS = 80
"""Bins per zone height: the zone rises by ``zone / ZONE_BINS`` at a time."""


FROZEN, ACTIVE, RETIRED = 0, 1, 2
CLOSINGS = ("paced", "prompt", "tail", "even")
FRONTS = ("bottom-up", "faceted")
STATUS_NOT_OFFERED, STATUS_PLACED, STATUS_REFUSED, STATUS_HELD = 0, 1, 2, 3

EVEN_CLASS_SIZE = 100
"""Fewest drawn particles of a size class of the ``even`` closing: coarser classes pool."""
EVEN_MIN_OFFERED = 25
"""Offered particles a size class needs before its share sets the ``even`` closing's floor."""


MAX_TILES = 1 << 10
"""Most columns over the box's floor."""


HIDDEN = -np.inf
"""Screening leaf of a candidate hidden from the search (no radius passes it)."""


def size_classes(radius: FloatArray, fewest: int = EVEN_CLASS_SIZE) -> IntArray:
    """Each radius's size class: sqrt(2) classes from the smallest radius, the coarsest pooled.

    Class ``k`` holds the radii in ``[r_min 2^(k/2), r_min 2^((k+1)/2))``; from the
    coarsest down, a class of fewer than ``fewest`` radii joins the one below it,
    so that the sparse coarse tail (most of the mass) is counted as one class.
    """
    if radius.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    ratio = radius / float(np.min(radius))
    cls = np.floor(2.0 * np.log2(ratio) + 1e-12).astype(np.int64)
    counts = np.bincount(cls)
    top = counts.shape[0] - 1
    pooled = int(counts[top])
    while top > 0 and pooled < fewest:
        top -= 1
        pooled += int(counts[top])
    pooled_cls: IntArray = np.minimum(cls, top)
    return pooled_cls


def held_back(offered: IntArray, placed: IntArray, c: int) -> bool:
    """Whether the ``even`` closing holds back a particle of size class ``c``.

    ``offered`` and ``placed`` count, per class, the particles offered (held
    ones included) and placed so far. The particle is held when its class has
    been placed in a larger share of those offered than the least placed class
    of at least :data:`EVEN_MIN_OFFERED` offered: the coarse particles refused
    under the top are then matched by finer ones left out, so that the
    particles not placed are spread over the sizes as a random subset is.
    """
    if offered[c] == 0:
        return False
    big = offered >= EVEN_MIN_OFFERED
    if not big.any():
        return False
    floor = float(np.min(placed[big] / offered[big]))
    return bool(placed[c] > floor * offered[c])


@numba.njit(cache=True)
def _set_leaves(tree: FloatArray, positions: IntArray, values: FloatArray) -> None:
    leaves = tree.shape[0] // 2
    for m in range(positions.shape[0]):
        tree_set(tree, leaves, positions[m], values[m])


class Zone:
    """The rising zone of one column: its bins, lowest and top bin, and counters.

    ``members[:size]`` lists the column's candidates in insertion order;
    ``tree`` is the screening max-tree over those positions (``2 * leaves``
    values, leaf ``leaves + p`` for ``members[p]``).
    """

    def __init__(self, index: int = 0) -> None:
        self.index = index  # the column's position among the sweep's columns
        self.bins: dict[int, list[int]] = {}  # filled bins only
        self.lo = self.hi = 0
        self.full = self.closed = self.seeded = False
        self.raises = self.offered = self.pace = self.since = 0
        self.members = np.zeros(64, dtype=np.int64)
        self.size = 0
        self.tree = np.full(2 * 64, HIDDEN)

    def append(self, k: int) -> int:
        """List candidate ``k`` (hidden); return its position."""
        if self.size == self.members.shape[0]:
            self._grow()
        p = self.size
        self.members[p] = k
        self.size += 1
        return p

    def _grow(self) -> None:
        old = self.members.shape[0]
        new = 2 * old
        members = np.zeros(new, dtype=np.int64)
        members[:old] = self.members
        tree = np.full(2 * new, HIDDEN)
        tree[new : new + old] = self.tree[old : 2 * old]
        level = new
        while level > 1:  # every node the larger of its children, level by level
            half = level // 2
            tree[half:level] = np.maximum(
                tree[level : 2 * level : 2], tree[level + 1 : 2 * level : 2]
            )
            level = half
        self.members = members
        self.tree = tree


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
        ``"paced"``, ``"prompt"``, ``"tail"`` or ``"even"``.
    strip
        Width of the columns (length units): the box's floor is cut into
        equal tiles of about this width, each column with its own zone, as the
        2D strips; 0: one zone over the whole floor.
    front
        ``"bottom-up"`` (heights along ``z``) or ``"faceted"`` (heights
        along a field of pyramids; see the module docstring).
    facet
        Side of the faceted front's pyramids (length units, > 0 with it): the
        floor is cut into equal squares of about this side.
    slope
        Angle (degrees, in (0, 90)) between the faceted front's face normals
        and ``z``; ``None``: a cube's corner, ``arctan(sqrt(2))`` (54.7°),
        computed as ``(z + sqrt(2) g) / sqrt(3)``.
    floor
        Corners ``(lo, hi)`` of the floor the columns cover (``x`` and ``y``;
        a tile's window); ``None``: the box's.
    """

    def __init__(
        self,
        state: SurfaceState,
        t: float,
        zone: float,
        closing: str,
        strip: float = 0.0,
        front: str = "bottom-up",
        facet: float = 0.0,
        slope: float | None = None,
        floor: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        if closing not in CLOSINGS:
            raise ValueError(f"closing must be one of {CLOSINGS}, not {closing!r}")
        if front not in FRONTS:
            raise ValueError(f"front must be one of {FRONTS}, not {front!r}")
        self.state = state
        self.t = t
        height = float(state.hi[2] - state.lo[2])
        self.z0 = float(state.lo[2])
        floor_lo, floor_hi = (state.lo[:2], state.hi[:2]) if floor is None else floor
        span = floor_hi[:2] - floor_lo[:2]
        self.faceted = front == "faceted"
        self._facets = (0.0, 0.0, 1.0, 1.0)
        self._slope: tuple[float, float] | None = None
        if self.faceted:
            if not facet > 0:
                raise ValueError(f"a faceted front needs facet > 0, not {facet!r}")
            side = span / np.maximum(1.0, np.round(span / facet))
            middle = 0.5 * (state.lo[:2] + state.hi[:2])
            # squares centred on the box's middle (their pattern repeats with a periodic box)
            self._facets = (
                float(middle[0]),
                float(middle[1]),
                float(side[0]),
                float(side[1]),
            )
            if slope is None:
                height = (height + math.sqrt(2.0) * 0.5 * float(side.max())) / math.sqrt(3.0)
            else:
                if not 0.0 < slope < 90.0:
                    raise ValueError(f"slope must be in (0, 90) degrees, not {slope!r}")
                angle = math.radians(slope)
                self._slope = (math.cos(angle), math.sin(angle))
                height = height * self._slope[0] + 0.5 * float(side.max()) * self._slope[1]
        self.ntile = np.array(
            [
                strip_count(float(span[0]), strip, MAX_TILES),
                strip_count(float(span[1]), strip, MAX_TILES),
            ]
        )
        while int(self.ntile.prod()) > MAX_TILES:
            self.ntile = np.maximum(1, self.ntile // 2)
        self.twidth = span / self.ntile
        if int(self.ntile.prod()) > 1 and state.n > 0:
            # with columns, a zone at least two circumradii of the largest particle
            # high: a column's next candidate is then always within one zone of its top
            zone = max(zone, 2.0 * float(np.max(state.circum)))
        self.zone = zone
        self.delta = max(min(zone, height) / ZONE_BINS, height / MAX_BINS)
        if not self.delta > 0:
            self.delta = 1.0
        self.nbins = max(1, math.ceil(height / self.delta)) + 1
        self.zones = [Zone(k) for k in range(int(self.ntile.prod()))]
        # the open columns by zone top (entries (hi, column), pushed when a top moves; an
        # entry whose column has closed or moved on is dropped when it comes up), and the
        # open full columns in index order: the column choice does not list every column
        self._tops: list[tuple[int, int]] = []
        self._full_open: list[int] = []
        self._any_full = False  # some column's zone has reached the box's top
        # a tile's obstacles not yet filed, per column, by bin (:meth:`seed_with`)
        self._pending: list[deque[tuple[int, int]]] = []
        self._tiles = (
            [float(v) for v in floor_lo[:2]],
            [float(v) for v in self.twidth],
            [int(v) for v in self.ntile],
        )
        n = max(state.n, 1)
        self.flag = np.full(n, FROZEN, dtype=np.int8)
        self.tile = np.zeros(n, dtype=np.int64)
        self.tried = np.full(n, -1, dtype=np.int64)  # particle last analysed at each candidate
        self.pos = np.zeros(n, dtype=np.int64)  # each candidate's position in its column's list
        self.status = np.zeros(n, dtype=np.int8)
        self.nzone = max(1, zone_bins(zone, self.delta, height, ZONE_BINS))
        self.closing = closing
        self.cur = -1
        self.done = self.started = False
        self.refused = 0
        self.held = 0
        # the even closing: each particle's sqrt(2) size class (from the smallest drawn),
        # with the particles of each class offered and placed so far
        self.size_class = size_classes(state.radius[: state.n])
        ncls = int(self.size_class.max()) + 1 if state.n else 1
        self.class_offered = np.zeros(ncls, dtype=np.int64)
        self.class_placed = np.zeros(ncls, dtype=np.int64)
        # the lags: per particle the bins the front rises before its offer, and the bin of
        # its column's zone top when it was placed with the zone at full height (the
        # pilot's measure; -1 otherwise); per column the particles waiting, by the bin of
        # the top they wait for, and the lowest bin still waited for
        self.lag = np.zeros(n, dtype=np.int64)
        self.top_at = np.full(n, -1, dtype=np.int64)
        self.queues: list[dict[int, deque[int]]] = [{} for _ in self.zones]
        self.qbin = [0] * len(self.zones)
        self.waiting = 0
        self.flush = 0  # 1: every waiting particle is due; 2: the stream has ended (paced)
        # a full zone's top rises on for a zone height while its bins retire
        self.nwait = self.nbins + 2 * self.nzone + 1

    def set_lags(self, lag: IntArray) -> None:
        """Offer each particle ``lag[i]`` bins of the front's rise after its turn.

        All zeros (the default) offers every particle at its turn.
        """
        self.lag[: lag.shape[0]] = lag

    @property
    def paced(self) -> bool:
        """Whether the lags go on once every zone is at the top (the ``paced`` closing).

        The ``even`` closing lets its waiting particles go at once then, as
        ``tail`` and ``prompt`` do: a waiting particle left out at the end would
        escape the class counts by which it keeps the placed sizes true.
        """
        return self.closing == "paced"

    @property
    def raises(self) -> int:
        """Rises of the zones, over all columns."""
        return sum(z.raises for z in self.zones)

    # ------------------------------------------------------------------ bins

    def _level(self, c: FloatArray) -> float:
        """Return a centre's height for the zone: ``z``, or along the faceted front."""
        if not self.faceted:
            return float(c[2])
        mx, my, sx, sy = self._facets
        u = float(c[0]) - mx
        v = float(c[1]) - my
        g = max(abs(u - sx * round(u / sx)), abs(v - sy * round(v / sy)))
        if self._slope is not None:
            return self.z0 + (float(c[2]) - self.z0) * self._slope[0] + g * self._slope[1]
        return self.z0 + (float(c[2]) - self.z0 + math.sqrt(2.0) * g) / math.sqrt(3.0)

    def _bin_of(self, z: float) -> int:
        b = math.floor((z - self.z0) / self.delta)
        return min(max(b, 0), self.nbins - 1)

    def _tile_of(self, c: FloatArray) -> int:
        if len(self.zones) == 1:
            return 0
        # in floats, not small arrays: this runs once per particle placed
        lo, width, n = self._tiles
        i = min(max(math.floor((float(c[0]) - lo[0]) / width[0]), 0), n[0] - 1)
        j = min(max(math.floor((float(c[1]) - lo[1]) / width[1]), 0), n[1] - 1)
        return j * n[0] + i

    def _flag(self, k: int, flag: int) -> None:
        """Set candidate ``k``'s flag and its screening leaf (open only when active)."""
        self.flag[k] = flag
        z = self.zones[self.tile[k]]
        leaf = self.state.rmin[k] if flag == ACTIVE else HIDDEN
        tree_set(z.tree, z.members.shape[0], self.pos[k], leaf)

    def _register(self, k: int) -> None:
        c = self.state.centre[self.state.order[k]]
        b = self._bin_of(self._level(c))
        tile = self._tile_of(c)
        self.tile[k] = tile
        z = self.zones[tile]
        self.pos[k] = z.append(k)
        z.bins.setdefault(b, []).append(k)
        if not z.seeded and (self.cur < 0 or b <= self.zones[self.cur].hi + self.nzone):
            # a column starts at its first candidate near the front (not at one that a
            # periodic box wrapped to the top: that one is filed frozen)
            z.seeded = True
            z.hi = b
            z.lo = max(0, b - self.nzone + 1)
            self._moved(z)
            for bb, ks in z.bins.items():  # candidates filed before it join the zone
                if z.lo <= bb <= z.hi:
                    for kk in ks:
                        self._flag(kk, ACTIVE)
        if b > z.hi:
            self._flag(k, FROZEN)
        elif b < z.lo:
            self._flag(k, RETIRED)
        else:
            self._flag(k, ACTIVE)

    def _retire_lowest(self, z: Zone) -> None:
        for k in z.bins.get(z.lo, ()):
            self._flag(k, RETIRED)
        z.lo += 1

    def _retire(self, z: Zone) -> None:
        """Retire zone ``z``'s lowest bin; close the column when no bin is left."""
        self._retire_lowest(z)
        if z.lo > z.hi:
            self._close(z)

    def _raise(self, z: Zone) -> bool:
        """Raise zone ``z`` by one bin; False when its top is the box's top already."""
        if z.hi + 1 >= self.nbins:
            return False
        z.hi += 1
        z.raises += 1
        self._moved(z)
        self._admit(z)
        for k in z.bins.get(z.hi, ()):
            if self.flag[k] == FROZEN:
                self._flag(k, ACTIVE)
        if z.hi - z.lo + 1 > self.nzone:
            self._retire_lowest(z)
        return True

    def _roll_back(self, z: Zone, lo0: int, hi0: int, raises: int) -> None:
        for b in range(hi0 + 1, z.hi + 1):
            for k in z.bins.get(b, ()):
                if self.flag[k] == ACTIVE:
                    self._flag(k, FROZEN)
        for b in range(lo0, z.lo):
            for k in z.bins.get(b, ()):
                self._flag(k, ACTIVE)
        z.lo = lo0
        z.hi = hi0
        z.raises -= raises
        self._moved(z)

    def _moved(self, z: Zone) -> None:
        """Record zone ``z``'s top for the column choice (after it was seeded or moved)."""
        heapq.heappush(self._tops, (z.hi, z.index))

    def _close(self, z: Zone) -> None:
        """Close zone ``z``'s column: no particle is offered to it any more."""
        z.closed = True
        if z.full:
            at = bisect_right(self._full_open, z.index) - 1
            if at >= 0 and self._full_open[at] == z.index:
                del self._full_open[at]

    def _set_full(self, z: Zone) -> None:
        """Mark zone ``z`` at the box's top: its column takes turns with the other full ones."""
        z.full = True
        self._any_full = True
        insort(self._full_open, z.index)

    def _choose(self, tried: set[int]) -> int:
        """Return the column to offer the particle to next; -1 when no open one is left.

        The open column whose zone top is lowest, the first such one, among
        those not yet tried; among full columns the turn passes on after the
        current one, so that they close together. The tops come from a heap
        and the full columns from a sorted list: the cost does not grow with
        the number of columns.
        """
        tops = self._tops
        zones = self.zones
        best = -1
        kept: list[tuple[int, int]] = []
        while tops:
            hi, k = tops[0]
            z = zones[k]
            if z.hi != hi or z.closed or not z.seeded:
                heapq.heappop(tops)  # an old top, or a closed column
                continue
            if k not in tried:
                best = k
                break
            kept.append(heapq.heappop(tops))
        for entry in kept:
            heapq.heappush(tops, entry)
        if best >= 0 and len(zones) > 1 and zones[best].full and self.cur >= 0:
            full = self._full_open
            start = bisect_right(full, self.cur)
            top = zones[best].hi
            for d in range(len(full)):
                k = full[(start + d) % len(full)]
                if k not in tried and zones[k].hi == top:
                    return k
        return best

    # ------------------------------------------------------------------ lags

    def _top(self, z: Zone) -> int:
        """Bin of zone ``z``'s top, rising on as a full zone's lowest bins retire."""
        if z.full:
            return max(z.hi, z.lo + self.nzone - 1)
        return z.hi

    def _all_full(self) -> bool:
        """Whether every open column's zone is at the box's top (False for none)."""
        seen = False
        for z in self.zones:
            if z.seeded and not z.closed:
                seen = True
                if not z.full:
                    return False
        return seen

    def _wait(self, i: int, home: int) -> bool:
        """Queue particle ``i`` until column ``home``'s zone top has risen by its lag.

        Returns False when ``i`` is to be offered now: no lag, before the first
        particle, no open column, or once the waiting particles have been let go.
        """
        if self.lag[i] <= 0 or not self.started or self.flush != 0 or home < 0:
            return False
        z = self.zones[home]
        # not below the lowest bin still waited for, which the release has passed
        b = min(max(self._top(z) + int(self.lag[i]), self.qbin[home]), self.nwait - 1)
        self.queues[home].setdefault(b, deque()).append(i)
        self.waiting += 1
        return True

    def _due(self) -> tuple[int, int]:
        """Column and bin of the next waiting particle to offer, (-1, -1) for none.

        The first started column, in index order, whose lowest waiting bin its
        zone top has reached (any waiting bin once they are let go, or once the
        column has closed).
        """
        for k, z in enumerate(self.zones):
            queue = self.queues[k]
            if not z.seeded or not queue:
                continue
            if self.flush != 0 or z.closed:
                limit = self.nwait - 1
            else:
                limit = min(self._top(z), self.nwait - 1)
            # the release passes only bins up to the top: a particle queued later
            # never waits below it
            b = self.qbin[k]
            while b <= limit and b not in queue:
                b += 1
            self.qbin[k] = b
            if b <= limit:
                return k, b
        return -1, -1

    def _release(self, rng: np.random.Generator, ended: bool) -> None:
        """Offer the waiting particles that are due (``ended``: the stream has ended)."""
        while self.waiting > 0 and not self.done:
            if self.flush == 0:
                full = self._all_full()
                if full and self.paced:
                    # the lags go on by the rising tops; when the stream ends the tops
                    # rise on without it (below)
                    if ended:
                        self.flush = 2
                elif full or ended:
                    # the prompt and tail closings leave out a random tail of the
                    # stream: every particle drawn before it is offered once every zone
                    # is at the top; so is every particle when the stream ends below it
                    self.flush = 1
            k, b = self._due()
            if k < 0:
                return
            queue = self.queues[k]
            q = queue[b].popleft()
            if not queue[b]:
                del queue[b]
            self.waiting -= 1
            if self.paced and self.flush != 1:
                z = self.zones[k]
                if self.flush == 2:
                    # the stream has ended: the column's top rises on to the particle's
                    # bin, as the stream would have raised it, retiring the bins below
                    while not z.closed and self._top(z) < b:
                        self._retire(z)
                if z.closed:
                    continue  # its column closed before it was due: not offered
            self.offer(q, rng, queued=True, prefer=k)

    # ---------------------------------------------------------------- search

    def _screened(self, i: int, rng: np.random.Generator) -> tuple[int, FloatArray | None]:
        z = self.zones[self.cur]
        return self.state.scan(z.members[: z.size], rng, tried=self.tried, tree=z.tree)

    def _exhaustive(self, i: int, rng: np.random.Generator) -> FloatArray | None:
        st = self.state
        z = self.zones[self.cur]
        members = z.members[: z.size]
        todo = members[(self.flag[members] != RETIRED) & (self.tried[members] != i)]
        x = st.scan(todo, rng, screened=False, tried=self.tried)[1]
        # the active candidates it found empty have a new rmin: so have their leaves
        seen = todo[(self.tried[todo] == i) & (self.flag[todo] == ACTIVE)]
        if seen.shape[0]:
            _set_leaves(z.tree, self.pos[seen], st.rmin[seen])
        return x

    def _offer_to(self, i: int, z: Zone, rng: np.random.Generator) -> FloatArray | None:
        """Offer particle ``i`` to the current column: screened, rising, then exact."""
        raises = 0
        lo0, hi0 = z.lo, z.hi
        while True:
            _, x = self._screened(i, rng)
            if x is not None:
                return x
            if not z.full and raises < self.nzone:
                if self._raise(z):
                    raises += 1
                    continue
                self._set_full(z)
                z.pace = max(1, z.offered // max(1, z.raises))
            if raises > 0:
                # rising did not help: the bins it retired reopen, those it opened
                # freeze again, unless the zone reached the top (the closing)
                self._roll_back(z, lo0, z.hi if z.full else hi0, raises)
            return self._exhaustive(i, rng)

    # ------------------------------------------------------------------ loop

    def offer(
        self, i: int, rng: np.random.Generator, queued: bool = False, prefer: int = -1
    ) -> None:
        """Offer particle ``i`` (after the run has closed it is not offered).

        ``queued``: ``i`` waited for its lag, so an earlier particle of the
        stream; its refusal does not close a column (tail) nor retire bins
        (prompt). ``prefer``: a column to offer it to first, if open.
        """
        if self.done:
            return
        if self.closing != "even":
            self._offer(i, rng, queued, prefer)
            return
        c = int(self.size_class[i])
        closing = self._any_full
        if closing and held_back(self.class_offered, self.class_placed, c):
            self.class_offered[c] += 1
            self.status[i] = STATUS_HELD
            self.held += 1
            return
        self._offer(i, rng, queued, prefer)
        if self.status[i] != STATUS_NOT_OFFERED:
            self.class_offered[c] += 1
            self.class_placed[c] += int(self.status[i] == STATUS_PLACED)

    def _offer(self, i: int, rng: np.random.Generator, queued: bool, prefer: int) -> None:
        st = self.state
        if not self.started:
            if st.begin(i):
                middle = 0.5 * (st.lo + st.hi)
                if st.window is not None:
                    # a tile starts below the middle of its window, not of the box
                    w_lo = np.maximum(st.lo, st.window[0])
                    w_hi = np.minimum(st.hi, st.window[1])
                    middle = 0.5 * (w_lo + w_hi)
                first = np.clip(middle, st.adm_lo, st.adm_hi)
                first[2] = st.lo[2] if st.period is not None else st.adm_lo[2]
                if st.fits_at(first):
                    self.started = True
                    self.cur = self._tile_of(first)
                    z = self.zones[self.cur]
                    z.seeded = True
                    z.hi = self._bin_of(self._level(first))
                    self._moved(z)
                    self._register(st.insert(i, first))
                    self.status[i] = STATUS_PLACED
                    return
            self.status[i] = STATUS_REFUSED
            self.refused += 1
            return
        x: FloatArray | None = None
        tried: set[int] = set()
        offered = -1  # the first column the particle is offered to
        fits = True
        while True:
            k = self._choose(tried)
            if prefer >= 0 and prefer not in tried and self._open(prefer):
                k = prefer
            if k < 0:
                break
            tried.add(k)
            self.cur = k
            z = self.zones[k]
            if z.full and self.closing in ("paced", "even"):
                # the lowest bin retires after as many offers as a bin took to pass before
                z.since += 1
                if z.since > z.pace:
                    z.since = 0
                    self._retire(z)
                    if z.closed:
                        continue
            elif not z.full:
                z.offered += 1
            was_full = z.full
            if offered < 0:
                offered = k
                fits = st.begin(i)
            x = self._offer_to(i, z, rng) if fits else None
            if x is not None:
                break
            if was_full and self.closing == "tail" and not queued:
                self._close(z)  # the first refusal under the top closes the column
            if not fits:
                break  # larger than the box
            # a particle one column refuses goes on to the other open columns
        if offered < 0:
            self.done = True  # every column closed before this particle was offered
            return
        if x is None:
            self.status[i] = STATUS_REFUSED
            self.refused += 1
            if self.closing == "prompt" and not queued:
                # the refusal stands for the rise each full column that refused it
                # would have made (a waiting particle's does not: the run could close
                # while particles drawn before it still wait)
                for k in sorted(tried):
                    z = self.zones[k]
                    if z.full and not z.closed:
                        self._retire(z)
            if self.closing in ("tail", "prompt") and self._choose(set()) < 0:
                self.done = True
            return
        z = self.zones[self.cur]
        if not z.full and z.hi - z.lo + 1 >= self.nzone:
            self.top_at[i] = z.hi
        self._register(st.insert(i, x))
        self.status[i] = STATUS_PLACED

    def _open(self, k: int) -> bool:
        """Whether column ``k`` has started and not closed."""
        z = self.zones[k]
        return z.seeded and not z.closed

    def seed_with(self, count: int) -> None:
        """Take the first ``count`` placed particles as candidates as the front reaches them.

        A tile's obstacles (placed before its own particles, lowest first)
        join their column's candidates when its zone's top reaches their bin,
        as the particles of a sweep are filed when the front has built up to
        them: the scan meets them in the order of a sweep that had placed
        them, not all before the tile's own. Each column's zone starts at its
        lowest obstacle; the sweep counts as started when there is one.
        """
        st = self.state
        pending: list[list[tuple[int, int]]] = [[] for _ in self.zones]
        for k in range(count):
            c = st.centre[st.order[k]]
            pending[self._tile_of(c)].append((self._bin_of(self._level(c)), k))
        self._pending = [deque(sorted(q)) for q in pending]
        for z in self.zones:
            q = self._pending[z.index]
            if q:
                low = q[0][0]
                while q and q[0][0] == low:
                    self._register(q.popleft()[1])
        if count > 0:
            self.started = True

    def _admit(self, z: Zone) -> None:
        """File the obstacles of zone ``z``'s column that its top has reached."""
        q = self._pending[z.index] if self._pending else None
        while q and q[0][0] <= z.hi:
            self._register(q.popleft()[1])

    def run(
        self,
        rng: np.random.Generator,
        progress: Callable[[int, int, int], None] | None = None,
        every: int = 500,
        first: int = 0,
    ) -> None:
        """Offer every particle from ``first`` on in population order, each after its lag."""
        n = self.state.n
        for i in range(first, n + 1):
            if progress is not None and i % every == 0 and i < n:
                progress(i - first, self.state.count - first, n - first)
            if self.done:
                break
            self._release(rng, ended=i == n)
            if i == n or self.done:
                break
            # no particle waits once every zone is at the top, but in the paced closing
            # (a particle without a lag, as every one with lag = "none", skips the test)
            if self.lag[i] > 0 and (self.paced or not self._all_full()):
                if self._wait(i, self._choose(set())):
                    continue
            self.offer(i, rng)
