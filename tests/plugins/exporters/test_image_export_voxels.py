"""The ``image`` export of 3D packings: voxels checked against independent membership tests.

The packings are built here, not packed: random convex polyhedra (the hulls
of random points) and spheres, one in each cell of a lattice so that none
overlaps. A voxel's membership is checked by another method than the
exporter's half-spaces: Delaunay simplices of the polyhedron's vertices, and
the plain distance to a sphere's centre.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull, Delaunay

from regopack.cli import main
from regopack.geometry.domain import Box, PeriodicBox
from regopack.packing.core import Packing, save
from regopack.plugins.exporters.image_export import (
    PORE,
    ImageConfig,
    ImageExporter,
    image_paths,
    rasterise,
)

CELL = 2.0
"""Side of the lattice cell that holds one particle."""


def _hull(points: np.ndarray) -> tuple[np.ndarray, list[np.ndarray], np.ndarray, np.ndarray]:
    """Vertices, outward triangle loops, normals and supports of the hull of ``points``."""
    hull = ConvexHull(points)
    keep = hull.vertices
    index = np.full(points.shape[0], -1)
    index[keep] = np.arange(keep.shape[0])
    verts = points[keep]
    loops, normals, support = [], [], []
    for tri, eq in zip(hull.simplices, hull.equations, strict=True):
        a, b, c = points[tri]
        if np.dot(np.cross(b - a, c - a), eq[:3]) < 0:
            tri = tri[::-1]
        loops.append(index[tri])
        normals.append(eq[:3])
        support.append(-eq[3])
    return verts, loops, np.array(normals), np.array(support)


def lattice_packing(
    cells: int = 3, seed: int = 0, periodic: bool = False, shift: float = 0.0
) -> Packing:
    """One particle per cell of a ``cells``³ lattice: random polyhedra and every 5th a sphere.

    Every particle lies in the ball of radius 0.45 ``CELL`` around its cell's
    centre; ``shift`` moves them all along x (across the side of a periodic box).
    """
    rng = np.random.default_rng(seed)
    grid = (np.indices((cells,) * 3).reshape(3, -1).T + 0.5) * CELL
    radius, rounding, verts, offsets = [], [], [], [0]
    loops, face_offsets, normals, support = [], [0], [], []
    for k in range(grid.shape[0]):
        if k % 5 == 4:
            rho = rng.uniform(0.3, 0.45) * CELL
            radius.append(rho)
            rounding.append(rho)
            verts.append(np.zeros((1, 3)))
        else:
            direction = rng.normal(size=(14, 3))
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            points = direction * rng.uniform(0.35, 0.45, size=(14, 1)) * CELL
            points -= points.mean(axis=0)  # the centre strictly inside
            v, f, n, s = _hull(points)
            radius.append(np.cbrt(3 * ConvexHull(v).volume / (4 * np.pi)))
            rounding.append(0.0)
            verts.append(v)
            loops += f
            normals.append(n)
            support.append(s)
        offsets.append(offsets[-1] + verts[-1].shape[0])
        face_offsets.append(len(loops))
    side = cells * CELL
    centre = grid + [shift, 0.0, 0.0]
    domain: Box = (
        PeriodicBox(0, side, 0, side, 0, side) if periodic else Box(0, side, 0, side, 0, side)
    )
    if periodic:
        centre = domain.wrap(centre)  # type: ignore[attr-defined]
    n = grid.shape[0]
    return Packing(
        radius=np.array(radius),
        mineral=np.arange(n) % 2,
        mineral_names=("plagioclase", "glass"),
        vertices=np.concatenate(verts),
        offsets=np.array(offsets),
        face_vertices=np.concatenate(loops).astype(np.int64),
        face_vertex_offsets=np.arange(len(loops) + 1) * 3,
        face_offsets=np.array(face_offsets),
        normals=np.concatenate(normals),
        support=np.concatenate(support),
        rotation=np.tile([1.0, 0, 0, 0], (n, 1)),
        centre=centre,
        insertion_index=np.arange(n),
        domain=domain,
        rounding=np.array(rounding),
    )


@pytest.fixture(scope="module")
def packing() -> Packing:
    return lattice_packing()


def oracle(packing: Packing, points: np.ndarray) -> np.ndarray:
    """Label (particle + 1, 0 void) of every point, by Delaunay simplices and distances."""
    out = np.zeros(points.shape[0], dtype=np.int64)
    period = np.array(packing.domain.period) if packing.domain.periodic else None  # type: ignore[attr-defined]
    rho = packing.rounding_radius
    for j in np.flatnonzero(packing.placed).tolist():
        delta = points - packing.centre[j]
        if period is not None:
            delta = packing.domain.minimum_image(delta)  # type: ignore[attr-defined]
        if rho[j] > 0:
            inside = np.einsum("ij,ij->i", delta, delta) <= rho[j] ** 2
        else:
            local = packing.vertices[packing.offsets[j] : packing.offsets[j + 1]]
            inside = Delaunay(local).find_simplex(delta) >= 0
        out[inside] = j + 1
    return out


def centres(image, index: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    g = image.grid
    return np.column_stack([g.x(index[:, 2]), g.y(index[:, 1]), g.z(index[:, 0])])


@pytest.mark.parametrize("periodic", [False, True])
def test_every_voxel_has_the_label_of_the_particle_its_centre_lies_in(periodic):
    packing = lattice_packing(periodic=periodic, shift=0.9 if periodic else 0.0, seed=1)
    image = rasterise(packing, 0.05)
    assert image.labels.shape == (120, 120, 120)
    assert image.inside.all()
    rng = np.random.default_rng(2)
    index = rng.integers(0, image.labels.shape, size=(40_000, 3))
    want = oracle(packing, centres(image, index))
    got = image.labels[tuple(index.T)]
    assert (want > 0).sum() > 4_000
    np.testing.assert_array_equal(got, want)


def test_a_centre_on_a_face_is_solid():
    # a cube of half-side 0.5 whose faces pass through voxel centres (h = 0.25)
    cube = lattice_packing(cells=1)
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * 0.5
    _, loops, normals, support = _hull(v)
    box = Packing(
        radius=np.array([np.cbrt(3 / (4 * np.pi))]),
        mineral=np.zeros(1, dtype=np.int64),
        mineral_names=("glass",),
        vertices=v,
        offsets=np.array([0, 8]),
        face_vertices=np.concatenate(loops).astype(np.int64),
        face_vertex_offsets=np.arange(len(loops) + 1) * 3,
        face_offsets=np.array([0, len(loops)]),
        normals=normals,
        support=support,
        rotation=cube.rotation[:1],
        centre=np.array([[1.125, 1.125, 1.125]]),
        insertion_index=np.zeros(1, dtype=np.int64),
        domain=Box(0, 2, 0, 2, 0, 2),
    )
    image = rasterise(box, 0.25)
    # centres 0.625 to 1.625 along each axis: 5 per axis, the outer ones on a face
    assert int(image.solid.sum()) == 5**3


def test_the_axes_run_along_z_up_y_down_and_x_right():
    box = Box(0, 4, 0, 3, 0, 2)
    image = rasterise(Packing.of_spheres([[0.5, 0.5, 0.5]], [0.3], box), 1.0)
    assert image.labels.shape == (2, 3, 4)  # (layers: z, rows: y, columns: x)
    assert np.argwhere(image.labels == 1).tolist() == [[0, 2, 0]]  # bottom layer, last row
    assert image.grid.bounds() == (0, 4, 0, 3, 0, 2)


def surface(packing: Packing) -> np.ndarray:
    """Surface area of every placed particle."""
    solids = packing.solids
    return np.array(
        [
            4 * math.pi * solids.rounding_radius[j] ** 2
            if solids.rounding_radius[j] > 0
            else ConvexHull(solids.solid(j)[0]).area
            for j in np.flatnonzero(packing.placed).tolist()
        ]
    )


def volume_error_bound(packing: Packing, h: float) -> float:
    """Bound on |voxel volume - exact volume| of the placed particles, summed.

    A voxel is miscounted only if its cube meets the particle's surface, so
    its centre lies within t = √3 h / 2 of that surface. That shell holds at
    most 2 S t + M t² + 4π t³ / 3 (Steiner's formula outside, S t inside),
    with the mean-curvature integral M ≤ 4π R, R the circumradius.
    """
    t = math.sqrt(3) * h / 2
    radius = packing.solids.circumradius[packing.placed]
    return float(
        np.sum(2 * surface(packing) * t + 4 * math.pi * radius * t**2 + 4 * math.pi * t**3 / 3)
    )


def test_phi_of_the_image_converges_to_the_exact_phi_within_the_voxel_error(packing):
    volume = packing.domain.measure
    for h in (0.2, 0.1, 0.05):
        error = abs(rasterise(packing, h).phi - packing.phi)
        assert error <= volume_error_bound(packing, h) / volume, h
        # the voxels along a surface err both ways and cancel: in practice the error is
        # that of a random walk over the surface's voxels, below h² √S / V
        assert error <= h**2 * math.sqrt(surface(packing).sum()) / volume, h


def test_a_periodic_cube_across_a_corner_is_drawn_in_all_eight_corners():
    packing = lattice_packing(cells=1)
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * 0.5
    _, loops, normals, support = _hull(v)
    cube = Packing(
        radius=np.array([np.cbrt(3 / (4 * np.pi))]),
        mineral=np.zeros(1, dtype=np.int64),
        mineral_names=("glass",),
        vertices=v,
        offsets=np.array([0, 8]),
        face_vertices=np.concatenate(loops).astype(np.int64),
        face_vertex_offsets=np.arange(len(loops) + 1) * 3,
        face_offsets=np.array([0, len(loops)]),
        normals=normals,
        support=support,
        rotation=packing.rotation[:1],
        centre=np.array([[0.1, 0.1, 0.1]]),
        insertion_index=np.zeros(1, dtype=np.int64),
        domain=PeriodicBox(0, 4, 0, 4, 0, 4),
    )
    image = rasterise(cube, 0.25)
    # the cube spans -0.4 to 0.6: centres 0.125, 0.375 and, wrapped, 3.625, 3.875
    assert int(image.solid.sum()) == 4**3 and image.phi == pytest.approx(cube.phi)
    corners = image.labels[np.ix_([0, -1], [0, -1], [0, -1])]
    assert (corners == 1).all()


def test_files_and_porespy(packing, tmp_path):
    tifffile = pytest.importorskip("tifffile", reason="tifffile (test extra) reads the TIFF")
    ps = pytest.importorskip("porespy", reason="PoreSpy (test extra) analyses the image")
    from PIL import Image

    h = 0.1
    path = ImageExporter(ImageConfig(pixel_size=h)).export(packing, tmp_path / "p.png")
    files = image_paths(path)
    image = rasterise(packing, h)
    meta = json.loads(files["meta"].read_text())
    assert meta["shape"] == [60, 60, 60] and meta["pixel_size"] == h
    assert meta["axes"][0].startswith("layer: z") and meta["extent"] == [0, 6, 0, 6, 0, 6]
    assert meta["png_layer"] == 30 and meta["png_z"] == pytest.approx(3.05)
    assert meta["phi_image"] == image.phi and meta["phi_exact"] == pytest.approx(packing.phi)
    np.testing.assert_array_equal(tifffile.imread(files["labels"]), image.labels)
    with Image.open(files["binary"]) as png:
        np.testing.assert_array_equal(np.asarray(png), image.layer(30).binary())
    with Image.open(files["minerals"]) as png:
        np.testing.assert_array_equal(np.asarray(png), image.minerals()[30])
    im = np.load(files["phases"])
    np.testing.assert_array_equal(im, image.phases())

    # PoreSpy: the porosity within the voxel error of the exact one
    bound = volume_error_bound(packing, h) / packing.domain.measure
    assert abs(ps.metrics.porosity(im) - (1 - packing.phi)) <= bound
    # local thickness: between a voxel's own distance to the solid and the largest one
    pores = np.pad(im == PORE, 1, constant_values=False)  # the walls as solid
    lt = ps.filters.local_thickness(pores, method="dt")[1:-1, 1:-1, 1:-1]
    dt = ps.tools.get_edt()(pores)[1:-1, 1:-1, 1:-1]
    inner = im == PORE
    assert np.all(lt[inner] > 0) and np.all(lt[~inner] == 0)
    assert lt.max() <= dt.max() + 1e-9
    assert np.all(lt[inner] >= dt[inner] - 1.0)  # one voxel: the radii lt tries are whole
    assert h < lt.max() * h < min(packing.domain.size) / 2  # type: ignore[attr-defined]
    # the pores are of the particles' size: gaps of about a particle between lattice cells
    r = packing.radius.mean()
    assert r / 3 < lt[inner].mean() * h < 3 * r
    psd = ps.metrics.pore_size_distribution(lt * h, log=False, bins=10)
    assert np.sum(psd.satn) == pytest.approx(1.0) and np.all(np.diff(psd.cdf) <= 0)


def one_line(capsys) -> str:  # type: ignore[no-untyped-def]
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("regopack: error: "), lines
    return lines[0]


def test_the_command_line_writes_a_3d_image(packing, tmp_path, capsys):
    source = tmp_path / "packing.npz"
    save(packing, source)
    assert main(["export", str(source), "--to", "image"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'packing.png'}"
    for file in image_paths(tmp_path / "packing.png").values():
        assert file.stat().st_size > 0
    meta = json.loads((tmp_path / "packing_image.json").read_text())
    # the default voxel: d_min/10, a whole number of voxels across the width
    d_min = 2 * packing.radius.min()
    n = math.ceil(6 / (d_min / 10))
    assert meta["shape"] == [n, n, n] and meta["pixel_size"] == pytest.approx(6 / n)
    assert np.load(tmp_path / "packing.npy").shape == (n, n, n)

    assert main(["export", str(source), "--to", "image", "--set", "pixel_size=-1"]) == 2
    assert "pixel_size" in one_line(capsys)
    args = ["export", str(source), "--to", "image", "--set", "pixel_size=0.001", "--force"]
    assert main(args) == 2
    line = one_line(capsys)
    assert "6000 x 6000 x 6000 = 216000000000 voxels, more than max_pixels" in line
    assert "use pixel_size >= 0.0093 or raise max_pixels (at most 536870912)" in line
