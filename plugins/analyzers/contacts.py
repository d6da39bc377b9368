"""Contacts and the equivalent bow-shaped (circular-segment) model (SPEC §5)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    ROUNDED_CONTACT_ERROR,
    contact_tolerances,
    eta_of,
    interior_margin,
    interior_mask,
    periodic_images,
    rounded_as_polygons,
)
from regopack.plugins.analyzers.segment import equivalent_segment
from regopack.registry.interfaces import Analyzer

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class ContactsConfig(BaseModel):
    """Parameters of the contact analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    tol: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Contact tolerance tol (length unit): each outline grows by tol/2 along its normals; "
            "default: d_min / 40 (0.05 at the built-in scenes' d_min = 2)."
        ),
    )
    tol_max: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Largest tolerance of later sweeps: pairs that touch up to tol_max are kept; "
            "default: the larger of d_min / 4 (0.5 at d_min = 2) and tol."
        ),
    )
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )

    @model_validator(mode="after")
    def _check(self) -> ContactsConfig:
        if self.tol is not None and self.tol_max is not None and self.tol_max < self.tol:
            raise ValueError(f"tol_max ({self.tol_max}) must be at least tol ({self.tol})")
        return self


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


class Contacts(Analyzer):
    """Contact pairs, their thresholds, and the bow model of every contact at ``tol``.

    After :meth:`compute`, ``pairs`` holds every pair (``i < j``, particle
    indices of the packing) whose grown outlines overlap at ``tol_max`` and
    ``threshold`` the tolerance above which each pair is in contact; the
    properties ``i, j, area, width, radius, depth, normal, point`` describe the
    contacts at ``tol``.
    """

    name = "contacts"

    def __init__(self, config: ContactsConfig | None = None) -> None:
        self.config = config or ContactsConfig()
        self._asked = self.config
        self._done = False

    @property
    def tol(self) -> float:
        """The contact tolerance used: ``config.tol``, or its default for the packing."""
        self._need()
        assert self.config.tol is not None
        return float(self.config.tol)

    @property
    def tol_max(self) -> float:
        """The largest tolerance kept: ``config.tol_max``, or its default for the packing."""
        self._need()
        assert self.config.tol_max is not None
        return float(self.config.tol_max)

    # -- computation -------------------------------------------------------
    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Find candidate pairs, their thresholds, and the regions at ``tol``."""
        from regopack.plugins.analyzers import contact_kernel as ck

        tol, tol_max = contact_tolerances(self._asked.tol, self._asked.tol_max, packing)
        # after compute, the config holds the tolerances used
        self.config = cfg = self._asked.model_copy(update={"tol": tol, "tol_max": tol_max})
        self.packing = packing
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
        self.pairs = np.column_stack([origin[pi], origin[pj]]).astype(np.int64)
        self.threshold = 2.0 * thr[keep]  # as a tolerance
        at_tol = self.threshold < tol
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
            px, py = packing.domain.wrap(np.column_stack([px, py])).T  # type: ignore[attr-defined]
        ok = (area > 0.0) & (width > 0.0)
        theta = np.zeros_like(area)
        radius = np.zeros_like(area)
        depth = np.zeros_like(area)
        if ok.any():
            theta[ok], radius[ok], depth[ok] = equivalent_segment(area[ok], width[ok])
        self._i, self._j = ci[ok], cj[ok]
        self._area, self._width = area[ok], width[ok]
        self._theta, self._radius, self._depth = theta[ok], radius[ok], depth[ok]
        self._point = np.column_stack([px[ok], py[ok]])
        self._normal = np.column_stack([unx[ok], uny[ok]])
        self.margin = interior_margin(packing, cfg.margin)
        self.interior = interior_mask(packing, self.margin)
        self._done = True
        return self

    def _need(self) -> None:
        if not self._done:
            raise RuntimeError("call compute() first")

    # -- results -------------------------------------------------------------
    @property
    def i(self) -> IntArray:
        """First particle of each contact at ``tol``."""
        self._need()
        return np.asarray(self._i, dtype=np.int64)

    @property
    def j(self) -> IntArray:
        """Second particle of each contact at ``tol``."""
        self._need()
        return np.asarray(self._j, dtype=np.int64)

    @property
    def area(self) -> FloatArray:
        """Contact area A_c (area of the overlap of the grown outlines)."""
        self._need()
        return self._area

    @property
    def width(self) -> FloatArray:
        """Contact width b_c (longest chord of the contact region)."""
        self._need()
        return self._width

    @property
    def radius(self) -> FloatArray:
        """Radius R_c of the equivalent circular segment."""
        self._need()
        return self._radius

    @property
    def depth(self) -> FloatArray:
        """Depth delta of the equivalent circular segment."""
        self._need()
        return self._depth

    @property
    def theta(self) -> FloatArray:
        """Central angle of the equivalent circular segment."""
        self._need()
        return self._theta

    @property
    def normal(self) -> FloatArray:
        """Unit contact normal (perpendicular to the chord, from i to j)."""
        self._need()
        return self._normal

    @property
    def point(self) -> FloatArray:
        """Midpoint of the chord of each contact."""
        self._need()
        return self._point

    def count_per_particle(self, tol: float | None = None) -> IntArray:
        """Count the contacts of every particle at ``tol`` (default: the analyzer's tol)."""
        self._need()
        if tol is None:
            i, j = self._i, self._j
        else:
            if tol > self.tol_max:
                raise ValueError(f"tol = {tol} exceeds tol_max = {self.tol_max}")
            sel = self.threshold < tol
            i, j = self.pairs[sel, 0], self.pairs[sel, 1]
        n = self.packing.n_particles
        return np.bincount(i, minlength=n) + np.bincount(j, minlength=n)

    def results(self) -> dict[str, Any]:
        """Return scalars: contacts, tol, medians of A_c, b_c, R_c, delta, share of delta < tol."""
        self._need()
        n = int(self._area.shape[0])

        def med(a: FloatArray) -> float | None:
            return float(np.median(a)) if a.shape[0] else None

        return {
            "tol": self.tol,
            "tol_max": self.tol_max,
            "eta": eta_of(self.packing),
            "interior_margin": self.margin,
            "n_contacts": n,
            "n_candidate_pairs": int(self.pairs.shape[0]),
            "median_area": med(self._area),
            "median_width": med(self._width),
            "median_radius": med(self._radius),
            "median_depth": med(self._depth),
            "mean_depth_over_width": float(np.mean(self._depth / self._width)) if n else None,
            "share_depth_below_tol": float(np.mean(self._depth < self.tol)) if n else None,
        }

    def tables(self) -> dict[str, dict[str, Any]]:
        """Per-contact table."""
        self._need()
        return {
            "contacts": {
                "i": self._i,
                "j": self._j,
                "area": self._area,
                "width": self._width,
                "radius": self._radius,
                "depth": self._depth,
                "theta": self._theta,
                "normal_x": self._normal[:, 0],
                "normal_y": self._normal[:, 1],
                "point_x": self._point[:, 0],
                "point_y": self._point[:, 1],
            }
        }
