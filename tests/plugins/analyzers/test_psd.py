"""The psd analyzer and the sieve classes: placed against requested sizes."""

from __future__ import annotations

import doctest
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

pytest.importorskip("regopack.plugins.inserters.available_arc")

from lattices3d import sphere_lattice

from regopack.analysis.pipeline import run_analyses, write_analysis
from regopack.packing import sieve
from regopack.packing.sieve import class_of, sieve_edges
from regopack.plugins.analyzers.psd import (
    Psd,
    PsdConfig,
    ks_distance,
    sampling_error,
    unplaced_per_class,
)
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons, scaled_packing


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


def sized(diameter, placed, size=None):
    """A packing of squares with the given equivalent diameters, ``placed`` as given."""
    d = np.asarray(diameter, dtype=np.float64)
    side = np.sqrt(np.pi) * d / 2
    x = 50.0 * np.arange(len(d))
    polys = [[(x0, 0), (x0 + s, 0), (x0 + s, s), (x0, s)] for x0, s in zip(x, side, strict=True)]
    p = packing_from_polygons(polys, (-10, 50.0 * len(d) + 10, -10, 60), placed=placed)
    scene = {"name": "test"} if size is None else {"name": "test", "size": size}
    return replace(p, radius=d / 2, scene=scene)


def sized3d(diameter, placed, size=None):
    """A row of spheres with the given diameters, ``placed`` as given (3D :func:`sized`)."""
    d = np.asarray(diameter, dtype=np.float64)
    lattice = sphere_lattice((len(d), 1, 1), float(d.max()) / 2, 1.0)
    mask = np.ones(len(d), bool) if placed is None else np.asarray(placed, bool)
    index = np.where(mask, np.cumsum(mask) - 1, -1)
    centre = np.where(mask[:, None], lattice.centre, np.nan)
    scene = {"name": "test"} if size is None else {"name": "test", "size": size}
    return replace(
        lattice, radius=d / 2, rounding=d / 2, insertion_index=index, centre=centre, scene=scene
    )


def analyse(packing, **params):
    return Psd(PsdConfig(**params)).compute(packing, {})


def test_sieve_edges_and_classes():
    edges = sieve_edges([2.0, 31.9], d_ref=2.0)
    assert np.allclose(edges, 2.0 * np.sqrt(2.0) ** np.arange(9))
    assert class_of([2.0, 2.82, 2.83, 31.9, 32.0], edges).tolist() == [0, 0, 1, 7, 7]
    # anchored at d_ref, covering only the drawn range
    assert np.allclose(sieve_edges([5.0, 7.0], d_ref=1.0), [4.0, 5.656854249492381, 8.0])
    assert np.allclose(sieve_edges([3.0, 3.0]), [3.0, 3.0 * math.sqrt(2.0)])
    with pytest.raises(ValueError, match="at least one"):
        sieve_edges([])
    assert doctest.testmod(sieve).failed == 0


