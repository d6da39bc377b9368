r"""Available-surface analysis for spheres: the free part of a sphere, exactly, and a centre on it.

For a candidate sphere ``k`` (centre ``c_k``, radius ``r_k``) and a new sphere
of radius ``r``, the centres at which the new sphere touches ``k`` form the
sphere ``S`` of radius ``R = r_k + r`` about ``c_k``. Every constraint removes
an open *cap* ``{u : n · u > h}`` of ``S`` (``u = x - c_k``, ``|n| = 1``):

- an interferer ``j`` at ``c_j`` (``d = c_j - c_k``), whose open ball of
  radius ``rho = r_j + r`` holds the centres that overlap it:
  ``n = d / |d|``, ``h = (R^2 + |d|^2 - rho^2) / (2 |d|)``;
- a wall: the centre must keep ``r`` from it, ``n = ∓e_a``, ``h`` the
  distance from ``c_k`` to the plane of admissible centres.

The packing control adds its margin to ``rho`` and to the walls.

**Certificate.** The free set ``F = S \\ ∪ caps`` is closed; unless there is
no cap, it is empty exactly when the boundary circle of every cap lies in
the union of the other caps (a boundary point of a non-empty ``F`` lies on
some circle and in no open cap). Each circle is handled as in 2D: every
other cap covers an open arc of it, computed in closed form; free arcs
shorter than ``THIN`` of ``R`` (tangent points) count as nothing, as do
circles thinner than that and arcs beside which the free set is narrower
than ``WIDTH`` tolerances at their middle and at both quarters (two caps
meeting along a seam; another cap that only touches the arc at one point
does not remove it).

**Sampling.** The centre is uniform by area on ``F``: points uniform on a cap
``K`` that holds ``F`` are proposed and the first free one is taken
(:func:`bounding_cap`). ``K`` is the smallest cap about the free arcs' mean
direction that holds every free arc, computed exactly per arc. Since the
boundary of ``F`` lies on the free arcs, the rest of the sphere, ``S \\ K``
(connected), is wholly free or wholly covered; the point opposite the axis
tells which, and when it is free ``K`` is the whole sphere. A free set in a
small corner is thus sampled with a hit rate of a few tenths, not its share
of the sphere. The boundary lies on the free arcs up to the seam rule: an arc
dropped because the free set beside it is too narrow at its middle and both
quarters bounds nothing, so other caps touching such an arc at exactly those
three points, and nowhere else, leave part of ``F`` outside ``K`` (a
configuration of measure zero: moving them apart by 1e-11 of ``R`` restores
the bound). After ``TRIES`` failures (a free set under about 1e-5 of
``K``: seams and slivers) a point uniform by length on the free arcs is
taken: free, but not uniform by area; in dense packings no placed sphere was
seen to take it.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)
from regopack.plugins.common.kernel_random import KernelSource, uniform

FloatArray = NDArray[np.float64]

EPS = 1e-12
"""Contact tolerance relative to ``R``: a point within it of a cap's edge is free."""
THIN = 1e-9
"""Free arcs (and circles) shorter than this fraction of ``R`` count as no surface."""
WIDTH = 16.0
"""A free set narrower than this many tolerances beside its boundary arc counts as nothing."""
TRIES = 1 << 16
"""Proposals of each sampling stage."""
WIDTH_AT = (0.5, 0.25, 0.75)
"""Where along a free arc :func:`_has_width` looks, in turn (fractions of the arc)."""


@numba.njit(cache=True)
def _frame(nx: float, ny: float, nz: float) -> tuple[float, float, float, float, float, float]:
    """Two unit vectors completing ``n`` to an orthonormal frame."""
    if abs(nx) < 0.9:
        ax, ay, az = 1.0, 0.0, 0.0
    else:
        ax, ay, az = 0.0, 1.0, 0.0
    e1x = ny * az - nz * ay
    e1y = nz * ax - nx * az
    e1z = nx * ay - ny * ax
    inv = 1.0 / math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x *= inv
    e1y *= inv
    e1z *= inv
    return e1x, e1y, e1z, ny * e1z - nz * e1y, nz * e1x - nx * e1z, nx * e1y - ny * e1x


