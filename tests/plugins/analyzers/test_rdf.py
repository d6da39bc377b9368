"""Radial distribution function of 2D and 3D point sets and packings.

In 3D: 1 for an uncorrelated pattern in a walled box, freud in a periodic one.
"""

from __future__ import annotations

import numpy as np
import pytest

from regopack.geometry.domain import Box, Circle, ConvexPolygon, PeriodicBox, PeriodicRectangle
from regopack.plugins.analyzers.rdf import Rdf, RdfConfig
from regopack.plugins.analyzers.rdf_histogram import covariogram, rdf3d_histogram, rdf_histogram
from regopack.testing import packing_from_polygons


def test_uniform_points_give_one_at_every_r() -> None:
    a, b = 300.0, 200.0
    curves = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        n = 4000
        x = rng.uniform(0, a, n)
        y = rng.uniform(0, b, n)
        total, _ = rdf_histogram(x, y, np.zeros(n, dtype=np.int64), 1, 0.0, 5.0, 36, a, b)
        curves.append(total)
    mean = np.mean(curves, axis=0)
    err = np.std(curves, axis=0, ddof=1) / np.sqrt(len(curves))
    assert np.all(np.abs(mean - 1.0) < 4 * err + 0.01)


def test_matches_brute_force_reference() -> None:
    rng = np.random.default_rng(1)
    a, b = 50.0, 40.0
    n = 300
    x, y = rng.uniform(0, a, n), rng.uniform(0, b, n)
    kind = rng.integers(0, 3, n).astype(np.int64)
    lo, width, bins = 1.0, 0.5, 30
    total, per = rdf_histogram(x, y, kind, 3, lo, width, bins, a, b)
    dx = x[:, None] - x[None, :]
    dy = y[:, None] - y[None, :]
    d = np.hypot(dx, dy)
    w = 1.0 / ((a - np.abs(dx)) * (b - np.abs(dy)))
    iu = np.triu_indices(n, 1)
    edges = lo + width * np.arange(bins + 1)
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    h, _ = np.histogram(d[iu], bins=edges, weights=w[iu])
    ref = h * (a * b) ** 2 / (n * (n - 1) / 2 * shell)
    assert np.allclose(total, ref, rtol=1e-10)
    sel = (kind[iu[0]] == 0) & (kind[iu[1]] == 2) | (kind[iu[0]] == 2) & (kind[iu[1]] == 0)
    h02, _ = np.histogram(d[iu][sel], bins=edges, weights=w[iu][sel])
    n0, n2 = np.sum(kind == 0), np.sum(kind == 2)
    assert np.allclose(per[0, 2], h02 * (a * b) ** 2 / (n0 * n2 * shell), rtol=1e-10)


def test_packing_rdf_has_a_contact_peak() -> None:
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    resolved = resolve_scene(load_scene("small", ["count=600"]), default_registry(autoload=False))
    packing = run_scene(resolved, None).packing
    rdf = Rdf(RdfConfig(far=(20.0, 50.0), far_bin=2.0)).compute(packing, {})
    near = rdf.curves["near"]
    assert near["total"][near["r"] < 1.0].max(initial=0.0) == 0.0  # no two centres that close
    assert np.nanmax(near["total"]) > 1.5
    assert "pyroxene-pyroxene" in rdf.pair_curves["near"]
    assert "pyroxene-pyroxene" in rdf.curves_fine["near"]


def test_bad_range_names_field() -> None:
    with pytest.raises(ValueError, match="near"):
        RdfConfig(near=(5.0, 1.0))


def _uniform_in(domain, n, rng):
    """``n`` uniform points inside ``domain`` (rejection from its box)."""
    b = domain.bounds()
    pts = np.empty((0, 2))
    while len(pts) < n:
        cand = rng.uniform([b[0], b[2]], [b[1], b[3]], size=(2 * n, 2))
        pts = np.concatenate([pts, cand[domain.contains(cand)]])
    return pts[:n]


@pytest.mark.parametrize(
    "domain",
    [
        Circle(3.0, -2.0, 150.0),
        ConvexPolygon(((-150.0, -100.0), (160.0, -120.0), (120.0, 130.0), (-130.0, 90.0))),
    ],
    ids=["circle", "polygon"],
)
def test_uniform_points_give_one_in_circle_and_polygon_windows(domain) -> None:
    curves = []
    for seed in range(6):
        pts = _uniform_in(domain, 4000, np.random.default_rng(seed))
        n = len(pts)
        total, _ = rdf_histogram(
            pts[:, 0].copy(),
            pts[:, 1].copy(),
            np.zeros(n, dtype=np.int64),
            1,
            0.0,
            10.0,
            24,
            domain.width,
            domain.height,
            window=domain,
        )
        curves.append(total)
    mean = np.mean(curves, axis=0)
    err = np.std(curves, axis=0, ddof=1) / np.sqrt(len(curves))
    assert np.all(np.abs(mean - 1.0) < 4 * err + 0.01)


