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


def test_lammps_refuses_bodies_in_a_cylinder_in_one_line(cubes, spheres, tmp_path, capsys) -> None:
    """LAMMPS' wall/body/polyhedron has planes only: no side wall for bodies."""
    from regopack.base.errors import ExportError
    from regopack.cli import main
    from regopack.packing.core import save

    with pytest.raises(ExportError, match="fix wall/body/polyhedron has planes only"):
        LammpsExporter().export(cubes, tmp_path / "c.data")
    with pytest.raises(ExportError, match="fix wall/body/polyhedron has planes only"):
        LammpsExporter(LammpsConfig(spheres="bodies")).export(spheres, tmp_path / "s.data")
    assert not list(tmp_path.iterdir())
    save(cubes, tmp_path / "c.npz")
    assert main(["export", str(tmp_path / "c.npz"), "--to", "lammps"]) != 0
    err = capsys.readouterr().err.strip()
    assert "planes only" in err and "Traceback" not in err and len(err.splitlines()) == 1


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