@numba.njit(cache=True)
def _circle_covers(
    caps: FloatArray,
    ncaps: int,
    j: int,
    hj: float,
    rc: float,
    shrink: float,
    lo: FloatArray,
    hi: FloatArray,
    below: bool,
) -> int:
    """Fill ``lo``/``hi`` with the open arcs of circle ``j`` that the other caps cover.

    The circle is ``n_j · u = hj`` (radius ``rc``), the other caps are read
    shrunk by ``shrink``; angles in the circle's frame (:func:`_frame`), each
    arc starting in ``[0, 2 pi)``. An arc through angle 0 is cut there into
    two (``below`` False), or kept whole with a copy one turn lower
    (``below`` True). Returns the number of arcs, or -1 when one cap holds
    the whole circle.
    """
    two_pi = 2.0 * math.pi
    nx, ny, nz = caps[j, 0], caps[j, 1], caps[j, 2]
    e1x, e1y, e1z, e2x, e2y, e2z = _frame(nx, ny, nz)
    m = 0
    for q in range(ncaps):
        if q == j:
            continue
        mx, my, mz = caps[q, 0], caps[q, 1], caps[q, 2]
        a = rc * (mx * e1x + my * e1y + mz * e1z)
        b = rc * (mx * e2x + my * e2y + mz * e2z)
        c = caps[q, 3] + shrink - hj * (mx * nx + my * ny + mz * nz)
        amp = math.sqrt(a * a + b * b)
        if c >= amp:
            continue  # cap q misses the circle
        if c < -amp:
            return -1
        mid = math.atan2(b, a)
        half = math.acos(c / amp)
        s = (mid - half) % two_pi
        e = s + 2.0 * half
        if e > two_pi and not below:  # through angle 0: two pieces
            lo[m] = s
            hi[m] = two_pi
            m += 1
            lo[m] = 0.0
            hi[m] = e - two_pi
            m += 1
            continue
        lo[m] = s
        hi[m] = e
        m += 1
        if e > two_pi:  # its copy one turn lower covers the start
            lo[m] = s - two_pi
            hi[m] = e - two_pi
            m += 1
    return m


@numba.njit(cache=True)
def _has_width(
    caps: FloatArray,
    ncaps: int,
    big_r: float,
    tau: float,
    j: int,
    angle: float,
    rc: float,
    hj: float,
    e1x: float,
    e1y: float,
    e1z: float,
    e2x: float,
    e2y: float,
    e2z: float,
) -> bool:
    """Whether the free set extends off circle ``j`` at ``angle``, away from cap ``j``.

    A free arc along which another cap meets cap ``j`` exactly (a seam of zero
    area) has no free point beside it; the point tried lies ``WIDTH * tau``
    from the circle on the sphere.
    """
    nx, ny, nz = caps[j, 0], caps[j, 1], caps[j, 2]
    c = math.cos(angle)
    sn = math.sin(angle)
    # the circle point and the unit tangent of the sphere pointing away from cap j
    px = hj * nx + rc * (c * e1x + sn * e2x)
    py = hj * ny + rc * (c * e1y + sn * e2y)
    pz = hj * nz + rc * (c * e1z + sn * e2z)
    ndot = (nx * px + ny * py + nz * pz) / (big_r * big_r)
    wx = ndot * px - nx
    wy = ndot * py - ny
    wz = ndot * pz - nz
    norm = math.sqrt(wx * wx + wy * wy + wz * wz)
    if norm == 0.0:
        return True
    step = WIDTH * tau / norm
    qx = px + step * wx
    qy = py + step * wy
    qz = pz + step * wz
    scale = big_r / math.sqrt(qx * qx + qy * qy + qz * qz)
    return is_free(caps, ncaps, qx * scale, qy * scale, qz * scale, tau)


@numba.njit(cache=True)
def _arc_has_width(
    caps: FloatArray,
    ncaps: int,
    big_r: float,
    tau: float,
    j: int,
    start: float,
    end: float,
    rc: float,
    hj: float,
    e1x: float,
    e1y: float,
    e1z: float,
    e2x: float,
    e2y: float,
    e2z: float,
) -> bool:
    """:func:`_has_width` at the middle of the arc, then at its quarters.

    A seam (another cap meeting cap ``j`` along its circle) has no width
    anywhere along the arc; a free set that another cap only pinches at
    one point (a tangency at the arc's middle) has width beside the rest.
    """
    for frac in WIDTH_AT:
        if _has_width(
            caps, ncaps, big_r, tau, j, start + frac * (end - start), rc, hj,
            e1x, e1y, e1z, e2x, e2y, e2z,
        ):  # fmt: skip
            return True
    return False


CONTAINED_MARGIN = 1e-9
"""Margin of :func:`drop_contained`'s cosine test (a cap must lie clearly inside another)."""


