"""Packings in a walled cylinder, exported and run by LAMMPS, LIGGGHTS and YADE.

Every program must keep the particles inside the cylinder: at rest (no
gravity) nothing moves, and under gravity tilted sideways, which presses the
particles onto the side wall, none passes the side wall, the floor or the lid.
The packings (``cylinder_packings.py``) have an axis off the origin and
particles that touch the side wall from the start.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from cylinder_packings import CYLINDER, cylinder_cubes, cylinder_spheres

import regopack
from regopack.packing.core import Packing
from regopack.plugins.exporters.lammps_export import (
    LammpsConfig,
    LammpsExporter,
    dump_path,
    script_path,
)
from regopack.plugins.exporters.lammps_side_wall import CORNER_GAP, side_wall

LIGGGHTS = shutil.which("liggghts")
YADE = shutil.which("yade")


def excess(centre: np.ndarray, radius: np.ndarray) -> float:
    """How far the farthest sphere reaches past the cylinder (side wall, floor or lid)."""
    c = CYLINDER
    side = np.hypot(centre[:, 0] - c.cx, centre[:, 1] - c.cy) + radius - c.radius
    floor = c.zmin - (centre[:, 2] - radius)
    lid = centre[:, 2] + radius - c.zmax
    return float(np.max([side.max(), floor.max(), lid.max()]))


def points_excess(points: np.ndarray, rounding: np.ndarray) -> float:
    """How far the farthest rounded point reaches past the cylinder."""
    return excess(points, rounding)


def tilt(script: Path, old: str, new: str) -> None:
    """Turn the script's gravity sideways (towards +x): replace ``old`` by ``new``, once."""
    text = script.read_text()
    assert text.count(old) == 1, old
    script.write_text(text.replace(old, new))


# ---------------------------------------------------------------------------
# LAMMPS


def simulate(path: Path, chunks: list[int], **variables: float) -> dict:
    """Run the exported script in a child process (the driver of the LAMMPS tests)."""
    from test_lammps_export import simulate as run

    return run(path, chunks, **variables)


@pytest.fixture(scope="module")
def spheres() -> Packing:
    return cylinder_spheres()


@pytest.fixture(scope="module")
def cubes() -> Packing:
    return cylinder_cubes()


def test_lammps_granular_spheres_script_has_the_cylinder(spheres, tmp_path) -> None:
    path = LammpsExporter().export(spheres, tmp_path / "p.data")
    script = script_path(path).read_text()
    c = CYLINDER
    assert (
        f"\nregion       container cylinder z {c.cx} {c.cy} {c.radius} {c.zmin} {c.zmax} "
        "side in units box\n" in script
    )
    assert script.count("wall/gran/region granular hertz/material") == 1
    assert "plane" not in script
    lo = [float(v) for v in re.findall(r"^(\S+) \S+ [xyz]lo", path.read_text(), re.M)]
    hi = [float(v) for v in re.findall(r"^\S+ (\S+) [xyz]lo", path.read_text(), re.M)]
    bounds = c.bounds().reshape(3, 2)
    assert np.all(np.array(lo) <= bounds[:, 0]) and np.all(np.array(hi) >= bounds[:, 1])


def test_lammps_holds_granular_spheres_still_in_a_cylinder(spheres, tmp_path) -> None:
    path = LammpsExporter().export(spheres, tmp_path / "p.data")
    report = simulate(path, [500, 500])
    d_min = 2.0 * float(spheres.solids.rounding_radius.min())
    assert report["natoms"] == spheres.n_placed and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min


def test_lammps_keeps_granular_spheres_in_the_cylinder_under_tilted_gravity(
    spheres, tmp_path
) -> None:
    path = LammpsExporter().export(spheres, tmp_path / "p.data")
    tilt(script_path(path), "gravity ${g} vector 0 0 -1", "gravity ${g} vector 1 0 -1")
    report = simulate(path, [3000], g=0.05)
    assert report["natoms"] == spheres.n_placed and report["finite"]
    r = np.array(report["radius"])
    moved = report["x"] - report["x0"]

    assert np.median(moved[:, 0]) > 0.1  # pushed sideways
    d_min = 2.0 * r.min()
    assert excess(report["x"], r) < 0.01 * d_min
    settled = regopack.settled(spheres, dump_path(path), "lammps")
    np.testing.assert_allclose(settled.centre, report["x"], atol=1e-12)


