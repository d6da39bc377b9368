"""The image exporter: exact pixel classification, φ within the pixel error, files, PoreSpy."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
import shapely

from regopack.base.errors import ExportError
from regopack.cli import main
from regopack.exports.pipeline import export_packing
from regopack.geometry.domain import PeriodicRectangle, Rectangle
from regopack.geometry.population import Population
from regopack.packing.core import Packing, save
from regopack.plugins.exporters.image_export import (
    MINERAL_OUTSIDE,
    OUTSIDE,
    OUTSIDE_LABEL,
    PNG_OUTSIDE,
    PNG_SOLID,
    PORE,
    SOLID,
    ImageConfig,
    ImageExporter,
    RasterImage,
    image_paths,
    pixel_grid,
    rasterise,
)
from regopack.plugins.shapes.disk import Disk
from regopack.registry.interfaces import InsertionResult
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons

H = 0.25
"""Pixel size of the scene tests; it divides every side of the rectangular domains."""

DOMAINS = {
    "rectangle": 'domain={kind = "rectangle", width = 60.0, height = 50.0}',
    "periodic": 'domain={kind = "periodic", width = 60.0, height = 50.0}',
    "circle": 'domain={kind = "circle", radius = 30.0, center = [3.0, -2.0]}',
    "polygon": 'domain={kind = "polygon", vertices = [[-30, -25], [28, -30], [33, 18], [0, 32]]}',
}
DISKS = [f'phases.{k}.shape={{kind = "disk"}}' for k in (0, 2, 4)]
"""Three of the six minerals as disks, the others octagons."""

CASES = [(kind, disks) for kind in DOMAINS for disks in (False, True)]
IDS = [f"{kind}-{'disks' if disks else 'polygons'}" for kind, disks in CASES]
TOL = 1e-9
"""Distance from an outline within which a pixel centre may go either way."""


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def scenes(registry) -> dict[tuple[str, bool], Packing]:
    out = {}
    for kind, disks in CASES:
        overrides = ["size.d_max=12.0", DOMAINS[kind], *(DISKS if disks else [])]
        packing = run_scene(resolve_scene(load_scene("small", overrides), registry)).packing
        assert packing.rounded == disks
        out[kind, disks] = packing
    return out


@pytest.fixture(scope="module", params=CASES, ids=IDS)
def case(request, scenes) -> tuple[Packing, RasterImage]:
    packing = scenes[request.param]
    return packing, rasterise(packing, H)


def shifts(packing: Packing) -> list[tuple[float, float]]:
    d = packing.domain
    if not isinstance(d, PeriodicRectangle):
        return [(0.0, 0.0)]
    return [(sx, sy) for sx in (-d.width, 0.0, d.width) for sy in (-d.height, 0.0, d.height)]


def cores(packing: Packing) -> np.ndarray:
    """Exact shapely cores of every particle: a point (disk) or the sharp polygon."""
    out = np.empty(packing.n_particles, dtype=object)
    for j in np.flatnonzero(packing.placed):
        v = packing.polygon(j)
        out[j] = shapely.Point(v[0]) if v.shape[0] == 1 else shapely.Polygon(v).convex_hull
    return out


def centres(image: RasterImage, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    return np.column_stack([image.grid.x(cols), image.grid.y(rows)])


# ---------------------------------------------------------------------------
# every pixel is classified by its centre


def test_every_labelled_pixel_centre_lies_in_its_particle(case):
    packing, image = case
    rows, cols = np.nonzero(image.labels > 0)
    assert rows.size > 1000
    j = image.labels[rows, cols] - 1
    assert packing.placed[j].all()
    core, rho = cores(packing)[j], packing.rounding_radius[j]
    p = centres(image, rows, cols)
    if isinstance(packing.domain, PeriodicRectangle):  # the image of p nearest the particle
        c = packing.centre[j]
        p = c + packing.domain.minimum_image(p - c)
    assert np.all(shapely.distance(core, shapely.points(p)) <= rho + TOL)


def test_no_particle_covers_a_void_pixel_centre(case):
    packing, image = case
    rows, cols = np.nonzero(image.labels == 0)
    points = shapely.points(centres(image, rows, cols))
    core, rho = cores(packing), packing.rounding_radius
    idx = np.flatnonzero(packing.placed)
    for sx, sy in shifts(packing):
        moved = shapely.transform(core[idx], lambda c, sx=sx, sy=sy: c + [sx, sy])
        # a centre deeper than TOL inside a sharp outline, or nearer than rho - TOL to a core
        shrunk = np.where(
            rho[idx] > 0,
            shapely.buffer(moved, rho[idx] - TOL),
            shapely.buffer(moved, -TOL, join_style="mitre"),
        )
        hit_point, _ = shapely.STRtree(shrunk).query(points, predicate="intersects")
        assert hit_point.size == 0, centres(image, rows, cols)[hit_point[:5]]


def test_pixels_outside_the_domain_are_marked(case):
    packing, image = case
    g = image.grid
    rows, cols = np.indices(g.shape).reshape(2, -1)
    inside = packing.domain.contains(centres(image, rows, cols)).reshape(g.shape)
    assert np.array_equal(image.labels == OUTSIDE_LABEL, ~inside)
    if isinstance(packing.domain, Rectangle):
        assert inside.all()  # the pixel size divides the sides
    else:
        assert 0.1 < np.mean(~inside) < 0.5


def test_a_square_and_the_orientation_of_the_rows():
    # one square at the bottom left, one at the top right of a 4 x 4 domain of unit pixels
    low = [(0.3, 0.3), (2.3, 0.3), (2.3, 1.3), (0.3, 1.3)]
    high = [(3.2, 3.2), (3.9, 3.2), (3.9, 3.9), (3.2, 3.9)]
    image = rasterise(packing_from_polygons([low, high], domain=(0, 4, 0, 4)), 1.0)
    assert image.labels.tolist() == [[0, 0, 0, 2], [0, 0, 0, 0], [0, 0, 0, 0], [1, 1, 0, 0]]
    assert image.phi == 3 / 16


def disks(centre, radius, domain) -> Packing:
    r = np.atleast_1d(np.asarray(radius, dtype=float))
    n = r.shape[0]
    shapes = Disk().generate(r, np.random.default_rng(0))
    pop = Population(r, np.zeros(n, dtype=np.int64), ("d",), shapes)
    res = InsertionResult(np.asarray(centre, dtype=float).reshape(n, 2), np.arange(n))
    return Packing.from_parts(pop, res, domain, {}, 0)


def test_a_disk_has_the_lattice_point_count():
    # a disk of radius 5.5 pixels on a pixel centre holds the integer points i^2 + j^2 <= 30.25
    expected = sum(1 for i in range(-6, 7) for k in range(-6, 7) if i * i + k * k <= 30.25)
    assert expected == 97
    image = rasterise(disks([(10.5, 10.5)], 5.5, Rectangle(0, 21, 0, 21)), 1.0)
    assert np.count_nonzero(image.labels == 1) == expected
    assert np.array_equal(image.labels, image.labels[::-1]) and np.array_equal(
        image.labels, image.labels.T
    )


def test_a_rounded_polygon_is_its_core_grown_by_the_radius():
    core = [(2.0, 2.0), (6.0, 2.0), (6.0, 5.0), (2.0, 5.0)]
    p = packing_from_polygons([core], domain=(0, 8, 0, 7))
    p = dataclasses.replace(p, rounding=np.array([1.3]))
    image = rasterise(p, 0.05)
    rows, cols = np.indices(image.grid.shape).reshape(2, -1)
    distance = shapely.distance(shapely.Polygon(core), shapely.points(centres(image, rows, cols)))
    assert np.array_equal(image.labels.reshape(-1) == 1, distance <= 1.3)
    assert np.count_nonzero(image.solid) * 0.05**2 == pytest.approx(p.area()[0], rel=2e-3)


def test_a_particle_across_a_periodic_corner_is_drawn_in_all_four_corners():
    square = [(-0.6, -0.6), (1.4, -0.6), (1.4, 1.4), (-0.6, 1.4)]  # centre (0.4, 0.4)
    p = packing_from_polygons([square], domain=PeriodicRectangle(0, 10, 0, 8))
    labels = rasterise(p, 0.5).labels
    # centres x = 0.25, 0.75, 1.25 and, one period on, 9.75; y likewise (row 0 at the top)
    expected = np.zeros((16, 20), dtype=bool)
    expected[np.ix_([0, 13, 14, 15], [0, 1, 2, 19])] = True
    assert np.array_equal(labels == 1, expected), labels
    assert np.count_nonzero(labels) * 0.25 == p.area()[0]
    without_wrap = dataclasses.replace(p, domain=Rectangle(0, 10, 0, 8))
    assert np.count_nonzero(rasterise(without_wrap, 0.5).labels) == 9


# ---------------------------------------------------------------------------
# phi of the image against the exact phi


def perimeter(packing: Packing) -> np.ndarray:
    """Perimeter of every placed particle: its core's, plus 2 pi rho for a rounded one."""
    idx = np.flatnonzero(packing.placed)
    return shapely.length(cores(packing)[idx]) + 2 * math.pi * packing.rounding_radius[idx]


