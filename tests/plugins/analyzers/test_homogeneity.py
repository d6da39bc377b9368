"""The homogeneity analyzer: rings, tiles, trends, and the regions' exact areas."""

from __future__ import annotations

import doctest
import json
import math
import re
from dataclasses import replace
from importlib.resources import files

import numpy as np
import pytest
import shapely
from lattices3d import cube_lattice

pytest.importorskip("regopack.plugins.inserters.available_arc")

from regopack.analysis.pipeline import run_analyses, write_analysis
from regopack.base.errors import ConfigError
from regopack.geometry.domain import Circle, ConvexPolygon, PeriodicRectangle, Rectangle
from regopack.plugins.analyzers import homogeneity as homogeneity_module
from regopack.plugins.analyzers.homogeneity import Homogeneity, HomogeneityConfig, trend
from regopack.plugins.analyzers.regions import (
    disk_areas,
    ring_edges,
    ring_mean_radius,
    ring_window_areas,
    tile_grid,
)
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


def reference(*overrides):
    """Scene overrides plus the paper's insertion order (the reference mode)."""
    return [*overrides, "insertion.order=paper"]


def squares(xy, side, domain, mineral=None):
    """Small squares centred on the points ``xy``."""
    h = 0.5 * np.asarray(side, dtype=np.float64) * np.ones(len(xy))
    polys = [
        [(x - s, y - s), (x + s, y - s), (x + s, y + s), (x - s, y + s)]
        for (x, y), s in zip(xy, h, strict=True)
    ]
    p = packing_from_polygons(polys, domain)
    if mineral is not None:
        p = replace(p, mineral=np.asarray(mineral, dtype=np.int64), mineral_names=("a", "b"))
    return p


def analyse(packing, **params):
    return Homogeneity(HomogeneityConfig(**params)).compute(packing, {})


# ---------------------------------------------------------------------------
# geometry


