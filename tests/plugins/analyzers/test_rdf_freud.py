"""g(r) of a periodic packing against ``freud.density.RDF`` on the same centres and bins.

Both estimate g(r) from the same pairs of one point set, so they must agree to
far better than the statistical error; the test asserts the stated criterion
(every bin within 3 Poisson errors, ``g / sqrt(pairs)``) and, more strictly,
that the pair counts and the normalisations match.

Normalisations. regopack divides the unordered pair count of a bin by
``N (N - 1) / 2`` pairs of a uniform pattern, ``g = 2 A n / (N (N - 1) S)``
(``A`` the box area, ``S`` the shell area). freud's default ``"exact"`` mode
divides the ordered count ``2 n`` by ``N`` query points times the density
``N / A``, ``g = 2 A n / (N² S)``, which tends to ``(N - 1) / N`` at large r.
So ``g_regopack = N / (N - 1) g_freud`` for the total curve and for a mineral
with itself; between two different minerals A and B (freud's query points A,
points B, disjoint sets) both divide by ``N_A N_B`` and agree without a factor.
"""

from __future__ import annotations

import numpy as np
import pytest

from regopack.packing.core import Packing
from regopack.plugins.analyzers.rdf import Rdf, RdfConfig
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

freud = pytest.importorskip("freud", reason="freud-analysis is not installed")

R_MAX = 50.0
"""Largest r compared; below half the shorter side (120) of the box."""

BINS = {"near": (0.0, R_MAX, 1.0), "far": (10.0, R_MAX + 5.0, 2.5)}
"""The two curves regopack computes: ``(lo, hi, bin width)``."""

SIGMAS = 3.0
"""Largest deviation allowed per bin, in Poisson errors ``g / sqrt(pairs)``."""


@pytest.fixture(scope="module")
def packing() -> Packing:
    registry = default_registry(autoload=False)
    scene = resolve_scene(
        load_scene(
            "small",
            [
                "domain.kind=periodic",
                "domain.width=150",
                "domain.height=120",
                "domain.center=[10.0, -5.0]",
                "count=400",
            ],
        ),
        registry,
    )
    return run_scene(scene).packing


@pytest.fixture(scope="module")
def curves(packing) -> dict:
    (lo_n, hi_n, w_n), (lo_f, hi_f, w_f) = BINS["near"], BINS["far"]
    cfg = RdfConfig(
        near=(lo_n, hi_n), near_bin=w_n, far=(lo_f, hi_f), far_bin=w_f, min_pairs_per_bin=0
    )
    rdf = Rdf(cfg).compute(packing, {})
    assert rdf.results()["window_kind"] == "periodic"
    assert rdf.results()["n_points"] == packing.n_placed
    return rdf.curves_fine  # the curves at the bins asked for, the pairs' too


def freud_rdf(packing: Packing, lo: float, hi: float, width: float, query=None, points=None):
    """freud's g(r) and ordered pair counts of the placed centres (or two subsets)."""
    d = packing.domain
    box = freud.box.Box(d.width, d.height, is2D=True)
    cx, cy = 0.5 * (d.xmin + d.xmax), 0.5 * (d.ymin + d.ymax)
    centre = packing.centre[packing.placed]
    xyz = np.column_stack([centre[:, 0] - cx, centre[:, 1] - cy, np.zeros(len(centre))])
    xyz = box.wrap(xyz)
    pts = xyz if points is None else xyz[points]
    qry = None if query is None else xyz[query]
    bins = round((hi - lo) / width)
    rdf = freud.density.RDF(bins=bins, r_max=lo + bins * width, r_min=lo)
    rdf.compute((box, pts), query_points=qry)
    np.testing.assert_allclose(rdf.bin_centers, lo + width * (np.arange(bins) + 0.5))
    return np.asarray(rdf.rdf, dtype=float), np.asarray(rdf.bin_counts, dtype=float)


def compare(g_ours, g_freud, pairs, factor):
    """Deviations in Poisson errors; checks the stated criterion and returns the largest."""
    expected = factor * g_freud
    assert g_ours.shape == expected.shape
    empty = pairs == 0
    np.testing.assert_array_equal(g_ours[empty], 0.0)
    sigma = expected[~empty] / np.sqrt(pairs[~empty])
    dev = np.abs(g_ours[~empty] - expected[~empty]) / sigma
    assert dev.max() <= SIGMAS, f"largest deviation {dev.max():.3g} sigma"
    return float(dev.max())


@pytest.mark.parametrize("field", list(BINS))
def test_total_g_matches_freud(packing, curves, field):
    lo, hi, width = BINS[field]
    ours = curves[field]
    g_freud, ordered = freud_rdf(packing, lo, hi, width)
    n = packing.n_placed
    pairs = ordered / 2.0  # freud counts every pair from both ends
    assert pairs.sum() > 10_000
    compare(ours["total"], g_freud, pairs, n / (n - 1.0))
    # stricter: the same pairs in every bin, the same normalisation to single precision
    area = packing.domain.area
    edges = lo + width * np.arange(len(pairs) + 1)
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    our_pairs = ours["total"] * n * (n - 1.0) / 2.0 * shell / area
    np.testing.assert_allclose(our_pairs, np.round(our_pairs), atol=1e-6)
    np.testing.assert_array_equal(np.round(our_pairs), pairs)
    np.testing.assert_allclose(ours["total"], n / (n - 1.0) * g_freud, rtol=1e-6, atol=0)


def test_mineral_pairs_match_freud(packing, curves):
    lo, hi, width = BINS["near"]
    names = packing.mineral_names
    mineral = packing.mineral[packing.placed]
    a, b = 0, 1  # the two most frequent minerals of the scene
    in_a, in_b = np.flatnonzero(mineral == a), np.flatnonzero(mineral == b)
    assert min(len(in_a), len(in_b)) > 80
    # A with B: disjoint sets, both normalise by N_A N_B
    g_ab, counts_ab = freud_rdf(packing, lo, hi, width, query=in_a, points=in_b)
    compare(curves["near"][f"{names[a]}-{names[b]}"], g_ab, counts_ab, 1.0)
    np.testing.assert_allclose(curves["near"][f"{names[a]}-{names[b]}"], g_ab, rtol=1e-6)
    # A with itself: N_A / (N_A - 1), as for the total
    g_aa, counts_aa = freud_rdf(packing, lo, hi, width, points=in_a)
    na = len(in_a)
    compare(curves["near"][f"{names[a]}-{names[a]}"], g_aa, counts_aa / 2.0, na / (na - 1.0))
    np.testing.assert_allclose(
        curves["near"][f"{names[a]}-{names[a]}"], na / (na - 1.0) * g_aa, rtol=1e-6
    )