def test_circle_covariogram_is_exact_and_polygon_covariogram_matches_shapely() -> None:
    c = Circle(0.0, 0.0, 2.0)
    assert covariogram(c, np.array([0.0]))[0] == pytest.approx(c.area)
    assert covariogram(c, np.array([4.0]))[0] == pytest.approx(0.0, abs=1e-12)
    sq = ConvexPolygon(((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)))
    # unit square: mean of (1 - r|cos|)(1 - r|sin|) over directions = 1 - 4r/pi + r^2/pi
    r = 0.3
    assert covariogram(sq, np.array([r]))[0] == pytest.approx(
        1 - 4 * r / np.pi + r**2 / np.pi, rel=1e-3
    )


def test_periodic_window_counts_pairs_through_the_sides() -> None:
    domain = PeriodicRectangle(0.0, 100.0, 0.0, 80.0)
    rng = np.random.default_rng(3)
    n = 3000
    centres = rng.uniform([0, 0], [100, 80], size=(n, 2))
    sq = 0.01 * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]])
    packing = packing_from_polygons([sq + c for c in centres], domain=domain)
    rdf = Rdf(
        RdfConfig(near=(0.0, 30.0), near_bin=2.0, far=(30.0, 39.0), far_bin=3.0, per_mineral=False)
    )
    rdf.compute(packing, {})
    g = rdf.curves["near"]["total"]
    assert np.all(np.abs(g - 1.0) < 0.08)
    # a pair straddling a side is at its short distance
    two = packing_from_polygons([sq + (1.0, 40.0), sq + (99.0, 40.0)], domain=domain)
    rdf = Rdf(
        RdfConfig(near=(0.0, 4.0), near_bin=1.0, far=(4.0, 5.0), far_bin=1.0, per_mineral=False)
    )
    rdf.compute(two, {})
    g = rdf.curves["near"]["total"]
    assert g[2] > 0 and np.count_nonzero(g) == 1


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_bins_are_bounded_relative_to_the_range(scale: float) -> None:
    """A bin width of 1e-9 over [0, 10] once asked for 10^10 bins (74 GiB)."""
    near = (0.0, 10.0 * scale)
    with pytest.raises(ValueError, match=r"near_bin\n.*gives 1e\+10 bins over near = .*65,536"):
        RdfConfig(near=near, near_bin=1e-9 * scale)
    with pytest.raises(ValueError, match=r"far_bin\n.*gives 5e\+\d+ bins over far"):
        RdfConfig(far=(0.0, 1e300), far_bin=2.0 * scale)
    # the default bin scales with the packing's d_min; the window bounds the range
    assert RdfConfig(far=(0.0, 1e300)).far_bin is None
    assert RdfConfig(near=near, near_bin=10.0 * scale / 65_536).near_bin > 0


def test_the_curves_of_many_minerals_are_bounded_by_the_memory(monkeypatch) -> None:
    import dataclasses

    import regopack.base.limits
    from regopack.base.limits import LimitError

    squares = [[(x, 0.0), (x + 1.0, 0.0), (x + 1.0, 1.0), (x, 1.0)] for x in (0.0, 3.0, 6.0)]
    packing = dataclasses.replace(
        packing_from_polygons(squares, domain=(-1, 10, -4, 5)),
        mineral=np.arange(3, dtype=np.int64),
        mineral_names=("a", "b", "c"),
    )
    monkeypatch.setattr(regopack.base.limits, "memory_limit", lambda: (1 << 20, "memory"))
    config = RdfConfig(near=(0.0, 2.0), near_bin=2.0 / 60_000, far=(2.0, 4.0), margin=0.0)
    with pytest.raises(LimitError, match=r"^rdf\.near_bin = .*60,000 bins x 9 mineral pairs"):
        Rdf(config).compute(packing, {})
    Rdf(RdfConfig(near=(0.0, 2.0), far=(2.0, 4.0), margin=0.0)).compute(packing, {})


def test_a_bin_width_over_the_default_range_is_bounded_when_analysed() -> None:
    """The default range scales with the packing's d_min, so the settings cannot check it:
    the analysis does, before it allocates."""
    import regopack
    from regopack.base.errors import ConfigError

    packing = regopack.pack("small", count=300)
    with pytest.raises(ConfigError, match=r"rdf.near_bin = 1e-09: gives 1e\+10 bins over near"):
        regopack.analyze(packing, ["rdf"], params={"rdf": {"near_bin": 1e-9}})


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
    freud = pytest.importorskip("freud", reason="freud-analysis is not installed")
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