def test_every_particle_has_its_area_within_the_lattice_point_bound(case):
    # convex set of area A and perimeter P, pixel centres of spacing h (Nosarzewska;
    # Bokowski, Hadwiger and Wills): -P h / 2 < N h^2 - A < P h / 2 + h^2
    packing, image = case
    idx = np.flatnonzero(packing.placed)
    n = np.bincount(image.labels[image.labels > 0], minlength=packing.n_particles + 1)[1:]
    err = n[idx] * H * H - packing.area()[idx]
    p = perimeter(packing)
    assert np.all(err > -p * H / 2) and np.all(err < p * H / 2 + H * H), err.min()


def test_phi_of_the_image_is_the_exact_phi_within_the_pixel_error(case):
    packing, image = case
    d = packing.domain
    idx = np.flatnonzero(packing.placed)
    area, p = packing.area()[idx].sum(), perimeter(packing)
    phi = area / d.area
    # worst case, from the lattice-point bound of every particle and of the domain
    solid_err = float(np.sum(p * H / 2 + H * H))
    domain_perimeter = 0.0 if isinstance(d, Rectangle) else shapely.Polygon(d.outline()).length
    domain_err = domain_perimeter * H / 2 + H * H
    worst = (solid_err + phi * domain_err) / (d.area - domain_err)
    # in practice: the outlines cross about P / h pixels, whose errors (each below h^2) cancel
    typical = H * H * math.sqrt((p.sum() + domain_perimeter) / H) / d.area
    print(f"{d.kind}, rounded {packing.rounded}: phi_image {image.phi:.6f}, exact {phi:.6f}")
    assert abs(image.phi - phi) < typical < worst


