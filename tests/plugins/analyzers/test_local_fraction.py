"""Local packing fraction: power cells, their clipping, and the lattice oracles."""

from __future__ import annotations

import doctest
import math
from dataclasses import replace

import numpy as np
import pytest
import shapely
from scipy.spatial import Voronoi

from regopack.analysis.pipeline import run_analyses
from regopack.geometry.domain import Circle, ConvexPolygon, PeriodicRectangle, Rectangle
from regopack.packing.core import Packing
from regopack.plugins.analyzers import local_fraction as local_fraction_module
from regopack.plugins.analyzers.local_fraction import (
    LocalFraction,
    LocalFractionConfig,
    domain_cells,
    inscribed_radius,
    power_cells,
)
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons

pytest.importorskip("regopack.plugins.inserters.available_arc")


def disks(centre, radius, domain):
    """A packing of disks (one vertex rounded by its radius)."""
    c = np.asarray(centre, dtype=np.float64)
    n = len(c)
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,)).copy()
    return Packing(
        radius=r,
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("test",),
        vertices=np.zeros((n, 2)),
        offsets=np.arange(n + 1, dtype=np.int64),
        orientation=np.zeros(n),
        centre=c,
        insertion_index=np.arange(n, dtype=np.int64),
        domain=domain,
        rounding=r,
    )


def analyse(packing, **params):
    return LocalFraction(LocalFractionConfig(**params)).compute(packing, {})


def brute_force_cell(p, w, i, box):
    """Power cell of site i: the box cut by the half-plane of every other site."""
    cell = shapely.box(*box)
    for j in range(len(p)):
        if j == i:
            continue
        a = 2.0 * (p[j] - p[i])
        b = p[j] @ p[j] - p[i] @ p[i] - w[j] + w[i]
        # a . x <= b, as a large polygon
        u = a / np.linalg.norm(a)
        base = u * b / np.linalg.norm(a)
        t = np.array([-u[1], u[0]]) * 1e3
        cell = cell.intersection(
            shapely.Polygon([base + t, base - t, base - t - 1e3 * u, base + t - 1e3 * u])
        )
    return cell


def test_power_cells_match_the_half_plane_definition():
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 10, (60, 2))
    w = rng.uniform(0, 0.5, 60)
    cells = power_cells(p, w, np.array([0, 10, 0, 10]))
    box = shapely.box(0, 0, 10, 10)
    for i in range(60):
        exact = brute_force_cell(p, w, i, (0, 0, 10, 10))
        assert cells[i].intersection(box).symmetric_difference(exact).area < 1e-9


def test_voronoi_cells_match_scipy():
    rng = np.random.default_rng(2)
    p = rng.uniform(0, 10, (200, 2))
    cells = power_cells(p, None, np.array([0, 10, 0, 10]))
    vor = Voronoi(p)
    box = shapely.box(0, 0, 10, 10)
    checked = 0
    for i in range(200):
        region = vor.regions[vor.point_region[i]]
        if -1 in region or len(region) == 0:
            continue
        poly = shapely.Polygon(vor.vertices[region]).convex_hull.intersection(box)
        assert cells[i].intersection(box).area == pytest.approx(poly.area, rel=1e-9)
        checked += 1
    assert checked > 150


@pytest.mark.parametrize(
    "domain",
    [
        Rectangle(0, 10, 0, 8),
        PeriodicRectangle(0, 10, 0, 8),
        Circle(5, 4, 4),
        ConvexPolygon(((0, 0), (10, 1), (8, 8), (1, 6))),
    ],
    ids=lambda d: d.kind,
)
def test_cell_areas_add_up_to_the_domain(domain):
    rng = np.random.default_rng(3)
    p = rng.uniform(domain.bounds()[[0, 2]], domain.bounds()[[1, 3]], (3000, 2))
    p = p[domain.contains(p)][:400]
    tess = domain_cells(domain, p, rng.uniform(0.0, 0.05, len(p)))
    assert tess.area.sum() == pytest.approx(domain.area, rel=1e-9)


def test_a_few_points_in_a_small_periodic_box():
    box = PeriodicRectangle(0, 1, 0, 1)
    for n in (1, 2, 5):
        p = np.random.default_rng(n).uniform(0, 1, (n, 2))
        assert domain_cells(box, p).area.sum() == pytest.approx(1.0, rel=1e-9)


def hexagonal(nx, ny, r):
    a = 2.0 * r
    h = a * math.sqrt(3.0) / 2.0
    xs, ys = np.meshgrid(np.arange(nx) * a, np.arange(ny) * h)
    xs = xs + 0.5 * a * (np.arange(ny)[:, None] % 2) + 0.1 * a
    return np.column_stack([xs.ravel(), ys.ravel() + 0.1 * h]), nx * a, ny * h


@pytest.mark.parametrize("cells", ["laguerre", "voronoi"])
def test_touching_disks_on_a_hexagonal_lattice(cells):
    c, lx, ly = hexagonal(12, 10, 1.0)
    lf = analyse(disks(c, 1.0, PeriodicRectangle(0, lx, 0, ly)), cells=cells)
    res = lf.results()
    assert np.allclose(lf.phi_local, math.pi / (2.0 * math.sqrt(3.0)), rtol=1e-9)
    assert res["cell_area_sum"] == pytest.approx(lx * ly, rel=1e-12)
    assert res["overhang_share"] == pytest.approx(0.0, abs=1e-12)
    assert res["share_beyond_cell"] == 0.0