def test_disk_areas_are_exact_also_for_a_tangent_edge():
    square = np.array([shapely.box(-60, -60, 60, 60)], dtype=object)
    assert disk_areas(square, (0, 0), 60.0)[0] == pytest.approx(math.pi * 3600, rel=1e-12)
    assert disk_areas(square, (0, 0), 30.0)[0] == pytest.approx(math.pi * 900, rel=1e-12)
    assert disk_areas(square, (0, 0), 100.0)[0] == pytest.approx(14400, rel=1e-12)
    rng = np.random.default_rng(4)
    polys = np.array(
        [shapely.MultiPoint(rng.normal(size=(6, 2)) * 4 + 3).convex_hull for _ in range(50)]
    )
    disk = shapely.Point(1.0, 2.0).buffer(5.0, quad_segs=4096)
    expected = shapely.area(shapely.intersection(polys, disk))
    assert np.allclose(disk_areas(polys, (1.0, 2.0), 5.0), expected, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize(
    "window",
    [
        Rectangle(-60, 60, -40, 40),
        Circle(5, -5, 50),
        ConvexPolygon(((-60, -40), (50, -60), (80, 40), (0, 70))),
    ],
    ids=["rectangle", "circle", "polygon"],
)
def test_rings_and_tiles_cover_the_window(window):
    centre = window.center
    edges = ring_edges(window, centre, 12.0)
    assert edges[0] == 0
    assert ring_window_areas(window, centre, edges).sum() == pytest.approx(window.area)
    tiles = tile_grid(window, 4, 4)
    if isinstance(window, Rectangle):
        assert len(tiles.area) == 16
        assert tiles.area.sum() == pytest.approx(window.area)
    else:  # cells less than half inside are left out
        assert len(tiles.area) < 16
        assert np.all(tiles.area > 0)


def test_ring_mean_radius_of_a_full_annulus():
    r = ring_mean_radius(Circle(0, 0, 50), (0, 0), 10.0, 30.0)
    assert r == pytest.approx(2 / 3 * (30**3 - 10**3) / (30**2 - 10**2), rel=1e-12)


def test_trend_is_weighted_least_squares():
    x = np.array([0.0, 1.0, 2.0, 3.0])
    y = np.array([1.0, 2.9, 5.2, 6.9])
    err = np.array([0.1, 0.2, 0.2, 0.4])
    t = trend(x, y, err)
    w = 1 / err**2
    coef, cov = np.polyfit(x, y, 1, w=np.sqrt(w), cov="unscaled")
    assert t.slope == pytest.approx(coef[0], rel=1e-12)
    assert t.intercept == pytest.approx(coef[1], rel=1e-12)
    chi2 = float(np.sum(w * (y - np.polyval(coef, x)) ** 2)) / 2
    assert t.chi2_dof == pytest.approx(chi2, rel=1e-10)
    assert t.slope_err == pytest.approx(math.sqrt(cov[0, 0]) * max(1.0, math.sqrt(chi2)))
    assert math.isnan(trend(x[:1], y[:1], err[:1]).slope)


def test_doctests():
    assert doctest.testmod(homogeneity_module).failed == 0


# ---------------------------------------------------------------------------
# synthetic patterns


def test_uniform_random_points_have_no_trend():
    rng = np.random.default_rng(7)
    n = 20_000
    xy = rng.uniform(-200, 200, size=(n, 2))
    mineral = (rng.random(n) < 0.3).astype(np.int64)
    side = rng.uniform(0.3, 0.8, n)
    h = analyse(squares(xy, side, (-200, 200, -200, 200), mineral), margin=10.0, rings=6)
    res = h.results()
    assert res["n_rings"] == 5  # the sixth, in the corners, is merged into the fifth
    assert res["n_interior"] == int(np.sum(np.all(np.abs(xy) < 190, axis=1)))
    for q in ("density", "phi", "mean_d"):
        assert abs(res[f"{q}_slope_per_100"]) < 3 * res[f"{q}_slope_err"], q
    for name in ("a", "b"):
        assert abs(res["fraction_slope_per_100"][name]) < 3 * res["fraction_slope_err"][name]
    n_min = int(np.min(h.rings["n"]))
    assert res["density_max_rel_dev"] < 4 / math.sqrt(n_min)
    assert res["mean_d_max_rel_dev"] < 0.05
    assert res["tile_density_max_rel_dev"] < 4 / math.sqrt(int(np.min(h.tiles_table["n"])))
    assert 0.3 < res["tile_density_chi2_dof"] < 2.5
    assert res["density_trend_chi2_dof"] < 4
    # φ of the window is the squares' area in it, cut exactly
    window = shapely.box(-190, -190, 190, 190)
    geoms = squares(xy, side, (-200, 200, -200, 200)).to_shapely()
    phi = shapely.area(shapely.intersection(geoms, window)).sum() / window.area
    assert res["phi"] == pytest.approx(phi, rel=1e-12)
    assert h.rings["area"].sum() == pytest.approx(380**2)
    assert np.sum(h.rings["phi"] * h.rings["area"]) == pytest.approx(phi * window.area)


def test_a_graded_pattern_has_a_negative_density_trend():
    rng = np.random.default_rng(11)
    xy = rng.uniform(-200, 200, size=(40_000, 2))
    r = np.hypot(*xy.T)
    keep = rng.random(len(xy)) < 1.0 - 0.6 * r / r.max()
    h = analyse(squares(xy[keep], 0.5, (-200, 200, -200, 200)), margin=10.0, rings=6)
    res = h.results()
    assert res["density_slope_per_100"] < -5 * res["density_slope_err"]
    assert np.all(np.diff(h.rings["number_density"]) < 0)
    assert abs(res["mean_d_slope_per_100"]) < 1e-9  # every square has the same size


@pytest.mark.slow  # 7 s; the layers' errors and slopes are checked in the default run too
def test_uniform_points_have_no_height_trend_and_a_gradient_has_one():
    """The layers (2D height profile): flat for a uniform pattern, falling for a graded one."""
    rng = np.random.default_rng(5)
    xy = rng.uniform(-200, 200, size=(30_000, 2))
    h = analyse(squares(xy, 0.5, (-200, 200, -200, 200)), margin=10.0, layers=5)
    res = h.results()
    assert res["layers"] == 5 and len(h.layers["n"]) == 5
    assert h.layers["n"].sum() == res["n_interior"]
    assert np.sum(h.layers["phi"] * h.layers["area"]) == pytest.approx(res["phi"] * 380**2)
    n_min = int(np.min(h.layers["n"]))
    assert res["layer_density_max_rel_dev"] < 4 / math.sqrt(n_min)
    for q in ("density", "phi"):
        assert abs(res[f"layer_{q}_slope_per_100"]) < 3 * res[f"layer_{q}_slope_err"], q
    assert 0.2 < res["layer_density_chi2_dof"] < 3.0
    # fewer particles the higher up: a negative trend with height, well beyond its error
    keep = rng.random(len(xy)) < 1.0 - 0.4 * (xy[:, 1] + 200) / 400
    res = analyse(squares(xy[keep], 0.5, (-200, 200, -200, 200)), margin=10.0).results()
    assert res["layer_density_slope_per_100"] < -5 * res["layer_density_slope_err"]
    assert res["layer_density_max_rel_dev"] > 0.1
    assert res["layer_density_chi2_dof"] > 10


def dense_lattice(rng, side=60, spacing=1.0):
    """Squares on a square lattice, sizes 0.6 to 0.95 of the spacing, jittered without overlap.

    Statistically the same everywhere, and far more even than independent
    placements: the particle area of a region fluctuates much less than the
    compound Poisson error says.
    """
    n = int(side / spacing)
    grid = (np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1).reshape(-1, 2) + 0.5) * spacing
    size = rng.uniform(0.6, 0.95, len(grid)) * spacing
    room = 0.5 * (spacing - size)[:, None]
    xy = grid + rng.uniform(-1.0, 1.0, grid.shape) * room
    return squares(xy, size, (0, side, 0, side))