@numba.njit(cache=True)
def drop_contained(caps: FloatArray, ncaps: int, big_r: float, tau: float) -> int:
    """Drop every cap that lies inside another one; return how many are left.

    Cap ``q`` (closed, ``n_q · u >= h_q``, angular radius ``theta_q``) lies
    inside the open cap ``p`` as :func:`free_arcs` and :func:`is_free` read
    it (``n_p · u > h_p + tau``, ``theta_p``) when the angle between their
    axes is less than ``theta_p - theta_q``, tested by cosines with a margin
    of :data:`CONTAINED_MARGIN`. Such a cap bounds no free arc, covers no
    point of any circle that ``p`` leaves free, and frees no point ``p``
    covers: the free arcs, :func:`is_free` and so the drawn centre are the
    same without it. The rows left keep their order, at the front of
    ``caps``. In a dense packing about 40 % of the caps are dropped.
    """
    cos_q = np.empty(ncaps)
    sin_q = np.empty(ncaps)
    cos_p = np.empty(ncaps)
    sin_p = np.empty(ncaps)
    for j in range(ncaps):
        c = caps[j, 3] / big_r
        cos_q[j] = c
        sin_q[j] = math.sqrt(max(1.0 - c * c, 0.0))
        c = (caps[j, 3] + tau) / big_r
        cos_p[j] = c
        sin_p[j] = math.sqrt(max(1.0 - c * c, 0.0))
    keep = np.ones(ncaps, dtype=np.bool_)
    for q in range(ncaps):
        for p in range(ncaps):
            # theta_p > theta_q, and cos(angle) > cos(theta_p - theta_q); a dropped p
            # lies inside a larger cap that holds q too
            if p == q or not cos_p[p] < cos_q[q]:
                continue
            dot = caps[p, 0] * caps[q, 0] + caps[p, 1] * caps[q, 1] + caps[p, 2] * caps[q, 2]
            if dot > cos_p[p] * cos_q[q] + sin_p[p] * sin_q[q] + CONTAINED_MARGIN:
                keep[q] = False
                break
    m = 0
    for q in range(ncaps):
        if keep[q]:
            for c in range(4):
                caps[m, c] = caps[q, c]
            m += 1
    return m


@numba.njit(cache=True)
def free_arcs(caps: FloatArray, ncaps: int, big_r: float, tau: float) -> FloatArray:
    """Free arcs of every cap's boundary circle.

    ``caps`` rows are ``(nx, ny, nz, h)``. Returns rows ``(cap, start, end)``
    (angles in the circle's frame from :func:`_frame`, ``start < end``).
    """
    out = np.empty((16, 3))
    nout = 0
    lo = np.empty(2 * ncaps + 2)
    hi = np.empty(2 * ncaps + 2)
    two_pi = 2.0 * math.pi
    for j in range(ncaps):
        nx, ny, nz, hj = caps[j, 0], caps[j, 1], caps[j, 2], caps[j, 3]
        rc = math.sqrt(max(big_r * big_r - hj * hj, 0.0))
        if rc <= THIN * big_r:
            continue
        e1x, e1y, e1z, e2x, e2y, e2z = _frame(nx, ny, nz)
        m = _circle_covers(caps, ncaps, j, hj, rc, tau, lo, hi, False)
        if m < 0:
            continue  # inside another cap
        order = np.argsort(lo[:m])
        at = 0.0
        min_angle = THIN * big_r / rc
        for idx in range(m + 1):
            if idx < m:
                s = lo[order[idx]]
                e = hi[order[idx]]
            else:
                s = two_pi
                e = two_pi
            if s - at > min_angle and _arc_has_width(
                caps, ncaps, big_r, tau, j, at, s, rc, hj, e1x, e1y, e1z, e2x, e2y, e2z
            ):
                if nout == out.shape[0]:
                    grown = np.empty((2 * nout, 3))
                    grown[:nout] = out[:nout]
                    out = grown
                out[nout, 0] = j
                out[nout, 1] = at
                out[nout, 2] = s
                nout += 1
            at = max(at, e)
    return out[:nout]


COVER_MARGIN = 1e-9
"""Depth, in fractions of ``R``, by which :func:`covers` wants every point covered."""


