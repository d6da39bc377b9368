"""The YADE export of 3D packings, built and run by the real ``yade``."""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import one_error_line
from packings3d import cube_and_sphere, packing3d, spheres3d
from pydantic import ValidationError
from scipy.spatial.transform import Rotation

import regopack
from regopack.base.errors import ConfigError, ExportError
from regopack.cli import main
from regopack.geometry.domain import PeriodicBox
from regopack.packing.core import Packing, save
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.plugins.exporters.yade_export import (
    STATE_FORMAT,
    YadeConfig,
    YadeExporter,
    bodies_path,
    state_path,
)
from regopack.testing import packing_from_polygons

YADE = shutil.which("yade")


@functools.cache
def dem3d_like() -> Packing:
    """The ``dem3d`` scene in a 40 µm cube with sizes up to 12 µm: 505 polyhedra."""
    scene = regopack.scene(
        "dem3d",
        domain__width=40,
        domain__height=40,
        domain__depth=40,
        size__d_max=12,
        insertion__strip=20,
    )
    return regopack.pack(scene, verify=False)


def body_lines(path: Path) -> list[list[str]]:
    """The words of every body line of a bodies file."""
    lines = bodies_path(path).read_text().splitlines()
    return [line.split() for line in lines if line and not line.startswith("#")]


def test_the_bodies_file_holds_every_vertex_exactly() -> None:
    packing = packing3d()
    path = Path("/nonexistent/p.py")
    exporter = YadeExporter(YadeConfig(length_scale=1.0))
    text = exporter_text(exporter, packing, path)
    rows = [line.split() for line in text.splitlines() if not line.startswith("#")]
    solids = placed_solids(packing, "yade")
    assert [int(r[0]) for r in rows] == [p.index for p in solids]  # draw order
    for row, p in zip(rows, solids, strict=True):
        assert int(row[1]) == packing.mineral[p.index]
        assert int(row[2]) == len(p.local) and float(row[3]) == 0.0
        points = np.array(row[4:], dtype=float).reshape(-1, 3)
        np.testing.assert_array_equal(points, p.world)  # the shortest round-trip text


def exporter_text(exporter: YadeExporter, packing: Packing, path: Path) -> str:
    """The bodies file's text, written by the exporter without touching ``path``."""
    from regopack.plugins.exporters import yade_export

    solids = placed_solids(packing, "yade", spheres=True)
    scale = exporter.config.length_scale or 1e-6
    return yade_export._bodies_text(packing, solids, scale)


def test_the_script_sets_materials_per_mineral_and_only_the_engines_it_needs(tmp_path) -> None:
    cfg = YadeConfig(mineral_density={"pyroxene": 3400.0}, mineral_friction={"glass": 0.3})
    path = YadeExporter(cfg).export(packing3d(), tmp_path / "p.py")
    script = path.read_text()
    assert (
        "DENSITY = {'plagioclase': 3100.0, 'pyroxene': 3400.0, 'glass': 3100.0}" in script
        and "FRICTION = {'plagioclase': 0.5, 'pyroxene': 0.5, 'glass': 0.3}" in script
    )
    assert "Polyhedra" in script and "Sphere_Sphere" not in script and "PERIODIC = False" in script
    assert "SPHERES = False" in script and "POLYHEDRA = True" in script
    lower = re.search(r"^LOWER = \(([^)]*)\)", script, re.M)[1]  # metres, from µm
    np.testing.assert_allclose(eval(lower), packing3d().domain.bounds()[::2] * 1e-6, rtol=1e-15)
    spheres = YadeExporter().export(spheres3d(30.0), tmp_path / "s.py").read_text()
    assert "Ig2_Sphere_Sphere_ScGeom" in spheres and "Polyhedra_Polyhedra" not in spheres
    mixed = YadeExporter().export(cube_and_sphere(), tmp_path / "m.py").read_text()
    assert "Ig2_Sphere_Polyhedra_ScGeom" in mixed and "Ip2_FrictMat_PolyhedraMat" in mixed
    compile(script, "p.py", "exec")  # plain Python, whatever YADE adds to it


