"""Contacts of polygons (and disks) at a tolerance, by the bow-shaped model (SPEC §5).

Each outline grows by ``tol / 2`` along its edge normals; two particles are in
contact at ``tol`` when their grown outlines overlap, and each contact region
gets its area, width (longest chord), normal and the equivalent circular
segment (:mod:`regopack.plugins.analyzers.segment`). Every pair gets, once, its
*threshold*: the tolerance above which it is in contact (compiled in
:mod:`regopack.plugins.analyzers.contact_kernel`); two disks are measured
exactly. Rounded outlines are measured on circumscribed polygons.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    ROUNDED_CONTACT_ERROR,
    FoundContacts,
    periodic_images,
    rounded_as_polygons,
)
from regopack.plugins.analyzers.segment import equivalent_segment

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _disk_mask(packing: Packing) -> NDArray[np.bool_]:
    """Particles that are disks: one vertex at the centre, rounded."""
    counts = np.diff(packing.offsets)
    return np.asarray((counts == 1) & (packing.rounding_radius > 0), dtype=np.bool_)


def _lens(
    ci: FloatArray, cj: FloatArray, ri: FloatArray, rj: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Overlap of two disks, exactly: area, common chord, chord midpoint, unit normal i -> j."""
    delta = cj - ci
    d = np.hypot(delta[:, 0], delta[:, 1])
    u = delta / d[:, None]
    # distance from centre i to the chord, and half the chord
    a = (d * d + ri * ri - rj * rj) / (2.0 * d)
    half = np.sqrt(np.maximum(ri * ri - a * a, 0.0))
    area = (
        ri * ri * np.arccos(np.clip(a / ri, -1.0, 1.0))
        - a * half
        + rj * rj * np.arccos(np.clip((d - a) / rj, -1.0, 1.0))
        - (d - a) * half
    )
    mid = ci + a[:, None] * u
    return area, 2.0 * half, mid[:, 0], mid[:, 1], u[:, 0], u[:, 1]


def _one_image_per_pair(
    pi: IntArray, pj: IntArray, origin: IntArray, n: int
) -> tuple[IntArray, IntArray]:
    """Keep one candidate pair per pair of original particles, with the first one real.

    ``pi, pj`` index particles and their ghosts (``>= n``); the pair kept for
    ``(a, b)``, ``a < b``, has ``a`` real and ``b`` real or a ghost of ``b``.
    """
    oi, oj = origin[pi], origin[pj]
    swap = oi > oj
    pi, pj = np.where(swap, pj, pi), np.where(swap, pi, pj)
    oi, oj = np.minimum(oi, oj), np.maximum(oi, oj)
    keep = (oi != oj) & (pi < n)
    pi, pj, oi, oj = pi[keep], pj[keep], oi[keep], oj[keep]
    _, first = np.unique(oi * n + oj, return_index=True)
    first.sort()
    return pi[first], pj[first]


def find_contacts(packing: Packing, tol: float, tol_max: float) -> FoundContacts:
    """Find the candidate pairs, their thresholds, and the regions at ``tol``."""
    from regopack.plugins.analyzers import contact_kernel as ck

    s_max = 0.5 * tol_max
    # in a periodic domain the particles near a side get ghost copies one
    # period away; ``origin`` maps every (ghost) particle to its original
    # rounded outlines (disks) are measured on circumscribed polygons within
    # ROUNDED_CONTACT_ERROR * tol of the true outline
    sharp = rounded_as_polygons(packing, ROUNDED_CONTACT_ERROR * tol)
    work, origin = sharp, np.arange(packing.n_particles, dtype=np.int64)
    if packing.domain.periodic and packing.n_placed:
        pad = 2.0 * float(np.max(sharp.circumradius[packing.placed]) + 2.0 * s_max)
        work, origin = periodic_images(sharp, pad)
    placed = np.flatnonzero(work.placed)
    offsets = np.ascontiguousarray(work.offsets, dtype=np.int64)
    vertices = np.ascontiguousarray(work.vertices, dtype=np.float64)
    nx, ny, mx, my, mitre = ck.edge_normals_and_mitres(vertices, offsets)
    circum = np.ascontiguousarray(work.circumradius, dtype=np.float64)
    centre = np.ascontiguousarray(np.nan_to_num(work.centre), dtype=np.float64)
    reach = circum[placed] + s_max * mitre[placed]
    bounds = work.domain.bounds()
    if work is not sharp:
        bounds = bounds + np.array([-1.0, 1.0, -1.0, 1.0]) * pad
    li, lj = ck.candidate_pairs(np.ascontiguousarray(centre[placed]), reach, bounds)
    pi = placed[li]
    pj = placed[lj]
    if work is not sharp:
        pi, pj = _one_image_per_pair(pi, pj, origin, packing.n_particles)
    thr = ck.thresholds(pi, pj, centre, vertices, offsets, nx, ny, mx, my, circum)
    # two disks: the exact half gap between the circles
    disk = _disk_mask(packing)
    both = disk[origin[pi]] & disk[origin[pj]]
    rho = packing.rounding_radius
    if both.any():
        d = np.hypot(*(centre[pj[both]] - centre[pi[both]]).T)
        thr[both] = 0.5 * (d - rho[origin[pi[both]]] - rho[origin[pj[both]]])
    keep = thr < s_max
    pi, pj = pi[keep], pj[keep]
    pairs = np.column_stack([origin[pi], origin[pj]]).astype(np.int64)
    threshold = 2.0 * thr[keep]  # as a tolerance
    at_tol = threshold < tol
    ci = pi[at_tol].copy()
    cj = pj[at_tol].copy()
    area, width, px, py, unx, uny = ck.contact_regions(
        ci, cj, 0.5 * tol, centre, vertices, offsets, nx, ny, mx, my
    )
    lens = disk[origin[ci]] & disk[origin[cj]]
    if lens.any():
        area[lens], width[lens], px[lens], py[lens], unx[lens], uny[lens] = _lens(
            centre[ci[lens]],
            centre[cj[lens]],
            rho[origin[ci[lens]]] + 0.5 * tol,
            rho[origin[cj[lens]]] + 0.5 * tol,
        )
    ci, cj = origin[ci], origin[cj]
    if work is not sharp:
        px, py = packing.domain.wrap(np.column_stack([px, py])).T
    ok = (area > 0.0) & (width > 0.0)
    theta = np.zeros_like(area)
    radius = np.zeros_like(area)
    depth = np.zeros_like(area)
    if ok.any():
        theta[ok], radius[ok], depth[ok] = equivalent_segment(area[ok], width[ok])
    columns = {
        "i": ci[ok],
        "j": cj[ok],
        "area": area[ok],
        "width": width[ok],
        "radius": radius[ok],
        "depth": depth[ok],
        "theta": theta[ok],
    }
    normal = np.column_stack([unx[ok], uny[ok]])
    return FoundContacts(pairs, threshold, columns, normal, np.column_stack([px[ok], py[ok]]))