def test_phi_errors_match_the_scatter_of_a_uniform_sample():
    """The error of φ is the scatter of φ between regions of one size, as a standard error is.

    Between the 64 tiles of one sample, and for each ring between 12
    samples. The compound Poisson error, as if the squares were placed
    independently, was 4 to 5 times that scatter.
    """
    rng = np.random.default_rng(8)
    rings, ring_errors = [], []
    for k in range(12):
        packing = dense_lattice(rng)
        h = analyse(packing, margin=0.0, rings=5, tiles=(8, 8))
        rings.append(h.rings["phi"])
        ring_errors.append(h.rings["phi_err"])
        if k == 0:
            tiles = h.tiles_table
            scatter = np.std(tiles["phi"], ddof=1)
            assert 0.6 < np.median(tiles["phi_err"]) / scatter < 1.6
            assert 0.3 < h.results()["tile_phi_chi2_dof"] < 2.5
            # the former error, sqrt(sum(a_i^2)) / A over the squares in a tile
            tile = np.floor(packing.centre / 7.5).astype(int) @ [1, 8]
            poisson = np.sqrt(np.bincount(tile, packing.area() ** 2)) / tiles["area"]
            assert np.median(poisson) > 3.0 * scatter
    ratio = np.mean(ring_errors, axis=0) / np.std(rings, axis=0, ddof=1)
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio


def test_phi_errors_of_independent_particles_stay_those_of_independent_particles():
    """Squares placed independently: the scatter of the parts gives the compound Poisson error."""
    rng = np.random.default_rng(9)
    n = 20_000
    xy = rng.uniform(-200, 200, size=(n, 2))
    h = analyse(squares(xy, rng.uniform(0.3, 0.8, n), (-200, 200, -200, 200)), margin=10.0)
    tiles = h.tiles_table
    ratio = np.median(tiles["phi_err"]) / np.std(tiles["phi"], ddof=1)
    assert 0.6 < ratio < 1.6, ratio


def test_the_parts_of_a_region_add_up_to_it(small):
    from regopack.plugins.analyzers.common import interior_margin, interior_window
    from regopack.plugins.analyzers.homogeneity import SECTORS, TILE_SPLIT
    from regopack.plugins.analyzers.regions import (
        ring_piece_areas,
        ring_sector_areas,
        tile_cell_areas,
        tile_piece_areas,
        window_pieces,
    )

    window = interior_window(small, interior_margin(small, None))
    centre = small.domain.center
    pieces = window_pieces(small, window)
    edges = ring_edges(window, centre, 15.0)
    solid, area = ring_sector_areas(pieces, window, centre, edges, SECTORS)
    assert solid.shape == area.shape == (len(edges) - 1, SECTORS)
    np.testing.assert_allclose(solid.sum(axis=1), ring_piece_areas(pieces, centre, edges).sum(0))
    np.testing.assert_allclose(area.sum(axis=1), ring_window_areas(window, centre, edges))
    tiles = tile_grid(window, 4, 4)
    solid, area = tile_cell_areas(pieces, window, tiles, TILE_SPLIT)
    np.testing.assert_allclose(solid.sum(axis=1), tile_piece_areas(pieces, tiles).sum(0))
    np.testing.assert_allclose(area.sum(axis=1), tiles.area)