def test_wrong_parameters_and_packings_are_refused_in_one_line(tmp_path, capsys) -> None:
    with pytest.raises(ValidationError):
        YadeConfig(youngs_modulus=-1.0)
    with pytest.raises(ValidationError):
        YadeConfig(dt_fraction=2.0)
    with pytest.raises(ConfigError, match="mineral_friction names 'basalt'"):
        YadeExporter(YadeConfig(mineral_friction={"basalt": 0.1})).export(
            packing3d(), tmp_path / "p.py"
        )
    with pytest.raises(ExportError, match="no positive finite mass"):
        YadeExporter(YadeConfig(length_scale=1e-200)).export(packing3d(), tmp_path / "p.py")
    small = packing3d()  # 12 µm grains in a 20 µm periodic box: more than half a side
    periodic = dataclasses.replace(small, domain=PeriodicBox(*small.domain.bounds()))
    with pytest.raises(ExportError, match="half the periodic box's side"):
        YadeExporter().export(periodic, tmp_path / "p.py")
    assert not list(tmp_path.iterdir())  # nothing written by a refusal
    plane = packing_from_polygons([np.array([[0.0, 0], [1, 0], [0, 1]])])
    file = tmp_path / "plane.npz"
    save(plane, file)
    assert main(["export", str(file), "--to", "yade"]) == 2
    line = one_error_line(capsys)
    assert "'yade'" in line and "3D" in line