def test_the_minerals_follow_the_labels(case):
    packing, image = case
    m, labels = image.minerals(), image.labels
    solid = labels > 0
    assert np.array_equal(m[solid], packing.mineral[labels[solid] - 1] + 1)
    assert np.all(m[labels == 0] == 0) and np.all(m[labels == OUTSIDE_LABEL] == MINERAL_OUTSIDE)
    # area share of each mineral, from pixels and exactly
    idx = np.flatnonzero(packing.placed)
    exact = np.bincount(packing.mineral[idx], packing.area()[idx], minlength=6)
    pixels = np.bincount(m[solid] - 1, minlength=6) * H * H
    assert np.abs(pixels - exact).max() < np.sum(perimeter(packing) * H / 2 + H * H)


def test_the_default_pixel_size_is_a_tenth_of_the_smallest_diameter(scenes):
    packing = scenes["rectangle", False]
    d_min = 2 * packing.radius[packing.placed].min()
    g = pixel_grid(packing)
    assert g.size <= d_min / 10 and g.size > d_min / 10 * (1 - 1 / g.n_cols)
    assert g.n_cols * g.size == pytest.approx(60.0, abs=1e-9)
    assert g.shape == (math.ceil(50.0 / g.size - 1e-9), g.n_cols)


def test_a_pixel_size_that_does_not_divide_the_sides_marks_the_last_pixels(scenes):
    image = rasterise(scenes["rectangle", False], 0.7)
    assert image.grid.shape == (72, 86)  # 50 / 0.7 = 71.4, 60 / 0.7 = 85.7
    # the centres of the last row lie 0.05 below the bottom wall, of the last column 0.15
    # inside the right one
    assert np.all(image.labels[-1] == OUTSIDE_LABEL)
    assert np.all(image.labels[:-1] >= 0)


