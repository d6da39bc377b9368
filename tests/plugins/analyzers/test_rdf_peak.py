"""The fitted first peak of g(r) and the pair-curve bins chosen from the counts."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.plugins.analyzers.rdf import Rdf, RdfConfig, rdf_histogram
from regopack.plugins.analyzers.rdf_peak import (
    DISTINCT_CONTRAST,
    MIN_ROUNDNESS,
    count_bins,
    first_peak,
    merge_bins,
)

R = np.arange(0.05, 10.0, 0.1)


def contact_peak(r: np.ndarray, r0: float) -> np.ndarray:
    """A smooth g(r): nothing below 1.5, a hump at ``r0``, 1 far away."""
    hump = 0.8 * np.exp(-((r - r0) ** 2) / (2 * 0.6**2))
    return np.where(r < 1.5, 0.0, 1.0 + hump - np.exp(-(((r - 1.5) / 0.5) ** 2)))


@pytest.mark.parametrize("per_bin", [30.0, 300.0])
def test_a_noisy_peak_is_recovered_within_its_reported_uncertainty(per_bin):
    """Poisson noise on a known g(r): the fitted peak lies within its error bars."""
    rng = np.random.default_rng(7)
    expected = per_bin * R  # pairs an uncorrelated pattern puts into each shell
    errors, sigmas, highest = [], [], []
    for _ in range(200):
        r0 = 3.27 + rng.uniform(-0.05, 0.05)
        g = rng.poisson(contact_peak(R, r0) * expected) / expected
        fit = first_peak(R, g, expected)
        assert fit is not None and fit.r_lo <= fit.r <= fit.r_hi
        errors.append(fit.r - r0)
        sigmas.append(fit.r_err)
        highest.append(fit.highest_bin_r - r0)
    errors, sigmas = np.abs(errors), np.asarray(sigmas)
    assert 0.55 <= np.mean(errors < sigmas) <= 0.9  # about 68 % within one standard error
    assert np.mean(errors < 2 * sigmas) >= 0.9
    assert np.mean(errors < 3 * sigmas) >= 0.97
    # the highest bin, the former estimate, is much farther off
    assert np.sqrt(np.mean(errors**2)) < 0.6 * np.sqrt(np.mean(np.square(highest)))


def test_a_smooth_peak_is_found_between_the_bins():
    fit = first_peak(R, contact_peak(R, 3.27), 1e12 * R)
    assert fit.r == pytest.approx(3.27, abs=0.01)
    assert fit.highest_bin_r == pytest.approx(3.25)
    assert fit.g == pytest.approx(contact_peak(np.array([3.27]), 3.27)[0], abs=0.02)


def test_degenerate_curves():
    assert first_peak(R, np.full(R.size, np.nan), R) is None
    few = first_peak(R[:3], np.array([0.0, 2.0, 1.0]), R[:3])
    assert few is not None and few.r == pytest.approx(R[1])
    flat = first_peak(R, np.ones(R.size), 100 * R)  # no peak: the error says so
    assert flat is not None and flat.r_err > 0.1 and not flat.distinct


def test_merged_bins_are_what_wider_bins_give():
    rng = np.random.default_rng(3)
    a, b, n = 60.0, 50.0, 800
    x, y = rng.uniform(0, a, n), rng.uniform(0, b, n)
    kind = np.zeros(n, dtype=np.int64)
    fine, _ = rdf_histogram(x, y, kind, 1, 0.0, 0.5, 24, a, b)
    wide, _ = rdf_histogram(x, y, kind, 1, 0.0, 2.0, 6, a, b)
    edges = 0.5 * np.arange(25)
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    merged = merge_bins(edges, fine, shell, 4)
    np.testing.assert_allclose(merged.g, wide, rtol=1e-12)
    np.testing.assert_array_equal(merged.edges, 2.0 * np.arange(7))
    # a short last group joins the one before it
    five = merge_bins(edges[:6], fine[:5], shell[:5], 2)
    assert five.r_lo.tolist() == [0.0, 1.0] and five.r_hi.tolist() == [1.0, 2.5]
    assert count_bins(25.0, 100, 24) == 4 and count_bins(0.0, 100, 24) == 24
    assert count_bins(5.0, 0, 24) == 1


@pytest.fixture(scope="module")
def packing():
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    resolved = resolve_scene(load_scene("small", ["count=600"]), default_registry(autoload=False))
    return run_scene(resolved, None).packing


def test_the_analyzer_reports_the_top_and_the_pair_bins(packing):
    rdf = Rdf(RdfConfig(far=(20.0, 50.0))).compute(packing, {})
    res = rdf.results()
    lo, hi = res["first_peak_fit_range"]
    assert 0.0 < lo < hi < 10.0 and res["first_peak_g"] > 1.0
    # 412 centres: the top of the curve is not told from a plateau within its noise
    assert res["first_peak_distinct"] is False and res["first_peak_contrast"] < DISTINCT_CONTRAST
    assert res["first_peak_r"] is None and res["first_peak_r_err"] is None
    assert res["first_plateau"] == [lo, hi]
    assert 0.0 < res["first_peak_highest_bin_r"] < 10.0  # a noisy bin, maybe far from the fit
    widths = res["pair_bins"]["near"]
    assert min(widths.values()) >= 0.1 and widths["others-others"] > widths["pyroxene-feldspar"]
    near, fine = rdf.curves["near"], rdf.curves_fine["near"]
    assert np.array_equal(near["total"], fine["total"]) and set(near) == {"r", "total"}
    # a merged pair curve has bins of its own, each the shell-weighted mean of its fine bins
    edges = 0.1 * np.arange(101)
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    curve = rdf.pair_curves["near"]["pyroxene-feldspar"]
    k = round((curve.r_hi[0] - curve.r_lo[0]) / 0.1)
    assert k > 1 and curve.r_lo[0] == 0.0 and curve.r_hi[-1] == pytest.approx(10.0)
    np.testing.assert_array_equal(curve.r_hi[:-1], curve.r_lo[1:])  # no gap, no overlap
    j = len(curve.g) - 2  # well past the contact peak
    cut = slice(round(curve.r_lo[j] / 0.1), round(curve.r_hi[j] / 0.1))
    expected = np.average(fine["pyroxene-feldspar"][cut], weights=shell[cut])
    assert curve.g[j] == pytest.approx(expected, rel=1e-12)
    unmerged = Rdf(RdfConfig(far=(20.0, 50.0), min_pairs_per_bin=0)).compute(packing, {})
    for key, pair in unmerged.pair_curves["near"].items():
        np.testing.assert_array_equal(pair.g, fine[key])
    assert set(unmerged.results()["pair_bins"]["near"].values()) == {0.1}


def test_a_merged_pair_bin_holds_g_only_where_its_pairs_are(packing):
    """No merged bin shows pairs closer than the closest pair of its minerals.

    The merged value used to be repeated over every fine bin, so that the
    table showed g > 0 at r = 0.05 for a pair of rare minerals whose closest
    centres are some 2 µm apart.
    """
    from regopack.plugins.analyzers.common import interior_mask

    rdf = Rdf(RdfConfig(far=(20.0, 50.0))).compute(packing, {})
    sel = interior_mask(packing, rdf.results()["interior_margin"])
    xy, mineral = packing.centre[sel], packing.mineral[sel]
    table = rdf.tables()["rdf_near_pairs"]
    assert list(table) == ["mineral_a", "mineral_b", "r_lo", "r_hi", "r", "g"]
    merged = 0
    pairs = np.unique(np.column_stack([table["mineral_a"], table["mineral_b"]]), axis=0)
    for a, b in pairs.tolist():
        rows = (table["mineral_a"] == a) & (table["mineral_b"] == b)
        d = np.hypot(*(xy[mineral == a][:, None] - xy[mineral == b][None]).transpose(2, 0, 1))
        closest = float(np.min(d[d > 0])) if d.size else np.inf
        r_lo, r_hi, g = table["r_lo"][rows], table["r_hi"][rows], table["g"][rows]
        assert np.all(g[r_hi <= closest] == 0.0)  # no pair that close: nothing there
        assert np.all(r_hi[g > 0] > closest)  # a bin with pairs reaches the closest pair
        merged += int(np.max(r_hi - r_lo) > 0.15)
    assert merged > 5  # most pairs of this packing are merged
    others = (table["mineral_a"] == 5) & (table["mineral_b"] == 5)
    assert table["r_lo"][others][0] == 0.0 and table["r_hi"][others][0] > 1.0


def contact_plateau(r: np.ndarray) -> np.ndarray:
    """A g(r) that rises from contact to 1.3 and stays there."""
    return np.clip((r - 2.0) / 1.5, 0.0, 1.3)


def flat_topped_hump(r: np.ndarray) -> np.ndarray:
    """A g(r) like the one of the dem scene: a flat top from 4 to 5.4, then down to about 1."""
    return np.interp(r, [2.2, 4.0, 5.4, 6.0, 10.0], [0.0, 1.25, 1.25, 1.1, 1.05])


@pytest.mark.parametrize("shape", [contact_plateau, flat_topped_hump])
def test_a_plateau_gives_no_peak_however_well_it_is_sampled(shape):
    rng = np.random.default_rng(2)
    for per_bin in (100.0, 3000.0, 1e5):
        expected = per_bin * R
        fits = [first_peak(R, rng.poisson(shape(R) * expected) / expected, expected, 0)]
        fits.append(first_peak(R, shape(R), 1e12 * R, 0))  # no noise at all
        for fit in fits:
            assert fit is not None and not fit.distinct, (per_bin, fit)
            assert fit.r_lo < 4.5 and fit.r_hi > 5.0  # the plateau's extent
    noiseless = first_peak(R, flat_topped_hump(R), 1e12 * R, 0)
    assert noiseless.contrast > 10 and noiseless.roundness < MIN_ROUNDNESS  # high, but flat


@pytest.mark.parametrize("per_bin", [300.0, 3000.0])
def test_a_real_peak_is_still_distinct(per_bin):
    rng = np.random.default_rng(4)
    expected = per_bin * R
    fits = [
        first_peak(R, rng.poisson(contact_peak(R, 3.27) * expected) / expected, expected, 0)
        for _ in range(40)
    ]
    assert np.mean([f.distinct for f in fits]) >= 0.85
    assert all(f.roundness > MIN_ROUNDNESS for f in fits if f.distinct)


def test_a_near_monodisperse_packing_has_a_distinct_contact_peak():
    import regopack

    scene = regopack.scene(
        "small",
        size={"kind": "uniform", "d_min": 2.0, "d_max": 2.5},
        domain__width=100.0,
        domain__height=100.0,
    )
    rdf = Rdf().compute(regopack.pack(scene, verify=False), {})
    res = rdf.results()
    assert res["first_peak_distinct"] is True and res["first_plateau"] is None
    assert 2.2 < res["first_peak_r"] < 2.6 and 0 < res["first_peak_r_err"] < 0.1
    assert res["first_peak_contrast"] > DISTINCT_CONTRAST


def test_no_pair_at_all_gives_no_peak():
    r = np.arange(0.05, 10.0, 0.1)
    assert first_peak(r, np.zeros_like(r), np.full_like(r, 5.0)) is None
    assert first_peak(r, np.full_like(r, np.nan), np.full_like(r, 5.0)) is None
    assert first_peak(r, np.ones_like(r), np.zeros_like(r)) is None


def test_few_bins_give_half_their_range_as_the_error():
    r = np.array([3.05, 3.15, 3.25])
    fit = first_peak(r, np.array([1.0, 2.0, 1.5]), np.full(3, 100.0))
    assert fit is not None and not fit.fitted
    assert fit.r_err == pytest.approx(0.1)
    assert all(isinstance(v, float) for v in (fit.r, fit.r_err, fit.r_lo, fit.r_hi))


def test_the_error_covers_a_peak_that_jumps_between_two_maxima():
    """Two humps of equal height: the fitted peak moves between them with the noise."""
    r = np.arange(0.05, 10.0, 0.1)
    expected = 40 * r
    shape = 1 + 0.6 * np.exp(-((r - 3.5) ** 2) / 0.08) + 0.6 * np.exp(-((r - 4.6) ** 2) / 0.08)
    rng = np.random.default_rng(5)
    fits = [first_peak(r, rng.poisson(shape * expected) / expected, expected) for _ in range(40)]
    spread = float(np.std([f.r for f in fits], ddof=1))
    assert spread > 0.3  # the two maxima do compete
    median_err = float(np.median([f.r_err for f in fits]))
    assert median_err > 0.5 * spread
    no_resampling = [
        first_peak(r, rng.poisson(shape * expected) / expected, expected, resamples=0)
        for _ in range(10)
    ]
    assert float(np.median([f.r_err for f in no_resampling])) < median_err


def test_the_reported_pair_width_is_the_widest_merged_bin(packing):
    rdf = Rdf(RdfConfig(far=(20.0, 50.0))).compute(packing, {})
    widths = rdf.results()["pair_bins"]["near"]
    for key, width in widths.items():
        curve = rdf.pair_curves["near"][key]
        assert width == pytest.approx(float(np.max(curve.r_hi - curve.r_lo)), rel=1e-12), key
        assert round(width / 0.1) * 0.1 == width  # a whole number of fine bins