def test_known_distribution_with_a_known_unplaced_subset():
    rng = np.random.default_rng(5)
    d = np.exp(rng.uniform(math.log(2.0), math.log(32.0), 3000))  # log-uniform on [2, 32]
    placed = ~((d > 16.0) | (np.arange(len(d)) % 10 == 0))
    psd = analyse(sized(d, placed), min_class_count=100, d_ref=2.0)
    c, res = psd.classes, psd.results()
    edges = 2.0 * np.sqrt(2.0) ** np.arange(9)
    assert np.allclose(np.r_[c["d_lo"], c["d_hi"][-1]], edges)
    drawn, _ = np.histogram(d, bins=edges)
    done, _ = np.histogram(d[placed], bins=edges)
    assert c["drawn"].tolist() == drawn.tolist()
    assert c["placed"].tolist() == done.tolist()
    assert c["not_placed"].tolist() == (drawn - done).tolist()
    assert c["placed"][6:].tolist() == [0, 0]  # d > 16 is never placed
    assert np.allclose(c["number_share_drawn"], drawn / len(d))
    assert np.allclose(c["number_share_placed"], done / placed.sum())
    area = np.pi * d**2 / 4
    mass_drawn, _ = np.histogram(d, bins=edges, weights=area)
    mass_done, _ = np.histogram(d[placed], bins=edges, weights=area[placed])
    assert np.allclose(c["mass_share_drawn"], mass_drawn / area.sum())
    assert np.allclose(c["mass_share_placed"], mass_done / area[placed].sum())
    assert np.allclose(c["number_rel_error"], (done / placed.sum()) / (drawn / len(d)) - 1)
    assert np.allclose(c["passing_number_drawn"], 100 * np.cumsum(drawn) / len(d))
    # KS by number: scipy's two-sample statistic, and its p-value from placed vs not placed
    ks = stats.ks_2samp(d[placed], d)
    assert res["ks_number"] == pytest.approx(ks.statistic, abs=1e-12)
    assert res["ks_number_pvalue"] == pytest.approx(stats.ks_2samp(d[placed], d[~placed]).pvalue)
    # KS by mass: largest gap between the area-weighted CDFs, at every diameter
    grid = np.sort(d)
    f_all = np.array([area[d <= g].sum() for g in grid]) / area.sum()
    f_sub = np.array([area[placed & (d <= g)].sum() for g in grid]) / area[placed].sum()
    assert res["ks_mass"] == pytest.approx(np.max(np.abs(f_sub - f_all)), abs=1e-12)
    # the worst class with at least 100 drawn particles
    rel = c["number_rel_error"]
    ok = drawn >= 100
    j = int(np.flatnonzero(ok)[np.argmax(np.abs(rel[ok]))])
    assert res["worst_number_rel_error"] == pytest.approx(rel[j])
    assert res["worst_number_class"] == pytest.approx([edges[j], edges[j + 1]])
    assert res["worst_number_rel_error"] == pytest.approx(-1.0)
    assert (res["n_drawn"], res["n_placed"]) == (3000, int(placed.sum()))
    assert res["analytic"] is None and res["notes"] == ["the scene has no size section"]


def test_everything_placed_gives_ks_zero():
    d = np.random.default_rng(1).uniform(2, 20, 500)
    res = analyse(sized(d, None)).results()
    assert res["ks_number"] == 0.0 and res["ks_mass"] == 0.0
    assert res["ks_number_pvalue"] == 1.0
    assert res["worst_number_rel_error"] == 0.0 and res["worst_mass_rel_error"] == 0.0
    assert res["n_not_placed"] == 0


def test_a_class_with_every_particle_unplaced_has_share_zero():
    d = np.array([2.1, 2.2, 2.5, 3.0, 3.5, 4.5, 5.0])
    placed = np.array([True, True, True, False, False, True, True])
    psd = analyse(sized(d, placed, {"kind": "uniform", "d_min": 2.0, "d_max": 6.0}), d_ref=2.0)
    c = psd.classes
    assert c["drawn"].tolist() == [3, 2, 2]
    assert c["placed"].tolist() == [3, 0, 2]
    assert c["number_share_placed"][1] == 0.0 and c["mass_share_placed"][1] == 0.0
    assert c["number_rel_error"][1] == -1.0 and c["placed_fraction"][1] == 0.0
    assert c["number_share_placed"].tolist() == pytest.approx([0.6, 0.0, 0.4])


def test_ks_distance_with_ties():
    d = np.array([1.0, 1.0, 2.0, 2.0, 3.0])
    sub = np.array([True, True, False, False, False])
    assert ks_distance(d, sub, np.ones(5)) == pytest.approx(0.6)
    assert math.isnan(ks_distance(d, np.zeros(5, bool), np.ones(5)))


