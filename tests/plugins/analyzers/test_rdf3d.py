"""g(r) of 3D point sets: 1 for an uncorrelated pattern in a walled box, freud in a periodic one."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.geometry.domain import Box, PeriodicBox
from regopack.plugins.analyzers.rdf3d import rdf3d_histogram

freud = pytest.importorskip("freud", reason="freud-analysis is not installed")

SIDES = (10.0, 12.0, 14.0)


def _uniform(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, 1.0, (n, 3)) * np.array(SIDES)


def test_an_uncorrelated_pattern_in_a_box_has_g_one_up_to_the_shortest_side() -> None:
    # without the translation correction g falls to ~ (1 - r/a)(1 - r/b)(1 - r/c) at large r
    pts = _uniform(4000, 1)
    kind = (np.arange(4000) % 2).astype(np.int64)
    width = 0.5
    total, per = rdf3d_histogram(pts, kind, 2, 0.0, width, 18, Box(0, 10, 0, 12, 0, 14))
    r = width * (np.arange(18) + 0.5)
    n_pairs = 4000 * 3999 / 2 * 4 * np.pi * r * r * width / np.prod(SIDES)
    err = 1.0 / np.sqrt(n_pairs)  # Poisson error of g in a bin
    assert np.all(np.abs(total[2:] - 1.0) < 4 * err[2:] + 0.01)
    assert abs(np.average(total[8:], weights=n_pairs[8:]) - 1.0) < 0.01  # r from 4 to 9
    for p, q in ((0, 0), (0, 1), (1, 1)):
        assert abs(np.average(per[p, q, 8:], weights=n_pairs[8:]) - 1.0) < 0.02


def test_a_periodic_box_agrees_with_freud() -> None:
    pts = _uniform(1500, 2)
    box = PeriodicBox(0, 10, 0, 12, 0, 14)
    width, bins = 0.25, 16  # r < 4: below half the shortest side
    total, _ = rdf3d_histogram(pts, np.zeros(1500, dtype=np.int64), 1, 0.0, width, bins, box)
    fbox = freud.box.Box(*SIDES)
    rdf = freud.density.RDF(bins=bins, r_max=width * bins, normalization_mode="finite_size")
    rdf.compute(system=(fbox, pts - np.array(SIDES) / 2))
    np.testing.assert_allclose(total, rdf.rdf, rtol=1e-6)  # freud works in single precision


def test_the_packing_rdf_is_zero_below_contact_and_knows_its_expected_pairs(analysed3d) -> None:
    rdf = analysed3d["rdf3d"]
    near = rdf.tables["rdf_near"]
    assert np.all(near["total"][near["r"] < 1.0] == 0)  # no two centres closer than 1 µm
    assert rdf["n_points"] > 10 and rdf["window"] == [12.0, 12.0, 12.0]
    lo, hi = rdf["first_peak_fit_range"]
    assert 2.0 < lo < hi < 6.0
    # about 25 centres: the top of the curve is within its noise of a plateau
    assert rdf["first_peak_distinct"] is False and rdf["first_peak_r"] is None
    # d_min = 3: the near field reaches 5 d_min = 15, beyond the 12 µm window, as the far one
    cut = [n.split(":")[0] for n in rdf["notes"]]
    assert cut == ["near field cut at 12", "far field cut at 12"]
    # the pairs an uncorrelated pattern puts into the near field (they weigh the peak's fit)
    n = rdf["n_points"]
    r_max = near["r"][-1] + 0.5 * (near["r"][1] - near["r"][0])  # the near field's last edge
    expected = n * (n - 1) / 2 * 4 / 3 * np.pi * r_max**3 / 12.0**3
    assert rdf.analyzer.expected["near"].sum() == pytest.approx(expected)