def test_squares_on_a_square_lattice_fill_their_cells():
    a, s = 2.0, 1.6
    polys = [
        [
            (x - s / 2, y - s / 2),
            (x + s / 2, y - s / 2),
            (x + s / 2, y + s / 2),
            (x - s / 2, y + s / 2),
        ]
        for x in (np.arange(8) + 0.5) * a
        for y in (np.arange(6) + 0.5) * a
    ]
    for domain in (Rectangle(0, 8 * a, 0, 6 * a), PeriodicRectangle(0, 8 * a, 0, 6 * a)):
        lf = analyse(packing_from_polygons(polys, domain))
        assert np.allclose(lf.phi_local, (s / a) ** 2, rtol=1e-9)
    full = [
        [(x0, y0), (x0 + a, y0), (x0 + a, y0 + a), (x0, y0 + a)] for x0 in (0, a) for y0 in (0, a)
    ]
    lf = analyse(packing_from_polygons(full, (0, 2 * a, 0, 2 * a)))
    assert np.allclose(lf.phi_local, 1.0)


def test_laguerre_and_voronoi_agree_for_equal_radii():
    rng = np.random.default_rng(5)
    c = rng.uniform(1, 39, (400, 2))
    keep = [0]
    for k in range(1, len(c)):  # a random set of non-overlapping unit disks
        if np.min(np.hypot(*(c[keep] - c[k]).T)) > 2.0:
            keep.append(k)
    p = disks(c[keep], 1.0, Rectangle(0, 40, 0, 40))
    lag, vor = analyse(p), analyse(p, cells="voronoi")
    assert np.allclose(lag.cell_area, vor.cell_area, rtol=1e-9)
    assert np.allclose(lag.phi_local, vor.phi_local, rtol=1e-9)
    # disks lie inside their cells: the solid share of a cell is the particle's
    assert np.allclose(lag.solid_area, lag.particle_area, rtol=1e-9)


def test_inscribed_radius():
    square = packing_from_polygons(
        [[(0, 0), (2, 0), (2, 2), (0, 2)], [(3, 0), (7, 0), (7, 1), (3, 1)]]
    )
    assert inscribed_radius(square).tolist() == pytest.approx([1.0, 0.5])
    assert inscribed_radius(disks([[0.0, 0.0]], 1.5, Rectangle(-2, 2, -2, 2))) == pytest.approx(
        [1.5]
    )


@pytest.fixture(scope="module")
def small():
    registry = default_registry(autoload=False)
    packing = run_scene(resolve_scene(load_scene("small", ["count=300"]), registry)).packing
    return packing, registry


def test_a_random_packing(small):
    packing, registry = small
    done = run_analyses(packing, registry, [("local_fraction", {}), ("density", {})])
    lf = done["local_fraction"]
    res = lf.results()
    assert res["cell_area_rel_error"] == pytest.approx(0.0, abs=1e-9)
    assert res["n_empty_cells"] == 0
    # the solid in all cells is all solid: the cells' fraction is the domain's
    assert res["phi_cells"] == pytest.approx(done["density"].results()["phi_domain"], rel=1e-9)
    assert len(lf.phi_local) == packing.n_particles
    assert np.isnan(lf.phi_local[~packing.placed]).all()
    assert np.isfinite(lf.phi_local[packing.placed]).all()
    assert ((lf.phi_local[packing.placed] > 0) & (lf.phi_local[packing.placed] <= 1)).all()
    tables = lf.tables()
    assert len(tables["local_fraction"]["phi_local"]) == packing.n_placed
    assert tables["local_fraction_hist"]["n_domain"].sum() == packing.n_placed
    assert res["phi_mean"] == pytest.approx(np.mean(lf.phi_local[packing.placed]))


def test_a_periodic_packing_of_polygons_wraps(small):
    """The particles moved across the sides of a periodic box: cells and solid wrap."""
    packing, _ = small
    box = PeriodicRectangle(*packing.domain.bounds())
    moved = replace(packing, domain=box, centre=box.wrap(packing.centre + 37.0))
    lf = analyse(moved)
    res = lf.results()
    assert res["cell_area_sum"] == pytest.approx(box.area, rel=1e-9)
    # all solid is found, across the sides too
    assert res["phi_cells"] == pytest.approx(
        packing.area()[packing.placed].sum() / box.area, rel=1e-9
    )
    assert res["phi_max"] <= 1.0


def test_the_figure_draws(small, tmp_path):
    from regopack.plugins.analyzers.figure_style import style
    from regopack.plugins.analyzers.local_fraction_figure import draw_local_fraction

    packing, _ = small
    with style():
        fig = draw_local_fraction(packing, analyse(packing))
        fig.savefig(tmp_path / "local-fraction.png", dpi=60)
    assert (tmp_path / "local-fraction.png").stat().st_size > 0


def test_doctests():
    assert doctest.testmod(local_fraction_module).failed == 0