def test_against_the_analytic_distribution():
    rng = np.random.default_rng(3)
    d = rng.uniform(2.0, 32.0, 4000)
    placed = d < 24.0
    psd = analyse(sized(d, placed, {"kind": "uniform", "d_min": 2.0, "d_max": 32.0}))
    c, res = psd.classes, psd.results()
    assert res["analytic"] == "uniform" and res["notes"] == []
    lo, hi = c["d_lo"], c["d_hi"]
    assert np.allclose(c["number_share_analytic"], (hi - lo) / 30.0)
    assert np.allclose(c["mass_share_analytic"], (hi**3 - lo**3) / (32.0**3 - 2.0**3), rtol=1e-5)
    ks = stats.kstest(d, stats.uniform(2.0, 30.0).cdf)
    assert res["ks_drawn_vs_analytic"] == pytest.approx(ks.statistic)
    assert res["ks_drawn_vs_analytic_pvalue"] == pytest.approx(ks.pvalue)
    assert res["ks_drawn_vs_analytic_pvalue"] > 0.01
    assert res["ks_placed_vs_analytic"] > 0.1  # the coarse end was not placed
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = c["number_share_placed"] / c["number_share_analytic"] - 1
    j = int(np.argmax(np.abs(rel)))
    assert (lo[j], hi[j]) == pytest.approx((16 * math.sqrt(2), 32.0))  # partly placed
    assert res["worst_analytic_number_rel_error"] == pytest.approx(rel[j])
    np.testing.assert_allclose(c["number_rel_error_analytic"], rel, rtol=1e-12)
    rel_mass = c["mass_share_placed"] / c["mass_share_analytic"] - 1
    np.testing.assert_allclose(c["mass_rel_error_analytic"], rel_mass, rtol=1e-12)
    k = int(np.argmax(np.abs(rel_mass)))
    assert res["worst_analytic_mass_rel_error"] == pytest.approx(rel_mass[k])
    assert res["worst_analytic_mass_class"] == pytest.approx([lo[k], hi[k]])
    assert rel_mass[k] > 1.0  # leaving out the coarsest third triples the finer mass shares


def test_a_size_distribution_that_cannot_be_rebuilt_is_noted():
    d = np.array([2.0, 3.0, 4.0])
    res = analyse(sized(d, None, {"kind": "no-such-size"})).results()
    assert res["analytic"] is None
    assert res["notes"][0].startswith("size distribution 'no-such-size' not rebuilt")
    res = analyse(sized(d, None, {"kind": "monodisperse", "d": 3.0})).results()
    assert res["notes"] == ["the size distribution gives no continuous CDF"]


def test_unplaced_per_class_of_a_packing_and_of_arrays():
    d = np.array([2.0, 2.5, 3.0, 5.0, 7.9, 8.0])
    placed = np.array([True, False, True, False, False, True])
    rows = unplaced_per_class(sized(d, placed, {"kind": "uniform", "d_min": 2.0, "d_max": 8.0}))
    assert [r["drawn"] for r in rows] == [2, 1, 1, 2]  # 8.0 closes the last class
    assert [r["not_placed"] for r in rows] == [1, 0, 1, 1]
    assert [r["placed"] for r in rows] == [1, 1, 0, 1]
    assert rows[0]["d_lo"] == 2.0 and rows[-1]["d_hi"] == pytest.approx(8.0)
    assert unplaced_per_class((d, placed), d_ref=2.0) == rows
    assert unplaced_per_class((np.zeros(0), np.zeros(0, bool))) == []


@pytest.fixture(scope="module")
def small(registry):
    return run_scene(resolve_scene(load_scene("small"), registry)).packing