# ---------------------------------------------------------------------------
# packings


@pytest.fixture(scope="module")
def small(registry):
    return run_scene(resolve_scene(load_scene("small", reference()), registry)).packing


def test_small_scene_density_falls_from_the_centre(small):
    res = analyse(small).results()
    assert res["ring_width"] == 15.0  # a quarter of the 60 µm to the window's edge
    assert res["density_slope_per_100"] < -2 * res["density_slope_err"]
    # the default 120 µm window is too small for the diameter trend (seed 1:
    # -0.03 ± 0.91 per 100 µm); a 180 µm window (margin 10 µm) shows it
    wide = analyse(small, margin=10.0).results()
    assert wide["mean_d_slope_per_100"] > 3 * wide["mean_d_slope_err"]
    assert wide["density_slope_per_100"] < -3 * wide["density_slope_err"]


def test_table1_scene_grades_radially(registry):
    scene = load_scene("table1", reference("domain.width=400", "domain.height=400"))
    packing = run_scene(resolve_scene(scene, registry)).packing
    h = analyse(packing)
    res = h.results()
    assert res["ring_width"] == 40.0
    assert res["density_slope_per_100"] < -3 * res["density_slope_err"]
    assert res["mean_d_slope_per_100"] > 3 * res["mean_d_slope_err"]
    assert abs(res["phi_slope_per_100"]) < 3 * res["phi_slope_err"]
    nd = h.rings["number_density"]
    assert nd[0] > 0.03 and nd[-1] < 0.025
    done = run_analyses(packing, registry, [("density", {})])
    assert res["phi"] == pytest.approx(done["density"].results()["phi_interior"], rel=1e-12)


SMALL = files("regopack.scenes").joinpath("small.toml").read_text(encoding="utf-8")
DOMAINS = {
    "circle": '[domain]\nkind = "circle"\nradius = 90.0\ncenter = [5.0, -5.0]',
    "polygon": (
        '[domain]\nkind = "polygon"\nvertices = [[-100, -80], [90, -100], [120, 60], [0, 110]]'
    ),
    "periodic": '[domain]\nkind = "periodic"\nwidth = 150.0\nheight = 120.0',
}


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_every_domain_kind_with_disks(kind, registry, tmp_path):
    text = re.sub(r"\[domain\].*?(?=\n\[size\])", DOMAINS[kind] + "\n", SMALL, flags=re.S)
    text = re.sub(r'shape = \{ kind = "octagon"[^}]*\}', 'shape = { kind = "disk" }', text)
    path = tmp_path / "scene.toml"
    path.write_text(text.replace('count = "auto"', "count = 400"), encoding="utf-8")
    packing = run_scene(resolve_scene(load_scene(path), registry)).packing
    assert packing.rounded
    done = run_analyses(packing, registry, [("homogeneity", {}), ("density", {})])
    h = done["homogeneity"]
    res = h.results()
    assert res["window_kind"] == kind
    assert res["phi"] == pytest.approx(done["density"].results()["phi_interior"], rel=1e-9)
    assert h.rings["area"].sum() == pytest.approx(res["window_area"], rel=1e-9)
    assert int(h.rings["n"].sum()) == res["n_interior"]
    if kind == "periodic":
        # no walls: every particle counts, and every part of it once
        assert res["interior_margin"] == 40.0 and res["n_interior"] == packing.n_placed
        assert isinstance(packing.domain, PeriodicRectangle)
        total = float(packing.area()[packing.placed].sum())
        assert np.sum(h.rings["phi"] * h.rings["area"]) == pytest.approx(total, rel=1e-3)
        assert h.tiles_table["area"].sum() == pytest.approx(150 * 120)


def test_parameters_are_checked(registry, small):
    with pytest.raises(ConfigError, match=r"homogeneity: .*at most one of ring_width and rings"):
        run_analyses(small, registry, [("homogeneity", {"ring_width": 10, "rings": 3})])
    with pytest.raises(ConfigError, match=r"homogeneity.ring_width = -1"):
        run_analyses(small, registry, [("homogeneity", {"ring_width": -1})])
    with pytest.raises(ConfigError, match=r"tiles must be two counts"):
        run_analyses(small, registry, [("homogeneity", {"tiles": [0, 3]})])