def test_the_command_writes_the_script_and_its_bodies(tmp_path, capsys) -> None:
    file = tmp_path / "packing.npz"
    save(packing3d(), file)
    assert main(["export", str(file), "--to", "yade", "--set", "yade.gravity=9.81"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'packing.py'}"
    assert "\nGRAVITY = 9.81  #" in (tmp_path / "packing.py").read_text()
    assert len(body_lines(tmp_path / "packing.py")) == packing3d().n_placed


# ---------------------------------------------------------------------------
# The real program

CHECK = """
exec(open({script!r}).read())
with open("bodies.check", "w") as out:
    for body_id, index in sorted(DRAW_INDEX.items(), key=lambda item: item[1]):
        b = O.bodies[body_id]
        if isinstance(b.shape, Polyhedra):
            points = [b.state.pos + b.state.ori * v for v in b.shape.v]
            volume = b.shape.GetVolume()
        else:
            points = [b.state.pos]
            volume = 4.0 / 3.0 * math.pi * b.shape.radius ** 3
        out.write(" ".join(repr(float(x)) for x in
                  [index, b.state.mass, volume, len(points)] + [c for p in points for c in p]))
        out.write("\\n")
"""


def run_yade(path: Path, *args: str, timeout: float = 300) -> str:
    """Run ``yade -n -x`` on the script ``path`` with ``args``; return its output."""
    if YADE is None:
        pytest.skip("the yade executable is not on PATH (Debian: apt-get install yade)")
    done = subprocess.run(
        [YADE, "-f1", "-n", "-x", path.name, *args],
        cwd=path.parent,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=timeout,
        check=False,
    )
    out = done.stdout + done.stderr
    assert done.returncode == 0 and "Traceback" not in out, out[-3000:]
    return out


def read_state(path: Path) -> tuple[dict[str, float], np.ndarray]:
    """The header numbers and the rows of the final state the script wrote."""
    lines = state_path(path).read_text().splitlines()
    assert lines[0] == STATE_FORMAT
    head = dict(re.findall(r"(steps|time|dt|bodies) ([^,]+)", lines[1]))
    table = np.array([line.split() for line in lines[3:]], dtype=float)
    return {k: float(v) for k, v in head.items()}, table


def check_bodies(
    path: Path, packing: Packing, density: dict[str, float] | None = None, origin=(0, 0, 0)
) -> None:
    """YADE built every placed particle with its exact vertices, volume and mass.

    ``density`` by mineral name (3100 for the others); ``origin``: the corner
    that the script's frame starts at (a periodic box's lower corner)."""
    check = path.with_name("check.py")
    check.write_text(CHECK.format(script=path.name))
    run_yade(check)
    rows = [line.split() for line in path.with_name("bodies.check").read_text().splitlines()]
    solids = placed_solids(packing, "yade", spheres=True)
    assert [int(float(r[0])) for r in rows] == [p.index for p in solids]
    scale = 1e-6
    for row, p in zip(rows, solids, strict=True):
        mass, volume, n = float(row[1]), float(row[2]), int(float(row[3]))
        points = np.array(row[4:], dtype=float).reshape(n, 3)
        if p.loops:
            want = (p.world - origin) * scale
            exact = mass_properties(p.local, p.loops)[0] * scale**3
        else:
            want = (p.centre[None, :] - origin) * scale
            exact = 4 / 3 * math.pi * (p.rounding * scale) ** 3
        name = packing.mineral_names[packing.mineral[p.index]]
        rho = (density or {}).get(name, 3100.0)
        # YADE keeps the vertices of the convex hull in its principal frame: the same
        # points, in another order, within rounding
        order = np.lexsort(points.T[::-1]), np.lexsort(want.T[::-1])
        np.testing.assert_allclose(points[order[0]], want[order[1]], rtol=0, atol=1e-12 * scale)
        assert volume == pytest.approx(exact, rel=1e-12)
        assert mass == pytest.approx(rho * exact, rel=1e-12)


def test_yade_builds_every_polyhedron_exactly_and_holds_the_packing_still(tmp_path) -> None:
    """505 polyhedra of the dem3d scene: exact bodies, then steps without gravity."""
    packing = dem3d_like()
    assert packing.n_placed >= 500
    density = {"ilmenite": 4700.0, "glass": 2400.0}
    path = YadeExporter(YadeConfig(mineral_density=density)).export(packing, tmp_path / "p.py")
    check_bodies(path, packing, density)
    out = run_yade(path, "--run", "20")
    assert f"regopack: {packing.n_placed} bodies" in out
    head, state = read_state(path)
    assert head["steps"] == 20 and state.shape == (packing.n_placed, 16)
    assert np.isfinite(state).all()
    d_min = float(re.search(r"^VOLUMETRIC_LENGTH = (\S+)", path.read_text(), re.M)[1])
    assert np.linalg.norm(state[:, 4:7], axis=1).max() < 0.01 * d_min


@pytest.mark.slow  # about 7 minutes: YADE spends 0.4 s a step on 505 touching polyhedra
def test_yade_holds_505_polyhedra_still_for_1000_steps(tmp_path) -> None:
    packing = dem3d_like()
    path = YadeExporter().export(packing, tmp_path / "p.py")
    run_yade(path, "--run", "1000", timeout=3600)
    head, state = read_state(path)
    assert head["steps"] == 1000 and state.shape[0] == packing.n_placed >= 500
    assert np.isfinite(state).all()
    d_min = float(re.search(r"^VOLUMETRIC_LENGTH = (\S+)", path.read_text(), re.M)[1])
    assert np.linalg.norm(state[:, 4:7], axis=1).max() < 0.01 * d_min


def check_settled(packing: Packing, path: Path, state: np.ndarray, g: float, time: float) -> None:
    """Under gravity the bodies fell, no faster than free fall, and none left the box."""
    scale = 1e-6
    drop = -state[:, 6]
    assert np.median(drop) > 0.2 * 0.5 * g * time**2  # gravity acts ...
    assert drop.max() <= 0.5 * g * time**2 * (1 + 1e-9)  # ... no faster than free fall
    lo, hi = packing.domain.bounds().reshape(3, 2).T * scale
    assert np.all(state[:, 1:4] > lo) and np.all(state[:, 1:4] < hi)  # every centroid inside


SETTLE = """
exec(open({script!r}).read())
O.engines[-1].gravity = (0, 0, -{g!r})
O.run({steps}, True)
save_state()
with open("bodies.after", "w") as out:
    for body_id, index in sorted(DRAW_INDEX.items(), key=lambda item: item[1]):
        b = O.bodies[body_id]
        points = [b.state.pos + b.state.ori * v for v in b.shape.v]
        out.write(" ".join(repr(float(c)) for p in points for c in p) + "\\n")
"""


def test_yade_settles_polyhedra_inside_their_walls_and_they_read_back(tmp_path) -> None:
    packing = packing3d()  # 57 polyhedra in a 20 µm box
    path = YadeExporter().export(packing, tmp_path / "p.py")
    g, steps = 1e7, 300
    check = tmp_path / "settle.py"  # a user's script that loads the export and goes on
    check.write_text(SETTLE.format(script=path.name, g=g, steps=steps))
    run_yade(check)
    head, state = read_state(path)
    # the settled packing holds every polyhedron where YADE left it
    settled = regopack.settled(packing, state_path(path), "yade")
    after = path.with_name("bodies.after").read_text().splitlines()
    for j, line in zip(np.flatnonzero(packing.placed), after, strict=True):
        yade_points = np.array(line.split(), dtype=float).reshape(-1, 3) / 1e-6
        ours = settled.world_vertices(j)
        order = np.lexsort(yade_points.T[::-1]), np.lexsort(ours.T[::-1])
        np.testing.assert_allclose(yade_points[order[0]], ours[order[1]], rtol=0, atol=1e-9)
    assert settled.stats["settled_steps"] == steps
    assert np.isfinite(state).all()
    check_settled(packing, path, state, g, head["time"])
    # the floor holds the bottom bodies: the volumetric law lets a corner into it, by less
    # than half the smallest grain under this gravity, and none passes through
    lowest = []
    for p, row in zip(placed_solids(packing, "yade"), state, strict=True):
        centroid = row[1:4] - row[4:7]  # where it was
        turn = row[7:].reshape(3, 3)
        lowest.append(((p.world * 1e-6 - centroid) @ turn.T + row[1:4])[:, 2].min())
    d_min = float(re.search(r"^VOLUMETRIC_LENGTH = (\S+)", path.read_text(), re.M)[1])
    floor = packing.domain.bounds()[4] * 1e-6
    assert floor - 0.5 * d_min < min(lowest) < floor


def test_yade_holds_spheres_still_and_settles_them(tmp_path) -> None:
    packing = spheres3d(30.0)
    path = YadeExporter().export(packing, tmp_path / "p.py")
    check_bodies(path, packing)
    run_yade(path, "--run", "1000")
    head, state = read_state(path)
    assert head["steps"] == 1000 and state.shape[0] == packing.n_placed > 200
    assert np.isfinite(state).all()
    d_min = 2 * packing.solids.rounding_radius[packing.placed].min() * 1e-6
    assert np.linalg.norm(state[:, 4:7], axis=1).max() < 0.01 * d_min
    g, steps = 1e5, 3000
    run_yade(path, "--run", str(steps), "--gravity", repr(g))
    head, state = read_state(path)
    check_settled(packing, path, state, g, head["time"])
    settled = regopack.settled(packing, state_path(path), "yade")
    np.testing.assert_allclose(settled.centre[packing.placed], state[:, 1:4] / 1e-6, atol=1e-9)
    radius = packing.solids.rounding_radius[packing.placed] * 1e-6
    lo = packing.domain.bounds()[4] * 1e-6
    assert (state[:, 3] - radius).min() > lo - 0.05 * radius.min()  # on the floor, not through


def test_yade_runs_spheres_in_a_periodic_cell(tmp_path) -> None:
    packing = spheres3d(30.0)
    shift = np.array([-40.0, 5.0, -12.5])  # a box whose lower corner is not the origin
    lo, hi = packing.domain.bounds().reshape(3, 2).T + shift
    periodic = dataclasses.replace(
        packing,
        domain=PeriodicBox(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]),
        centre=packing.centre + shift,
    )
    path = YadeExporter().export(periodic, tmp_path / "p.py")
    assert "PERIODIC = True" in path.read_text()
    check_bodies(path, periodic, origin=lo)
    run_yade(path, "--run", "1000")
    _, state = read_state(path)
    assert np.isfinite(state).all() and state.shape[0] == periodic.n_placed
    d_min = 2 * packing.solids.rounding_radius[packing.placed].min() * 1e-6
    assert np.linalg.norm(state[:, 4:7], axis=1).max() < 0.01 * d_min