def test_small_scene(small, registry, tmp_path):
    done = run_analyses(small, registry, [("psd", {})])
    psd = done["psd"]
    res = psd.results()
    assert res["analytic"] == "change5"
    assert res["d_ref"] == 2.0 and res["n_classes"] == 9
    assert res["n_drawn"] == small.n_particles and res["n_placed"] == small.n_placed
    assert int(psd.classes["not_placed"].sum()) == small.n_particles - small.n_placed
    assert res["ks_drawn_vs_analytic_pvalue"] > 0.01
    assert [r["not_placed"] for r in unplaced_per_class(small)] == list(psd.classes["not_placed"])
    files_ = write_analysis(tmp_path, small, done)
    assert set(files_.tables) == {"psd_classes"}
    header = files_.tables["psd_classes"].read_text(encoding="utf-8").splitlines()[0]
    assert header.startswith("class,d_lo,d_hi,drawn,placed,not_placed,placed_fraction,")
    assert [p.name for p in files_.figures] == ["psd.png", "psd.svg"]
    svg = (tmp_path / "figures" / "psd.svg").read_text(encoding="utf-8")
    assert "percent finer than d (%)" in svg


def test_cli_only_psd(small, tmp_path):
    from regopack.cli import main
    from regopack.packing.core import save

    path = tmp_path / "packing.npz"
    save(small, path)
    argv = ["analyze", str(path), "--only", "psd", "--set", "psd.min_class_count=50"]
    assert main([*argv, "--no-figures"]) == 0
    data = json.loads((tmp_path / "analysis" / "analysis.json").read_text(encoding="utf-8"))
    assert data["analyses"] == ["psd"]
    assert data["psd"]["min_class_count"] == 50
    assert (tmp_path / "analysis" / "psd_classes.csv").exists()


def test_mass_shares_weight_the_cube_of_the_diameter(packing3d) -> None:
    psd = Psd().compute(packing3d, {})
    c = psd.classes
    d = 2.0 * packing3d.radius
    placed = packing3d.placed
    k = np.searchsorted(c["d_hi"], d, side="right").clip(0, len(c["d_hi"]) - 1)
    mass = np.bincount(k[placed], weights=d[placed] ** 3, minlength=len(c["d_lo"]))
    np.testing.assert_allclose(c["mass_share_placed"], mass / mass.sum(), rtol=1e-12)
    np.testing.assert_allclose(psd.mass, np.pi / 6 * d**3, rtol=1e-15)
    # the scene's uniform 3-6 µm diameters: class shares of d³ in closed form
    lo, hi = np.clip(c["d_lo"], 3.0, 6.0), np.clip(c["d_hi"], 3.0, 6.0)
    expected = (hi**4 - lo**4) / (6.0**4 - 3.0**4)
    np.testing.assert_allclose(c["mass_share_analytic"], expected, atol=2e-4)
    assert psd.results()["analytic"] == "uniform"


# Four classes of one diameter each ([2, 2.83), [2.83, 4), [4, 5.66), [5.66, 8) µm): 400, 200,
# 100 and 99 drawn, so the coarsest class is below min_class_count and is not checked.
CLASS_D = (2.0, 3.0, 4.5, 7.0)
CLASS_DRAWN = (400, 200, 100, 99)


def population(placed_per_class, dimension):
    """The hand-built population: the first ``placed_per_class[k]`` of class ``k`` placed."""
    d = np.repeat(CLASS_D, CLASS_DRAWN)
    placed = np.concatenate(
        [np.arange(n) < p for n, p in zip(CLASS_DRAWN, placed_per_class, strict=True)]
    )
    size = {"kind": "uniform", "d_min": 2.0, "d_max": 7.0}
    return (sized if dimension == 2 else sized3d)(d, placed, size)


def expected_errors(placed_per_class, power):
    """Number and mass errors of each class, placed share / drawn share − 1, by hand."""
    drawn, done = np.array(CLASS_DRAWN, float), np.array(placed_per_class, float)
    mass = np.array(CLASS_D) ** power
    number = (done / done.sum()) / (drawn / drawn.sum()) - 1
    by_mass = (done * mass / (done @ mass)) / (drawn * mass / (drawn @ mass)) - 1
    return number, by_mass