# ---------------------------------------------------------------------------
# files and errors


def test_files_round_trip(scenes, tmp_path):
    tifffile = pytest.importorskip("tifffile", reason="tifffile (test extra) reads the TIFF")
    from PIL import Image

    packing = scenes["circle", True]
    exporter = ImageExporter(ImageConfig(pixel_size=H))
    path = exporter.export(packing, tmp_path / "p.png")
    files = image_paths(path)
    assert path == files["binary"] == tmp_path / "p.png"
    assert set(exporter.companions(path)) == set(files.values()) - {path}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in files.values())
    image = rasterise(packing, H)
    binary = np.asarray(Image.open(path))
    assert binary.dtype == np.uint8 and np.array_equal(binary, image.binary())
    assert set(np.unique(binary)) == {0, PNG_SOLID, PNG_OUTSIDE}
    labels = tifffile.imread(files["labels"])
    assert labels.dtype == np.int32 and np.array_equal(labels, image.labels)
    minerals = np.asarray(Image.open(files["minerals"]))
    assert np.array_equal(minerals, image.minerals())
    phases = np.load(files["phases"], allow_pickle=False)
    assert phases.dtype == np.uint8 and np.array_equal(phases, image.phases())
    assert np.array_equal(phases == SOLID, image.solid)
    assert np.array_equal(phases == OUTSIDE, ~image.inside)
    meta = json.loads(files["meta"].read_text())
    assert meta["pixel_size"] == H and meta["shape"] == list(image.grid.shape)
    assert meta["phi_image"] == image.phi
    assert meta["phi_exact"] == pytest.approx(
        packing.area()[packing.placed].sum() / (900 * math.pi)
    )
    assert meta["mineral_names"] == list(packing.mineral_names)
    assert meta["files"]["labels"] == "p_labels.tif"


def test_the_command_line_writes_the_images(scenes, tmp_path, capsys):
    source = tmp_path / "packing.npz"
    save(scenes["periodic", False], source)
    args = ["export", str(source), "--to", "image", "--set", f"pixel_size={H}"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'packing.png'}"
    for p in image_paths(tmp_path / "packing.png").values():
        assert p.stat().st_size > 0


def one_line(capsys) -> str:
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("regopack: error: "), lines
    return lines[0]


@pytest.mark.parametrize(
    ("setting", "words"),
    [
        ("pixel_size=-0.5", ["pixel_size"]),
        ("pixel_size=nan", ["pixel_size"]),
        ("max_pixels=0", ["max_pixels"]),
        ("formats=1", ["formats"]),
    ],
)
def test_bad_parameters_are_one_line(scenes, tmp_path, capsys, setting, words):
    source = tmp_path / "packing.npz"
    save(scenes["rectangle", False], source)
    assert main(["export", str(source), "--to", "image", "--set", setting]) == 2
    line = one_line(capsys)
    assert all(w in line for w in words), line