def test_empty_window(registry):
    p = squares(np.array([[0.0, 0.0], [1.0, 1.0]]), 0.5, (-5, 5, -5, 5))
    res = analyse(p, margin=6.0).results()
    assert res["n_rings"] == 0 and res["n_tiles"] == 0
    assert res["density_slope_per_100"] is None
    assert res["notes"] == ["the interior window is empty (margin 6)"]


def test_files_and_figure(small, registry, tmp_path):
    from matplotlib.image import imread

    from regopack.plugins.analyzers import figures
    from regopack.plugins.analyzers.figure_specs import CAPTIONS

    done = run_analyses(small, registry, [("homogeneity", {"rings": 4, "tiles": [3, 2]})])
    files_ = write_analysis(tmp_path, small, done)
    summary = json.loads(files_.results.read_text(encoding="utf-8"))
    assert summary["homogeneity"]["n_rings"] == 3  # the corners merge into the third ring
    assert summary["interior_margin"] == 40.0
    assert set(files_.tables) == {"homogeneity_rings", "homogeneity_tiles", "homogeneity_layers"}
    header = files_.tables["homogeneity_rings"].read_text(encoding="utf-8").splitlines()[0]
    assert header.startswith("ring,r_inner,r_outer,r_mean,area,n,number_density,")
    assert "frac_pyroxene,frac_pyroxene_err" in header
    rows = files_.tables["homogeneity_tiles"].read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + 6
    assert [p.name for p in files_.figures] == ["homogeneity.png", "homogeneity.svg"]
    image = imread(tmp_path / "figures" / "homogeneity.png")
    assert image.shape[1] == pytest.approx(figures.WIDTH * figures.DPI, abs=2)
    assert CAPTIONS["homogeneity"] in files_.report.read_text(encoding="utf-8")


def test_cli_only_homogeneity(small, tmp_path, capsys):
    from regopack.cli import main
    from regopack.packing.core import save

    path = tmp_path / "packing.npz"
    save(small, path)
    args = ["analyze", str(path), "--only", "homogeneity", "--set", "homogeneity.rings=3"]
    assert main([*args, "--no-figures"]) == 0
    data = json.loads((tmp_path / "analysis" / "analysis.json").read_text(encoding="utf-8"))
    assert data["analyses"] == ["homogeneity"]
    assert data["homogeneity"]["n_rings"] == 3
    assert "homogeneity" in capsys.readouterr().out


def test_layers_and_shells_add_up_to_the_window(packing3d) -> None:
    from regopack.packing.solid_fraction import phi_in_box

    h = Homogeneity(HomogeneityConfig(layers=4, shells=3)).compute(packing3d, {})
    window = packing3d.domain.interior(6.0)  # the scene's d_max
    phi = phi_in_box(packing3d, window)
    # equal layers: the window's fraction is their mean; shells: their volume-weighted mean
    assert np.mean(h.layers["phi"]) == pytest.approx(phi, rel=1e-12)
    steps = np.array([0, 1, 2, 3]) / 3
    weights = np.diff(steps**3)
    assert np.average(h.shells["phi"], weights=weights) == pytest.approx(phi, rel=1e-12)
    inside = window.contains(packing3d.centre)
    assert h.layers["n"].sum() == h.shells["n"].sum() == inside.sum()


def test_a_lattice_of_cubes_is_homogeneous_layer_by_layer() -> None:
    # 4 x 4 x 6 touching unit cubes, the window cutting through none: every layer holds
    # 16 cubes in a 4 x 4 x 1 slab
    p = cube_lattice((4, 4, 6), (0.0, 0.0, 0.0))
    h = Homogeneity(HomogeneityConfig(layers=6, shells=1, margin=0.5)).compute(p, {})
    np.testing.assert_allclose(h.layers["phi"], 1.0, rtol=1e-12)
    np.testing.assert_array_equal(h.layers["n"], 16)
    r = h.results()
    assert r["phi_layers_cv"] == pytest.approx(0.0, abs=1e-12)
    assert r["mean_diameter_layers"] == pytest.approx([2 * p.radius[0]] * 6)
    # the height profile: every layer at the window's values, no trend, exact φ errors of 0
    np.testing.assert_allclose(h.layers["phi_err"], 0.0, atol=1e-12)
    assert r["layer_phi_max_rel_dev"] == pytest.approx(0.0, abs=1e-12)
    assert r["layer_density_max_rel_dev"] == pytest.approx(0.0, abs=1e-12)
    assert r["layer_density_slope_per_100"] == pytest.approx(0.0, abs=1e-12)