@numba.njit(cache=True)
def covers(caps: FloatArray, ncaps: int, big_r: float, depth: float) -> bool:
    """Whether the caps, each shrunk by ``depth``, cover the whole sphere.

    Strict: any gap, however thin, counts as free (no :data:`THIN` or
    :data:`WIDTH` rule), and covers that only share an end leave that point
    free. Every point then lies deeper than ``depth`` inside some cap. The
    shrunk caps ``{u : n · u > h + depth}`` cover the sphere exactly when each
    one's boundary circle lies in the union of the others (see the module
    docstring); the test stops at the first gap.
    """
    if ncaps == 0:
        return False
    lo = np.empty(2 * ncaps + 2)
    hi = np.empty(2 * ncaps + 2)
    two_pi = 2.0 * math.pi
    live = False
    for j in range(ncaps):
        if caps[j, 3] + depth <= -big_r:
            return True  # one cap holds the whole sphere
        live = live or caps[j, 3] + depth < big_r
    if not live:
        return False  # every cap shrunk to nothing: the whole sphere is free
    for j in range(ncaps):
        hj = caps[j, 3] + depth
        if hj >= big_r:
            continue  # shrunk to nothing: no circle
        rc = math.sqrt(big_r * big_r - hj * hj)
        m = _circle_covers(caps, ncaps, j, hj, rc, depth, lo, hi, True)
        if m < 0:
            continue  # inside another cap
        if m == 0:
            return False
        order = np.argsort(lo[:m])
        first = lo[order[0]]
        reach = hi[order[0]]
        for idx in range(1, m):
            if lo[order[idx]] >= reach:
                return False  # a gap (open covers: a shared end is not covered)
            reach = max(reach, hi[order[idx]])
        if not reach > first + two_pi:
            return False
    return True


@numba.njit(cache=True)
def is_free(caps: FloatArray, ncaps: int, ux: float, uy: float, uz: float, tau: float) -> bool:
    """Whether ``u`` lies in no open cap (within ``tau``)."""
    for q in range(ncaps):
        if caps[q, 0] * ux + caps[q, 1] * uy + caps[q, 2] * uz > caps[q, 3] + tau:
            return False
    return True


@numba.njit(cache=True)
def _arc_point(
    caps: FloatArray, big_r: float, cap: int, angle: float
) -> tuple[float, float, float]:
    nx, ny, nz, h = caps[cap, 0], caps[cap, 1], caps[cap, 2], caps[cap, 3]
    rc = math.sqrt(max(big_r * big_r - h * h, 0.0))
    e1x, e1y, e1z, e2x, e2y, e2z = _frame(nx, ny, nz)
    c = rc * math.cos(angle)
    s = rc * math.sin(angle)
    return h * nx + c * e1x + s * e2x, h * ny + c * e1y + s * e2y, h * nz + c * e1z + s * e2z


@numba.njit(cache=True)
def _arc_min(
    caps: FloatArray, big_r: float, arc: FloatArray, ax: float, ay: float, az: float
) -> float:
    """Return the least ``a · u`` over a free arc (``u`` on it, ``a`` a unit vector), exactly."""
    cap = int(arc[0])
    nx, ny, nz, h = caps[cap, 0], caps[cap, 1], caps[cap, 2], caps[cap, 3]
    rc = math.sqrt(max(big_r * big_r - h * h, 0.0))
    e1x, e1y, e1z, e2x, e2y, e2z = _frame(nx, ny, nz)
    # a . u(t) = h (a . n) + rc (A cos t + B sin t) = h (a . n) + rc M cos(t - mid)
    base = h * (ax * nx + ay * ny + az * nz)
    a = ax * e1x + ay * e1y + az * e1z
    b = ax * e2x + ay * e2y + az * e2z
    start = float(arc[1])
    end = float(arc[2])
    low = min(a * math.cos(start) + b * math.sin(start), a * math.cos(end) + b * math.sin(end))
    amp = math.sqrt(a * a + b * b)
    if amp > 0.0:
        # the minimum of the whole circle, at mid + pi, when the arc passes it
        t = (math.atan2(b, a) + math.pi - start) % (2.0 * math.pi)
        if t <= end - start:
            low = -amp
    return float(base + rc * low)