@pytest.mark.parametrize("dimension", [2, 3])
def test_classes_within_the_tolerance_exactly(dimension):
    placed = (400, 190, 100, 99)  # ten of the 3 µm class left out
    psd = analyse(population(placed, dimension))
    c, res = psd.classes, psd.results()
    number, mass = expected_errors(placed, dimension)
    # 2D: +1.27 % / +0.88 % for the complete classes, -3.80 % / -4.16 % for the short one;
    # 3D: the same by number, +0.53 % / -4.50 % by volume
    np.testing.assert_allclose(c["number_rel_error"], number, rtol=1e-12)
    np.testing.assert_allclose(c["mass_rel_error"], mass, rtol=1e-12)
    assert number[1] == pytest.approx(0.95 * 799 / 789 - 1)
    assert c["drawn"].tolist() == list(CLASS_DRAWN) and c["placed"].tolist() == list(placed)
    assert c["checked"].tolist() == [True, True, True, False]
    assert c["within"].tolist() == [True, False, True, False]
    assert res["tolerance"] == 0.03
    assert (res["n_classes_checked"], res["n_classes_within"]) == (3, 2)
    assert res["classes_outside"] == [pytest.approx([2 * math.sqrt(2), 4.0])]
    assert res["all_classes_within"] is False
    assert res["worst_number_rel_error"] == pytest.approx(number[1])
    assert res["worst_mass_rel_error"] == pytest.approx(mass[1])
    # the class of 99 is held to the tolerance once 99 are enough
    c99 = analyse(population(placed, dimension), min_class_count=99).classes
    assert c99["checked"].tolist() == [True] * 4
    assert c99["within"].tolist() == [True, False, True, True]
    # everything placed: every checked class holds
    res_all = analyse(population(CLASS_DRAWN, dimension)).results()
    assert res_all["all_classes_within"] is True and res_all["classes_outside"] == []


def test_the_mass_power_decides_between_the_dimensions():
    # 3 µm class: -2.66 % by number (both), -2.74 % by area, -3.08 % by volume
    placed = (400, 192, 97, 99)
    flat, solid = (analyse(population(placed, k)) for k in (2, 3))
    assert flat.mass_power == 2 and solid.mass_power == 3
    number = flat.classes["number_rel_error"]
    np.testing.assert_array_equal(number, solid.classes["number_rel_error"])
    assert flat.classes["within"].tolist() == [True, True, True, False]
    assert solid.classes["within"].tolist() == [True, False, True, False]
    np.testing.assert_allclose(solid.classes["mass_rel_error"], expected_errors(placed, 3)[1])


def test_each_share_must_hold_and_the_bound_is_inclusive():
    # number outside, mass inside: -17.1 % by number, +0.38 % by area for the 3 µm class
    placed = (400, 144, 100, 50)
    c = analyse(population(placed, 2), tolerance=0.1).classes
    number, mass = expected_errors(placed, 2)
    assert abs(number[1]) > 0.1 > abs(mass[1])
    assert not c["within"][1]
    # mass outside, number inside (the 2D case of the test above, tolerance 4 %)
    placed = (400, 190, 100, 99)
    number, mass = expected_errors(placed, 2)
    c = analyse(population(placed, 2), tolerance=0.04).classes
    assert abs(number[1]) < 0.04 < abs(mass[1]) and not c["within"][1]
    # exactly at the tolerance a class holds; a rounding step below, it does not
    psd = analyse(population(placed, 2))
    c = psd.classes
    bound = float(max(abs(c["number_rel_error"][1]), abs(c["mass_rel_error"][1])))
    assert analyse(population(placed, 2), tolerance=bound).classes["within"][1]
    assert not analyse(population(placed, 2), tolerance=np.nextafter(bound, 0)).classes["within"][1]
    # the same for a number error larger than the mass error
    short = population((400, 144, 100, 50), 2)
    bound = abs(float(analyse(short).classes["number_rel_error"][1]))
    assert analyse(short, tolerance=bound).classes["within"][1]
    assert not analyse(short, tolerance=np.nextafter(bound, 0)).classes["within"][1]
    # no class held to the tolerance: no verdict
    res = analyse(short, min_class_count=1000).results()
    assert (res["n_classes_checked"], res["all_classes_within"]) == (0, None)
    assert res["worst_number_rel_error"] is None and res["classes_outside"] == []