def test_a_graded_3d_lattice_shows_its_height_trend() -> None:
    """Cubes thinned towards the top: the layers' number density falls with height."""
    import dataclasses

    p = cube_lattice((6, 6, 8), (0.0, 0.0, 0.0))
    z = p.centre[:, 2]
    keep = np.ones(len(z), bool)
    rng = np.random.default_rng(3)
    keep &= rng.random(len(z)) < 1.0 - 0.6 * (z - z.min()) / np.ptp(z)
    index = np.where(keep, np.cumsum(keep) - 1, -1)
    centre = np.where(keep[:, None], p.centre, np.nan)
    thinned = dataclasses.replace(p, insertion_index=index, centre=centre)
    h = Homogeneity(HomogeneityConfig(layers=8, shells=1, margin=0.5)).compute(thinned, {})
    r = h.results()
    assert r["layer_density_slope_per_100"] < -3 * r["layer_density_slope_err"]
    assert h.layers["number_density_err"].min() > 0


def test_3d_shells_carry_sampling_errors_and_their_deviation_from_the_window(
    packing3d,
) -> None:
    h = Homogeneity(HomogeneityConfig(layers=4, shells=3)).compute(packing3d, {})
    shells, r = h.shells, h.results()
    n = shells["n"]
    half = np.array([0, 1, 2, 3]) / 3 * np.array(h.window.size)[:, None] / 2
    volume = np.diff(np.prod(2 * half, axis=0))
    # Poisson for the number density, std / sqrt(n) for the mean diameter, as the layers'
    np.testing.assert_allclose(shells["number_density"], n / volume, rtol=1e-12)
    np.testing.assert_allclose(
        shells["number_density_err"], np.sqrt(np.maximum(n, 1)) / volume, rtol=1e-12
    )
    window = packing3d.domain.interior(6.0)
    placed = packing3d.placed
    c = np.asarray(window.center)
    reach = np.max(np.abs(packing3d.centre - c) / (0.5 * np.array(window.size)), axis=1)
    d = 2.0 * packing3d.radius
    expected = []
    for k in range(3):
        sel = placed & (reach >= k / 3) & (reach < (k + 1) / 3)
        m = int(sel.sum())
        expected.append(d[sel].std(ddof=1) / np.sqrt(m) if m > 1 else np.nan)
    np.testing.assert_allclose(shells["mean_d_err"], expected, rtol=1e-12)
    assert np.isfinite(shells["mean_d_err"]).sum() >= 2  # the fixture has a chi2 to check
    dev = np.max(np.abs(shells["number_density"] / r["number_density"] - 1.0))
    assert r["shell_density_max_rel_dev"] == pytest.approx(dev, rel=1e-12)
    dev = np.nanmax(np.abs(shells["mean_d"] / r["mean_d"] - 1.0))
    assert r["shell_mean_d_max_rel_dev"] == pytest.approx(dev, rel=1e-12)
    ok = np.isfinite(shells["mean_d_err"]) & (shells["mean_d_err"] > 0)
    w = 1.0 / shells["mean_d_err"][ok] ** 2
    mean = np.sum(w * shells["mean_d"][ok]) / w.sum()
    chi2 = np.sum(w * (shells["mean_d"][ok] - mean) ** 2) / (ok.sum() - 1)
    assert r["shell_mean_d_chi2_dof"] == pytest.approx(chi2, rel=1e-12)
    assert r["shell_density_chi2_dof"] is not None


def test_a_periodic_cell_counts_the_solids_that_cross_its_faces_in_their_images() -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    # 4 x 4 x 4 touching unit cubes in a cell shifted by half a cube: every cube crosses
    # faces of the cell, and its images fill every layer and shell to phi = 1
    p = cube_lattice((4, 4, 4), (0.0, 0.0, 0.0))
    lo = p.centre.min(axis=0)
    cell = dataclasses.replace(p, domain=PeriodicBox(*(v for a in lo for v in (a, a + 4.0))))
    h = Homogeneity(HomogeneityConfig(layers=4, shells=2)).compute(cell, {})
    np.testing.assert_allclose(h.layers["phi"], 1.0, rtol=1e-12)
    np.testing.assert_allclose(h.shells["phi"], 1.0, rtol=1e-12)
    np.testing.assert_array_equal(h.layers["n"], 16)