def test_yade_runs_a_packing_of_polyhedra_and_spheres(tmp_path) -> None:
    packing = cube_and_sphere()
    path = YadeExporter(YadeConfig(length_scale=1e-6)).export(packing, tmp_path / "p.py")
    check_bodies(path, packing)
    run_yade(path, "--run", "200", "--gravity", "1e7")
    _, state = read_state(path)
    assert np.isfinite(state).all() and (state[:, 6] < 0).all()


def write_state(path: Path, packing: Packing, rows: list[str] | None = None) -> Path:
    """A state file of ``packing``'s bodies at rest, or with the given rows."""
    index = np.flatnonzero(packing.placed)
    rest = " ".join(["0.0"] * 6 + ["1.0", "0", "0", "0", "1.0", "0", "0", "0", "1.0"])
    lines = [STATE_FORMAT, "# steps 0, time 0.0", "# columns"]
    lines += rows if rows is not None else [f"{j} {rest}" for j in index]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_state_at_rest_gives_the_packing_back(tmp_path, capsys) -> None:
    packing = packing3d()
    file = tmp_path / "packing.npz"
    save(packing, file)
    state = write_state(tmp_path / "packing.final.txt", packing)
    assert main(["settled", str(file), str(state), "--from", "yade"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'packing.final.npz'}"
    back = regopack.load(tmp_path / "packing.final.npz")
    np.testing.assert_allclose(back.vertices, packing.vertices, atol=1e-12)
    np.testing.assert_allclose(back.centre[back.placed], packing.centre[packing.placed])
    assert back.stats["settled_steps"] == 0


@pytest.mark.parametrize(
    ("rows", "first", "message"),
    [
        (None, "something else", "not a YADE state written by regopack's script"),
        (["0 1 2"], None, "bodies of 16 columns expected"),
        ("nan", None, "not finite (the run blew up)"),
        ("shuffled", None, "draw indices are not the packing's placed particles"),
        ("stretched", None, "not a rotation matrix"),
    ],
)
def test_a_wrong_state_is_refused_in_one_line(tmp_path, capsys, rows, first, message) -> None:
    packing = packing3d()
    file = tmp_path / "packing.npz"
    save(packing, file)
    index = np.flatnonzero(packing.placed)
    rest = ["0.0"] * 6 + ["1.0", "0", "0", "0", "1.0", "0", "0", "0", "1.0"]
    if rows == "nan":
        rows = [" ".join([str(j), "nan", *rest[1:]]) for j in index]
    elif rows == "shuffled":
        rows = [" ".join([str(j), *rest]) for j in index[::-1]]
    elif rows == "stretched":
        rows = [" ".join([str(j), *rest[:6], "2.0", *rest[7:]]) for j in index]
    state = write_state(tmp_path / "s.txt", packing, rows)
    if first is not None:
        state.write_text(first + "\n" + state.read_text().split("\n", 1)[1])
    assert main(["settled", str(file), str(state), "--from", "yade"]) == 2
    line = one_error_line(capsys)
    assert str(state) in line and message in line
    assert not (tmp_path / "s.npz").exists()


def test_exporters_without_a_state_and_2d_packings_are_refused(tmp_path, capsys) -> None:
    file = tmp_path / "packing.npz"
    save(packing3d(), file)
    state = write_state(tmp_path / "s.txt", packing3d())
    assert main(["settled", str(file), str(state), "--from", "vtk"]) == 2
    line = one_error_line(capsys)
    assert "exporter 'vtk' reads no state back; these do: lammps, liggghts, yade" in line
    plane = tmp_path / "plane.npz"
    save(packing_from_polygons([np.array([[0.0, 0], [1, 0], [0, 1]])]), plane)
    assert main(["settled", str(plane), str(state), "--from", "yade"]) == 2
    assert "3D packings only" in one_error_line(capsys)


def test_a_sphere_on_the_floor_beside_polyhedra_runs(tmp_path) -> None:
    """Spheres and polyhedra meet walls of their own material (YADE asserts otherwise)."""
    packing = dataclasses.replace(cube_and_sphere(), centre=np.array([[3.0, 3, 5], [7.0, 3, 1]]))
    path = YadeExporter().export(packing, tmp_path / "p.py")
    run_yade(path, "--run", "50", "--gravity", "1e6")
    _, state = read_state(path)
    assert np.isfinite(state).all() and state[0, 6] < 0  # the cube falls onto the floor
    assert abs(state[1, 6]) < 1e-3 * 1e-6  # the sphere rests on it


def test_the_state_goes_beside_the_bodies_whatever_the_working_folder(tmp_path) -> None:
    (tmp_path / "runs").mkdir()
    (tmp_path / "mine").mkdir()
    path = YadeExporter().export(packing3d(), tmp_path / "runs" / "p.py")
    runner = tmp_path / "mine" / "go.py"  # a script of the user's, in another folder
    runner.write_text(
        "REGOPACK_BODIES = '../runs/p.bodies'\n"
        "exec(open('../runs/p.py').read())\n"
        "O.run(2, True)\n"
        "save_state()\n"
    )
    run_yade(runner)
    assert state_path(path).exists() and not list((tmp_path / "mine").glob("*.final.txt"))
    state_path(path).unlink()
    done = subprocess.run(  # yade started from elsewhere on the script itself
        [YADE, "-f1", "-n", "-x", "runs/p.py", "--run", "2"],
        cwd=tmp_path,
        capture_output=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0 and state_path(path).exists()


AXIS = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
"""A unit axis (YADE's Quaternion(axis, angle) takes it as it is)."""


def test_a_turned_body_reads_back_turned(tmp_path) -> None:
    """A polyhedron turned by hand in YADE: the state's rotation and the settled vertices."""
    packing = packing3d()
    path = YadeExporter().export(packing, tmp_path / "p.py")
    (tmp_path / "turn.py").write_text(
        SETTLE.format(script=path.name, g=0.0, steps=1).replace(
            "save_state()",
            "b = O.bodies[min(DRAW_INDEX)]\n"
            f"b.state.ori = Quaternion({tuple(AXIS.tolist())!r}, 1.1) * b.state.ori\n"
            "b.state.pos = b.state.pos + Vector3(1e-7, 0, -2e-7)\n"
            "save_state()",
        )
    )
    run_yade(tmp_path / "turn.py")
    _, state = read_state(path)
    want = Rotation.from_rotvec(1.1 * AXIS).as_matrix()
    np.testing.assert_allclose(state[0, 7:].reshape(3, 3), want, atol=1e-12)
    settled = regopack.settled(packing, state_path(path), "yade")
    after = path.with_name("bodies.after").read_text().splitlines()
    j = int(np.flatnonzero(packing.placed)[0])
    yade_points = np.array(after[0].split(), dtype=float).reshape(-1, 3) / 1e-6
    ours = settled.world_vertices(j)
    order = np.lexsort(yade_points.T[::-1]), np.lexsort(ours.T[::-1])
    np.testing.assert_allclose(yade_points[order[0]], ours[order[1]], atol=1e-9)
    assert np.abs(ours - packing.world_vertices(j)).max() > 0.1  # it did turn


def test_far_coordinates_and_odd_scene_names(tmp_path) -> None:
    with pytest.raises(ExportError, match="YADE builds polyhedra only up to 10000"):
        YadeExporter(YadeConfig(length_scale=1e4)).export(packing3d(), tmp_path / "p.py")
    odd = dataclasses.replace(packing3d(), scene={"name": "a\nprint('INJECTED')"})
    path = YadeExporter().export(odd, tmp_path / "q.py")
    text = path.read_text()
    compile(text, "q.py", "exec")
    assert "\nprint('INJECTED')" not in text
    assert "a?print('INJECTED')" in text.splitlines()[0]


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ("# steps abc, time 0.5", "header holds a value that is not a number"),
        ("# steps 3, time nan", "header holds a value that is not finite"),
        ("# steps 3, time 0.5, dt 1e-9, length scale 1e-06, bodies 57", None),
        ("# steps 3, time 0.5, dt 1e-9, length scale 1.0, bodies 57", "written with length"),
    ],
)
def test_the_state_s_header_is_checked(tmp_path, capsys, header, message) -> None:
    packing = packing3d()
    file = tmp_path / "packing.npz"
    save(packing, file)
    state = write_state(tmp_path / "s.txt", packing)
    lines = state.read_text().split("\n")
    state.write_text("\n".join([lines[0], header, *lines[2:]]))
    status = main(["settled", str(file), str(state), "--from", "yade"])
    if message is None:
        assert status == 0 and regopack.load(tmp_path / "s.npz").stats["settled_steps"] == 3
        return
    assert status == 2
    line = one_error_line(capsys)
    assert str(state) in line and message in line


def test_an_output_folder_that_does_not_exist_is_named(tmp_path, capsys) -> None:
    file = tmp_path / "packing.npz"
    save(packing3d(), file)
    state = write_state(tmp_path / "s.txt", packing3d())
    out = tmp_path / "nowhere" / "x.npz"
    assert main(["settled", str(file), str(state), "--from", "yade", "--out", str(out)]) == 2
    assert f"--out {out}: its folder {out.parent} does not exist" in one_error_line(capsys)