@numba.njit(cache=True)
def bounding_cap(
    caps: FloatArray, ncaps: int, arcs: FloatArray, big_r: float, tau: float
) -> tuple[float, float, float, float]:
    """Return a cap ``{u : a · u >= R cos_max}`` holding the whole free set, and its axis.

    The axis ``a`` is the free arcs' mean direction; ``cos_max`` is the
    least ``a · u / R`` over the arcs (exact per arc, :func:`_arc_min`), less a
    margin of the tolerance. Every boundary point of the free set lies on a
    free arc, so inside the cap: the rest of the sphere, connected, is then
    either wholly free or wholly covered, and one point of it tells which —
    the point opposite the axis. When it is free, the cap is the whole sphere
    (``cos_max = -1``). Without arcs (no caps) the whole sphere.
    """
    na = arcs.shape[0]
    if na == 0:
        return 0.0, 0.0, 1.0, -1.0
    ax = ay = az = 0.0
    for a in range(na):
        for m in range(9):
            ang = arcs[a, 1] + (arcs[a, 2] - arcs[a, 1]) * m / 8.0
            px, py, pz = _arc_point(caps, big_r, int(arcs[a, 0]), ang)
            ax += px
            ay += py
            az += pz
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if not norm > 1e-6 * big_r * 9 * na:
        # arcs all about the sphere: the middle of the first one
        mid = 0.5 * (arcs[0, 1] + arcs[0, 2])
        ax, ay, az = _arc_point(caps, big_r, int(arcs[0, 0]), mid)
        norm = math.sqrt(ax * ax + ay * ay + az * az)
    ax /= norm
    ay /= norm
    az /= norm
    if is_free(caps, ncaps, -big_r * ax, -big_r * ay, -big_r * az, tau):
        return ax, ay, az, -1.0
    low = big_r
    for a in range(na):
        low = min(low, _arc_min(caps, big_r, arcs[a], ax, ay, az))
    # points within tau of a cap's edge are free: reach that far beyond the arcs
    cos_max = (low - 2.0 * tau) / big_r - 1e-12
    return ax, ay, az, max(cos_max, -1.0)


@numba.njit(cache=True)
def _boundary_first(
    caps: FloatArray, ncaps: int, arcs: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Return copies of ``caps[:ncaps]`` with the caps owning free arcs first, and of ``arcs``."""
    rank = np.full(ncaps, -1, dtype=np.int64)
    m = 0
    for a in range(arcs.shape[0]):
        c = int(arcs[a, 0])
        if rank[c] < 0:
            rank[c] = m
            m += 1
    for c in range(ncaps):
        if rank[c] < 0:
            rank[c] = m
            m += 1
    ordered = np.empty((ncaps, 4))
    for c in range(ncaps):
        ordered[rank[c]] = caps[c]
    moved = arcs.copy()
    for a in range(arcs.shape[0]):
        moved[a, 0] = rank[int(arcs[a, 0])]
    return ordered, moved


@numba.njit(cache=True)
def sample_free(
    caps: FloatArray,
    ncaps: int,
    arcs: FloatArray,
    big_r: float,
    tau: float,
    rng: KernelSource,
) -> tuple[float, float, float]:
    """Draw a point of the free set, uniform by area (see the module docstring).

    The proposals fall near the free set, so the caps that bound it (those
    with a free arc) reject most of them: they are tested first
    (:func:`_boundary_first`), which changes no answer of :func:`is_free`.
    """
    caps, arcs = _boundary_first(caps, ncaps, arcs)
    na = arcs.shape[0]
    ax, ay, az, cos_max = bounding_cap(caps, ncaps, arcs, big_r, tau)
    e1x, e1y, e1z, e2x, e2y, e2z = _frame(ax, ay, az)
    for _ in range(TRIES):
        z = 1.0 - uniform(rng) * (1.0 - cos_max)
        phi = 2.0 * math.pi * uniform(rng)
        s = math.sqrt(max(1.0 - z * z, 0.0))
        c1 = s * math.cos(phi)
        c2 = s * math.sin(phi)
        ux = big_r * (z * ax + c1 * e1x + c2 * e2x)
        uy = big_r * (z * ay + c1 * e1y + c2 * e2y)
        uz = big_r * (z * az + c1 * e1z + c2 * e2z)
        if is_free(caps, ncaps, ux, uy, uz, tau):
            return ux, uy, uz
    # a sliver: uniform by length on the free arcs
    total = 0.0
    for a in range(na):
        h = caps[int(arcs[a, 0]), 3]
        total += (arcs[a, 2] - arcs[a, 1]) * math.sqrt(max(big_r * big_r - h * h, 0.0))
    pick = uniform(rng) * total
    for a in range(na):
        h = caps[int(arcs[a, 0]), 3]
        length = (arcs[a, 2] - arcs[a, 1]) * math.sqrt(max(big_r * big_r - h * h, 0.0))
        if pick <= length or a == na - 1:
            frac = min(max(pick / length, 0.0), 1.0) if length > 0 else 0.5
            return _arc_point(
                caps, big_r, int(arcs[a, 0]), arcs[a, 1] + frac * (arcs[a, 2] - arcs[a, 1])
            )
        pick -= length
    return _arc_point(caps, big_r, int(arcs[0, 0]), arcs[0, 1])