def test_a_too_large_image_is_refused_before_it_is_allocated(scenes, tmp_path, capsys):
    packing = scenes["rectangle", False]
    with pytest.raises(ExportError, match=r"2400000 x 2000000 = .* more than max_pixels") as err:
        rasterise(packing, 2.5e-5)
    assert "\n" not in str(err.value)
    source = tmp_path / "packing.npz"
    save(packing, source)
    args = ["export", str(source), "--to", "image", "--set", "max_pixels=1000"]
    assert main(args) == 2
    assert "use pixel_size >= 1.73" in one_line(capsys)
    assert not (tmp_path / "packing.png").exists()


def test_other_errors_are_one_line(tmp_path):
    square = [(1, 1), (3, 1), (3, 3), (1, 3)]
    none_placed = packing_from_polygons([square], domain=(0, 4, 0, 4), placed=[False])
    with pytest.raises(ExportError, match="none is placed; set pixel_size > 0"):
        rasterise(none_placed)
    assert rasterise(none_placed, 1.0).phi == 0.0
    with pytest.raises(ExportError, match=r"pixel_size = -1\.0"):
        rasterise(none_placed, -1.0)
    many = dataclasses.replace(none_placed, mineral_names=tuple(f"m{k}" for k in range(255)))
    with pytest.raises(ExportError, match="holds up to 254 minerals; this packing has 255"):
        ImageExporter(ImageConfig(pixel_size=1.0)).export(many, tmp_path / "p.png")
    assert not list(tmp_path.iterdir())
    registry = default_registry(autoload=False)
    with pytest.raises(ExportError, match=r"cannot write .*missing"):
        export_packing(
            none_placed,
            "image",
            tmp_path / "missing" / "p.png",
            registry=registry,
            params={"pixel_size": 1.0},
        )


# ---------------------------------------------------------------------------
# PoreSpy reads the images


def test_porespy_porosity_and_local_thickness(scenes, tmp_path):
    ps = pytest.importorskip("porespy", reason="PoreSpy (test extra) analyses the image")
    # a slot two units wide between two solid blocks: its pores have radius 1
    slot = [[(0, 0), (4, 0), (4, 4), (0, 4)], [(6, 0), (10, 0), (10, 4), (6, 4)]]
    image = rasterise(packing_from_polygons(slot, domain=(0, 10, 0, 4)), 0.1)
    lt = ps.filters.local_thickness(image.phases() == PORE, method="dt")
    assert np.unique(lt[image.phases() == PORE]) * 0.1 == pytest.approx([1.0])

    for kind in ("rectangle", "circle"):
        packing = scenes[kind, False]
        path = ImageExporter(ImageConfig(pixel_size=H)).export(packing, tmp_path / f"{kind}.png")
        im = np.load(image_paths(path)["phases"])
        meta = json.loads(image_paths(path)["meta"].read_text())
        # PoreSpy ignores the value 2 (outside the domain): porosity over the domain
        assert ps.metrics.porosity(im) == pytest.approx(1 - meta["phi_image"], abs=1e-15)
        assert abs(ps.metrics.porosity(im) - (1 - meta["phi_exact"])) < 0.01
        pores = im == PORE
        lt = ps.filters.local_thickness(pores, method="dt") * H  # radius, in µm
        assert np.all(lt[pores] > 0) and np.all(lt[~pores] == 0)
        size = min(packing.domain.width, packing.domain.height)
        assert H < lt.max() < size / 2
        psd = ps.metrics.pore_size_distribution(lt, log=False, bins=10)
        assert np.all(psd.pdf >= 0) and psd.cdf[0] == pytest.approx(1.0)
        assert np.all(np.diff(psd.cdf) <= 0) and np.sum(psd.satn) == pytest.approx(1.0)
        # most pore space sits in throats far narrower than the largest particles
        assert np.median(lt[pores]) < 12.0 / 2


def test_the_docstring_examples_run():
    import doctest

    import regopack.plugins.exporters.image_export as module

    result = doctest.testmod(module)
    assert result.attempted >= 4 and result.failed == 0