# ---------------------------------------------------------------------------
# LAMMPS bodies: the side wall is a ring of fixed plates

TILTED_G = 2.0
"""Gravity of the tilted LAMMPS runs of bodies: 1 000 steps move the free cubes sideways by
about a quarter of their size."""

SIDE_SLACK = CORNER_GAP + 0.005
"""How far a rounded cube may reach past the side wall, as a fraction of d_min: the corners
of the plates' polygon (CORNER_GAP, 1 %) and the overlap of the body pair's linear springs
under the tilted weight and the impacts (measured below 0.1 %; 0.5 % allowed)."""


@pytest.fixture(scope="module")
def turned_cubes() -> Packing:
    """The cubes turned off the axes (LAMMPS cannot take edges parallel to x or y)."""
    return cylinder_cubes(turn=0.1)


def body_points(report: dict, n: int, rounding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Core vertices of the first ``n`` bodies where LAMMPS left them, and their rounding."""
    verts = report["vertices"]
    verts = verts[verts[:, 0] <= n]
    return verts[:, 1:4], rounding[verts[:, 0].astype(int) - 1]


def plate_blocks(path: Path, n: int) -> list[np.ndarray]:
    """Core vertices (box frame, relative to the centre) of the plates of a data file."""
    from test_lammps_export import solid_blocks

    blocks = solid_blocks(path.read_text())
    return [np.array(values[6 : 6 + 3 * h[3]]).reshape(-1, 3) for h, values in blocks[n:]]


def test_lammps_walls_bodies_in_a_cylinder_with_a_ring_of_plates(turned_cubes, tmp_path) -> None:
    from test_lammps_export import solid_blocks

    from regopack.plugins.exporters.lammps_export import polyhedron_bodies

    cubes = turned_cubes
    path = LammpsExporter().export(cubes, tmp_path / "p.data")
    text, script = path.read_text(), script_path(path).read_text()
    n, c = cubes.n_placed, CYLINDER
    d_min, d_max = 2.0 * float(cubes.radius.min()), 2.0 * float(cubes.radius.max())
    r_w = 0.05 * 0.5 * d_min  # the smallest grain's rounding radius
    wall = side_wall(c, r_w, d_min, d_max)
    atoms = n + wall.count
    assert f"{atoms} atoms\n{atoms} bodies\n2 atom types" in text
    assert wall.corner_gap <= CORNER_GAP * d_min
    # the plates: type 2, ids after the grains', their rounded inner faces on the circle
    rows = text.split("Atoms # body\n\n", 1)[1].split("\n\n", 1)[0].splitlines()
    table = np.array([row.split() for row in rows], dtype=float)
    assert table[:n, 1].tolist() == [1.0] * n and table[n:, 1].tolist() == [2.0] * wall.count
    blocks = solid_blocks(text)
    assert [b[0][0] for b in blocks] == list(range(1, atoms + 1))
    bodies = polyhedron_bodies(cubes)
    np.testing.assert_allclose(table[:n, 4:7], bodies.position)
    around, heights = [], []
    for k, local in enumerate(plate_blocks(path, n)):
        points = local + table[n + k, 4:7]
        assert blocks[n + k][1][-1] == pytest.approx(2 * r_w)
        assert blocks[n + k][1][3:6] == [0.0, 0.0, 0.0]  # isotropic inertia: box frame kept
        axis = np.array([c.cx, c.cy])
        mid = table[n + k, 4:6] - axis
        normal = mid / np.linalg.norm(mid)
        inner = (points[:, :2] - axis) @ normal
        assert inner.min() - r_w == pytest.approx(c.radius, abs=1e-12)  # tangent to the circle
        extent = np.ptp(points, axis=0)
        assert extent[2] <= d_max and np.hypot(*extent[:2]) <= 1.1 * d_max  # about a grain
        heights.append(points[:, 2])
        around.append(np.arctan2(normal[1], normal[0]))
    z = np.concatenate(heights)  # past the floor and the lid, by more than the rounding
    assert z.min() < c.zmin - r_w and z.max() > c.zmax + r_w
    steps = np.diff(np.sort(np.unique(np.round(around, 9))))
    assert steps == pytest.approx(2 * np.pi / wall.segments)  # the whole ring, evenly
    # the box holds every rounded plate
    lo = np.array([float(v) for v in re.findall(r"^(\S+) \S+ [xyz]lo", text, re.M)])
    hi = np.array([float(v) for v in re.findall(r"^\S+ (\S+) [xyz]lo", text, re.M)])
    for k, local in enumerate(plate_blocks(path, n)):
        points = local + table[n + k, 4:7]
        assert np.all(points - r_w >= lo - 1e-12) and np.all(points + r_w <= hi + 1e-12)
    # only the grains are integrated, pulled, walled, counted and dumped
    assert "group        plates type 2\ngroup        grains subtract all plates\n" in script
    assert "neigh_modify exclude type 2 2" in script
    for line in (
        "integrate grains nve/body",
        "weight grains gravity",
        "disp grains displace",
        "q grains property/atom",
        "q0 grains store/state",
        "write_dump   grains custom",
        "thermo_style custom step v_grains ke pe",
        "temp t_grains norm no",
    ):
        assert line in script, line
    assert (
        f"wall1 grains wall/body/polyhedron ${{k_n}} ${{c_n}} ${{c_t}} zplane {c.zmin} "
        f"{c.zmax}\n" in script
    )
    assert script.count("wall/body/polyhedron") == 1 and " all " not in script.split("plates\n")[1]


def test_lammps_holds_bodies_still_in_a_cylinder(turned_cubes, tmp_path) -> None:
    """1 000 steps without gravity: no NaN, no body lost, no cube moves, the plates stay."""
    cubes = turned_cubes
    path = LammpsExporter().export(cubes, tmp_path / "p.data")
    report = simulate(path, [1000])
    n = cubes.n_placed
    d_min = 2.0 * float(cubes.radius.min())
    assert report["natoms"] == n + len(plate_blocks(path, n)) and report["finite"]
    assert np.abs(report["x"][:n] - report["x0"][:n]).max() < 0.01 * d_min
    assert np.array_equal(report["x"][n:], report["x0"][n:])  # never integrated
    assert max(report["ke"]) < 1e-12 * n


def test_lammps_holds_spheres_written_as_bodies_still_in_a_cylinder(spheres, tmp_path) -> None:
    path = LammpsExporter(LammpsConfig(spheres="bodies")).export(spheres, tmp_path / "p.data")
    assert "atom_style   body rounded/polyhedron 1 12" in script_path(path).read_text()
    report = simulate(path, [1000])
    n = spheres.n_placed
    d_min = 2.0 * float(spheres.solids.rounding_radius.min())
    assert report["natoms"] > n and report["finite"]
    assert np.abs(report["x"][:n] - report["x0"][:n]).max() < 0.01 * d_min


def tilted_run(cubes: Packing, path: Path) -> tuple[dict, float, float]:
    """Export, tilt the gravity towards +x, run 1 000 steps; return the report and how far
    the rounded cubes reach past the side wall and past the floor or lid (over d_min)."""
    from regopack.plugins.exporters.lammps_export import polyhedron_bodies

    LammpsExporter().export(cubes, path)
    tilt(script_path(path), "gravity ${g} vector 0 0 -1", "gravity ${g} vector 1 0 -1")
    report = simulate(path, [1000], g=TILTED_G)
    points, r = body_points(report, cubes.n_placed, polyhedron_bodies(cubes).rounding)
    c, d_min = CYLINDER, 2.0 * float(cubes.radius.min())
    side = np.hypot(points[:, 0] - c.cx, points[:, 1] - c.cy) + r - c.radius
    ends = np.maximum(c.zmin - (points[:, 2] - r), points[:, 2] + r - c.zmax)
    return report, float(side.max()) / d_min, float(ends.max()) / d_min


def test_lammps_keeps_bodies_in_the_cylinder_under_tilted_gravity(turned_cubes, tmp_path) -> None:
    from regopack.plugins.exporters.lammps_export import polyhedron_bodies

    cubes = turned_cubes
    path = tmp_path / "p.data"
    report, side, ends = tilted_run(cubes, path)
    n = cubes.n_placed
    assert report["natoms"] > n and report["finite"]
    moved = report["x"][:n] - report["x0"][:n]
    assert np.median(moved[:, 0]) > 0.1  # pushed sideways
    assert side < SIDE_SLACK and ends < 0.01
    # read back: the settled cubes, exported again, have their cores where LAMMPS left them
    settled = regopack.settled(cubes, dump_path(path), "lammps")
    assert settled.stats["settled_steps"] == 1000 and settled.n_placed == n
    again = polyhedron_bodies(settled)
    verts = report["vertices"]
    for k, core in enumerate(again.cores):
        ours = core.vertices + again.position[k]
        theirs = verts[verts[:, 0] == k + 1, 1:4]
        order = np.lexsort(ours.T[::-1]), np.lexsort(theirs.T[::-1])
        np.testing.assert_allclose(ours[order[0]], theirs[order[1]], atol=1e-9)


def test_a_side_wall_farther_out_lets_the_cubes_out(turned_cubes, tmp_path, monkeypatch) -> None:
    """The check above fails when the plates stand 5 % of the radius farther out."""
    from dataclasses import replace

    import regopack.plugins.exporters.lammps_export as module

    def farther(domain, *args):
        return side_wall(replace(domain, radius=1.05 * domain.radius), *args)

    monkeypatch.setattr(module, "side_wall", farther)
    report, side, _ = tilted_run(turned_cubes, tmp_path / "p.data")
    assert report["finite"] and side > 5 * SIDE_SLACK


# ---------------------------------------------------------------------------
# LIGGGHTS


def run_liggghts(path: Path, **variables: float) -> dict:
    """Run ``liggghts`` on the exported script (the runner of the LIGGGHTS tests)."""
    from test_liggghts_export import run_liggghts as run

    return run(path, **variables)


def test_liggghts_script_has_the_cylinder(spheres, tmp_path) -> None:
    from regopack.plugins.exporters.liggghts_export import LiggghtsExporter
    from regopack.plugins.exporters.liggghts_export import script_path as liggghts_script

    path = LiggghtsExporter().export(spheres, tmp_path / "p.data")
    script = liggghts_script(path).read_text()
    walls = re.findall(r"^fix +(\w+) all wall/gran .* primitive type 1 (.*)$", script, re.M)
    c = CYLINDER
    assert walls == [
        ("wall_side", f"zcylinder {c.radius} {c.cx} {c.cy}"),
        ("wall_zlo", f"zplane {c.zmin}"),
        ("wall_zhi", f"zplane {c.zmax}"),
    ]


def test_liggghts_holds_spheres_still_in_a_cylinder(spheres, tmp_path) -> None:
    from regopack.plugins.exporters.liggghts_export import LiggghtsExporter

    path = LiggghtsExporter().export(spheres, tmp_path / "p.data")
    report = run_liggghts(path, steps=1000)
    final = report["final"]
    d_min = 2.0 * float(spheres.solids.rounding_radius.min())
    assert report["natoms"] == final.shape[0] == spheres.n_placed
    assert set(report["atoms"]) == {spheres.n_placed} and np.isfinite(final).all()
    assert np.abs(final[:, 2:5] - spheres.centre).max() < 0.01 * d_min


def test_liggghts_keeps_spheres_in_the_cylinder_under_tilted_gravity(spheres, tmp_path) -> None:
    from regopack.plugins.exporters.liggghts_export import LiggghtsExporter
    from regopack.plugins.exporters.liggghts_export import dump_path as liggghts_dump
    from regopack.plugins.exporters.liggghts_export import script_path as liggghts_script

    path = LiggghtsExporter().export(spheres, tmp_path / "p.data")
    tilt(liggghts_script(path), "gravity ${g} vector 0 0 -1", "gravity ${g} vector 1 0 -1")
    report = run_liggghts(path, steps=3000, g=0.05)
    final = report["final"]
    assert set(report["atoms"]) == {spheres.n_placed} and np.isfinite(final).all()
    moved = final[:, 2:5] - spheres.centre

    assert np.median(moved[:, 0]) > 0.1  # pushed sideways
    assert excess(final[:, 2:5], final[:, 5]) < 0.01 * 2.0 * final[:, 5].min()
    settled = regopack.settled(spheres, liggghts_dump(path), "liggghts")
    np.testing.assert_allclose(settled.centre, final[:, 2:5], atol=1e-12)


# ---------------------------------------------------------------------------
# YADE

TILTED = """
exec(open({script!r}).read())
O.run({rest}, True)
save_state("rest.txt")
O.engines[-1].gravity = ({g!r}, 0, -{g!r})
O.run({steps}, True)
save_state()
with open("bodies.after", "w") as out:
    for body_id, index in sorted(DRAW_INDEX.items(), key=lambda item: item[1]):
        b = O.bodies[body_id]
        points = [b.state.pos + b.state.ori * v for v in b.shape.v] if POLYHEDRA else [b.state.pos]
        radius = 0.0 if POLYHEDRA else b.shape.radius
        out.write(repr(radius) + " " + " ".join(repr(float(c)) for p in points for c in p) + "\\n")
"""


def run_yade_tilted(path: Path, rest: int, g: float, steps: int) -> tuple[np.ndarray, list]:
    """Run the export at rest for ``rest`` steps, then under gravity ``g`` tilted by 45°
    towards +x; return the state at rest and every body's points and radius at the end."""
    from test_yade_export import read_state, run_yade

    check = path.with_name("tilted.py")
    check.write_text(TILTED.format(script=path.name, rest=rest, g=g, steps=steps))
    run_yade(check)
    rest_state = np.array(
        [line.split() for line in path.with_name("rest.txt").read_text().splitlines()[3:]],
        dtype=float,
    )
    _, state = read_state(path)
    assert np.isfinite(state).all() and np.isfinite(rest_state).all()
    bodies = []
    for line in path.with_name("bodies.after").read_text().splitlines():
        values = np.array(line.split(), dtype=float)
        bodies.append((values[1:].reshape(-1, 3) / 1e-6, values[0] / 1e-6))
    return rest_state, bodies


def yade_excess(bodies: list) -> float:
    """How far the farthest point of a body reaches past the cylinder."""
    return max(excess(points, np.full(len(points), radius)) for points, radius in bodies)


def test_yade_script_has_the_side_wall(cubes, tmp_path) -> None:
    from regopack.plugins.exporters.yade_export import YadeExporter

    text = YadeExporter().export(cubes, tmp_path / "p.py").read_text()
    c = CYLINDER
    found = re.search(r"^CYLINDER = \((\S+), (\S+), (\S+), (\d+)\)", text, re.M)
    assert found is not None
    cx, cy, radius, n = (float(v) for v in found.groups())
    assert (cx, cy, radius) == pytest.approx((c.cx * 1e-6, c.cy * 1e-6, c.radius * 1e-6))
    d_min = 2.0 * float(cubes.radius.min())
    assert c.radius * (1 / np.cos(np.pi / n) - 1) <= 0.01 * d_min  # corners close to the circle
    assert "Ig2_Facet_Polyhedra_PolyhedraGeom()" in text and "Bo1_Facet_Aabb()" in text


def test_yade_keeps_spheres_in_the_cylinder(spheres, tmp_path) -> None:
    from regopack.plugins.exporters.yade_export import YadeExporter, state_path

    path = YadeExporter().export(spheres, tmp_path / "p.py")
    assert "Ig2_Facet_Sphere_ScGeom()" in path.read_text()
    rest, bodies = run_yade_tilted(path, 1000, 1e5, 3000)
    d_min = 2.0 * float(spheres.solids.rounding_radius.min())
    assert rest.shape[0] == spheres.n_placed
    assert np.abs(rest[:, 4:7]).max() / 1e-6 < 0.01 * d_min  # at rest nothing moved
    centre = np.array([p[0] for p, _ in bodies])
    assert np.median(centre[:, 0] - spheres.centre[:, 0]) > 0.1  # pushed sideways
    assert yade_excess(bodies) < 0.01 * d_min
    settled = regopack.settled(spheres, state_path(path), "yade")
    np.testing.assert_allclose(settled.centre, centre, atol=1e-6)


def test_yade_keeps_polyhedra_in_the_cylinder(cubes, tmp_path) -> None:
    from regopack.plugins.exporters.yade_export import YadeExporter, state_path

    path = YadeExporter().export(cubes, tmp_path / "p.py")
    rest, bodies = run_yade_tilted(path, 1000, 1e7, 300)
    d_min = 2.0 * float(cubes.radius.min())
    assert rest.shape[0] == cubes.n_placed
    assert np.abs(rest[:, 4:7]).max() / 1e-6 < 0.01 * d_min  # at rest nothing moved
    centre = np.array([p.mean(axis=0) for p, _ in bodies])
    assert np.median(centre[:, 0] - cubes.centre[:, 0]) > 0.1  # pushed sideways
    assert yade_excess(bodies) < 0.05 * d_min
    settled = regopack.settled(cubes, state_path(path), "yade")
    assert settled.n_placed == cubes.n_placed


# ---------------------------------------------------------------------------
# the other 3D exporters


def test_voxels_outside_the_cylinder_are_neither_solid_nor_pore(spheres, tmp_path) -> None:
    ps = pytest.importorskip("porespy", reason="PoreSpy (test extra) analyses the image")
    from regopack.plugins.exporters.image_export import ImageConfig, ImageExporter, image_paths

    h = 0.1
    path = ImageExporter(ImageConfig(pixel_size=h)).export(spheres, tmp_path / "p.png")
    im = np.load(image_paths(path)["phases"])
    assert im.shape == (100, 100, 100)
    c = CYLINDER
    inside = im != 2
    # the voxels inside: those of the circle in every layer (its area within the voxel error)
    assert inside.sum() * h**3 == pytest.approx(c.volume, rel=4 * h / c.radius)
    assert np.array_equal(inside[0], inside[-1])
    solid = sum(4 / 3 * np.pi * r**3 for r in spheres.solids.rounding_radius)
    phi = solid / c.volume
    assert spheres.phi == pytest.approx(phi, rel=1e-12)
    assert ps.metrics.porosity(im) == pytest.approx(1 - phi, abs=0.002)
    # solid outside the cylinder, or pore, would give another porosity
    assert abs(ps.metrics.porosity(np.where(inside, im, 0)) - (1 - phi)) > 0.1
    assert abs(ps.metrics.porosity(np.where(inside, im, 1)) - (1 - phi)) > 0.01


def test_sections_of_a_cylinder_lie_in_its_circle_or_chord(spheres, tmp_path) -> None:
    from regopack.base.errors import ConfigError
    from regopack.geometry.domain import Circle, Rectangle
    from regopack.plugins.exporters.slice_export import SliceConfig, slice_packing

    c = CYLINDER
    level = slice_packing(spheres, SliceConfig(axis="z", at=1.0))
    assert level.domain == Circle(c.cx, c.cy, c.radius)
    assert level.n_placed == 9  # the lower ring and the sphere on the axis
    assert level.stats["slice_phi"] == pytest.approx((8 + 1.2**2 - 0.2**2) / c.radius**2, rel=0.01)
    side = slice_packing(spheres, SliceConfig(axis="x", at=c.cx + 3.0))
    assert side.domain == Rectangle(c.cy - 4.0, c.cy + 4.0, c.zmin, c.zmax)
    with pytest.raises(ConfigError, match="outside the box along y"):
        slice_packing(spheres, SliceConfig(axis="y", at=c.cy + c.radius + 0.0))
    for to in ("slice", "gsd", "image"):
        regopack.export(spheres, to, tmp_path / f"p-{to}")
    for to in ("vtk", "stl", "gsd", "yade", "image", "slice"):
        regopack.export(cylinder_cubes(), to, tmp_path / f"c-{to}")


def test_the_yade_constants_each_have_their_own_documentation():
    """Each constant of the YADE exporter is followed by the string that documents it."""
    import ast
    import inspect
    import itertools

    from regopack.plugins.exporters import yade_export

    body = ast.parse(inspect.getsource(yade_export)).body
    docs: dict[str, str] = {}
    for here, after in itertools.pairwise(body):
        if isinstance(here, ast.Assign) and isinstance(here.targets[0], ast.Name):
            if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant):
                docs[here.targets[0].id] = str(after.value.value)
    assert "verletDist" in docs["VERLET_FRACTION"]
    assert "facets" in docs["FACET_GAP"] and "Fewest facets" in docs["MIN_SEGMENTS"]
    strings = [n for n in body if isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)]
    assert len(strings) == 1 + len(docs)  # the module's docstring and one per constant