@pytest.mark.parametrize("dimension", [2, 3])
def test_classes_do_not_depend_on_the_length_unit(dimension):
    placed = (400, 190, 100, 99)
    base = population(placed, dimension)
    for scene in (base.scene, {"name": "test"}):  # anchored on size.d_min, else the finest drawn
        packing = replace(base, scene=scene)
        c = analyse(packing).classes
        for s in (1e-3, 10.0**-6.5):
            other = analyse(scaled_packing(packing, s)).classes
            np.testing.assert_allclose(other["d_lo"], c["d_lo"] * s, rtol=1e-12)
            for key in ("drawn", "placed", "checked", "within"):
                np.testing.assert_array_equal(other[key], c[key])
            for key in ("number_rel_error", "mass_rel_error"):
                np.testing.assert_allclose(other[key], c[key], rtol=1e-9)


def test_the_figure_shows_the_class_errors_and_the_tolerance():
    from matplotlib.patches import Polygon, Rectangle

    from regopack.plugins.analyzers.psd_figure import draw_psd

    psd = analyse(population((400, 190, 100, 99), 3))
    fig = draw_psd(psd)
    errors = [ax for ax in fig.axes if ax.get_title().startswith("class error by")]
    assert [ax.get_title() for ax in errors] == ["class error by number", "class error by mass"]
    for ax, basis in zip(errors, ("number", "mass"), strict=True):
        band = [p for p in ax.patches if isinstance(p, Polygon | Rectangle)]
        assert band and band[0].get_extents().height > 0
        filled, hollow = ax.get_lines()[-2:]
        np.testing.assert_allclose(filled.get_ydata(), 100 * psd.classes[f"{basis}_rel_error"][:3])
        assert len(hollow.get_xdata()) == 1 and hollow.get_markerfacecolor() == "white"
        lo, hi = ax.get_ylim()
        assert lo == -hi and hi >= 1.25 * 100 * abs(psd.classes[f"{basis}_rel_error"][1])
    words = " ".join(t.get_text() for ax in fig.axes for t in ax.texts)
    assert "3 classes with ≥ 100 drawn" in words and "2 of them within ±3 %" in words


def test_the_sampling_error_of_a_random_subset():
    # by number: the hypergeometric standard deviation of a class's share, exactly
    placed = (400, 190, 100, 99)
    c = analyse(population(placed, 2)).classes
    n, p = 799, np.array(CLASS_DRAWN) / 799
    hyper = np.sqrt((1 - p) * (n - 789) / ((n - 1) * 789 * p))
    np.testing.assert_allclose(c["number_rel_error_sampling"], hyper, rtol=1e-12)
    # by mass: the spread of the class errors of many random subsets, within 5 %
    rng = np.random.default_rng(7)
    k = rng.integers(0, 3, 300)
    w = rng.uniform(1.0, 4.0, 300) ** 3
    share = np.bincount(k, weights=w) / w.sum()
    subsets = np.argsort(rng.random((4000, 300)), axis=1)[:, :200]
    got = np.stack([np.bincount(k[s], weights=w[s], minlength=3) for s in subsets])
    spread = np.std(got / got.sum(axis=1, keepdims=True) / share - 1, axis=0)
    np.testing.assert_allclose(sampling_error(k, w, 3, 200), spread, rtol=0.05)
    assert np.isnan(sampling_error(k, w, 4, 200)[3])  # an empty class
    assert np.all(sampling_error(k, w, 3, 300) == 0.0)  # everything placed
