"""The LIGGGHTS export of packings of spheres, read and run by the real ``liggghts``."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import one_error_line
from packings3d import cube_and_sphere, spheres3d
from pydantic import ValidationError

import regopack
from regopack.base.errors import ConfigError, ExportError, PackingFileError
from regopack.cli import main
from regopack.geometry.domain import PeriodicBox
from regopack.packing.core import Packing, save
from regopack.plugins.exporters.liggghts_export import (
    LiggghtsConfig,
    LiggghtsExporter,
    dump_path,
    script_path,
)
from regopack.testing import packing_from_polygons

LIGGGHTS = shutil.which("liggghts")


@pytest.fixture(scope="module")
def spheres() -> Packing:
    """224 spheres of three minerals in a walled 30 µm box."""
    return spheres3d(30.0)


@pytest.fixture(scope="module")
def periodic(spheres) -> Packing:
    return dataclasses.replace(spheres, domain=PeriodicBox(*spheres.domain.bounds()))


def data_atoms(text: str) -> np.ndarray:
    """``id type diameter density x y z`` of each atom of a data file."""
    rows = text.split("\nAtoms # granular\n", 1)[1].split()
    return np.array(rows, dtype=float).reshape(-1, 7)


def rayleigh_time(diameter: np.ndarray, density: np.ndarray, cfg: LiggghtsConfig) -> np.ndarray:
    """Rayleigh time of each sphere, written out here from its textbook form."""
    shear = cfg.youngs_modulus / (2 * (1 + cfg.poisson_ratio))
    speed = (0.1631 * cfg.poisson_ratio + 0.8766) * np.sqrt(shear / density)
    return np.pi * (diameter / 2) / speed


def test_the_data_file_and_the_script(spheres, tmp_path) -> None:
    cfg = LiggghtsConfig(mineral_density={"pyroxene": 3.4, "glass": 2.4})
    path = LiggghtsExporter(cfg).export(spheres, tmp_path / "p.data")
    text = path.read_text()
    assert text.startswith("LIGGGHTS data file from regopack")
    assert "# lengths = packing lengths (µm) x 1.0;" in text
    assert "\n224 atoms\n3 atom types\n\n-15.0 15.0 xlo xhi\n" in text
    atoms = data_atoms(text)
    idx = np.flatnonzero(spheres.placed)
    assert atoms.shape == (idx.size, 7) and idx.size == spheres.n_placed == 224
    np.testing.assert_array_equal(atoms[:, 0], np.arange(1, idx.size + 1))
    np.testing.assert_array_equal(atoms[:, 1], spheres.mineral[idx] + 1)
    np.testing.assert_array_equal(atoms[:, 2], 2 * spheres.solids.rounding_radius[idx])
    np.testing.assert_array_equal(atoms[:, 4:], spheres.centre[idx])
    by_name = dict(zip(spheres.mineral_names, (3.1, 3.4, 2.4), strict=True))
    names = np.array(spheres.mineral_names)[spheres.mineral[idx]]
    np.testing.assert_array_equal(atoms[:, 3], [by_name[n] for n in names])

    script = script_path(path).read_text()
    for line in (
        "units        micro",
        "atom_style   granular",
        "atom_modify  map array",
        "boundary     f f f",
        "newton       off",
        "communicate  single vel yes",
        "read_data    p.data",
        "fix          m1 all property/global youngsModulus peratomtype ${E} ${E} ${E}",
        "fix          m2 all property/global poissonsRatio peratomtype ${nu} ${nu} ${nu}",
        "fix          m3 all property/global coefficientRestitution peratomtypepair 3"
        + " ${e_n}" * 9,
        "fix          m4 all property/global coefficientFriction peratomtypepair 3" + " ${mu}" * 9,
        "pair_style   gran model hertz tangential history",
        "pair_coeff   * *",
        "fix          integrate all nve/sphere",
        "fix          gravi all gravity ${g} vector 0 0 -1",
        "variable steps index 10000",
        "variable E     index 100000.0   # Young's modulus (pressure)",
        "variable g     index 0.0   # gravity along -z (acceleration)",
        "run          ${steps}",
    ):
        assert f"\n{line}\n" in script, line
    walls = re.findall(
        r"^fix +wall_(\w+) all wall/gran model hertz tangential history primitive type 1 "
        r"([xyz])plane (\S+)$",
        script,
        re.M,
    )
    assert [(w, a, float(v)) for w, a, v in walls] == [
        (f"{a}{side}", a, v) for a in "xyz" for side, v in (("lo", -15.0), ("hi", 15.0))
    ]


def test_units_si_and_a_length_scale_and_the_safety_factor(spheres, tmp_path) -> None:
    cfg = LiggghtsConfig(units="si", density=3100.0, youngs_modulus=1e8, rayleigh_fraction=0.1)
    path = LiggghtsExporter(cfg).export(spheres, tmp_path / "p.data")
    text = path.read_text()
    assert "# lengths = packing lengths (µm) x 1e-06;" in text
    atoms = data_atoms(text)
    idx = np.flatnonzero(spheres.placed)
    np.testing.assert_allclose(atoms[:, 2], 2e-6 * spheres.solids.rounding_radius[idx])
    np.testing.assert_allclose(atoms[:, 4:], 1e-6 * spheres.centre[idx])
    zlo, zhi = re.findall(r"^(\S+) (\S+) zlo zhi$", text, re.M)[0]
    assert float(zlo) == pytest.approx(-1.5e-5, rel=1e-15) and float(zhi) == -float(zlo)
    script = script_path(path).read_text()
    assert "\nunits        si\n" in script and f"zplane {zhi}\n" in script
    assert "\nvariable dt    equal 0.1*PI*v_r_rho/sqrt(v_G)" in script
    scaled = LiggghtsExporter(LiggghtsConfig(length_scale=2.0)).export(spheres, tmp_path / "s.data")
    np.testing.assert_allclose(data_atoms(scaled.read_text())[:, 4:], 2 * spheres.centre[idx])


def test_wrong_parameters_are_refused(spheres, tmp_path) -> None:
    with pytest.raises(ValidationError, match="stiffness"):
        LiggghtsConfig.model_validate({"stiffness": 1.0})
    with pytest.raises(ValidationError, match="rayleigh_fraction"):
        LiggghtsConfig(rayleigh_fraction=2.0)
    with pytest.raises(ValidationError, match="units"):
        LiggghtsConfig.model_validate({"units": "lj"})
    with pytest.raises(ConfigError, match=r"^exporter 'liggghts': mineral_density names 'olivine'"):
        LiggghtsExporter(LiggghtsConfig(mineral_density={"olivine": 3.3})).export(
            spheres, tmp_path / "p.data"
        )


POLYHEDRA_REFUSED = (
    "exporter 'liggghts' writes packings of spheres alone (LIGGGHTS' granular atoms are "
    "spheres), and this packing has polyhedra; polyhedra: gsd, image, lammps, slice, stl, vtk, yade"
)


def test_polyhedra_and_2d_packings_are_refused_in_one_line(tmp_path, capsys) -> None:
    for packing in (cube_and_sphere(), cube_and_sphere(rounded=False)):
        with pytest.raises(ExportError) as err:
            LiggghtsExporter().export(packing, tmp_path / "p.data")
        assert str(err.value) == POLYHEDRA_REFUSED
    assert not (tmp_path / "p.data").exists() and not (tmp_path / "p.in").exists()
    file = tmp_path / "poly.npz"
    save(cube_and_sphere(rounded=False), file)
    assert main(["export", str(file), "--to", "liggghts"]) != 0
    assert one_error_line(capsys) == f"regopack: error: {POLYHEDRA_REFUSED}"
    assert not file.with_suffix(".data").exists()
    flat = tmp_path / "flat.npz"
    save(packing_from_polygons([[[0, 0], [1, 0], [1, 1], [0, 1]]], (-1, 3, -1, 3)), flat)
    assert main(["export", str(flat), "--to", "liggghts"]) != 0
    assert one_error_line(capsys) == (
        f"regopack: error: {flat}: exporter 'liggghts' writes 3D packings, and this is a 2D "
        "packing; 2D exporters: csv, gsd, image, json, lammps, svg, vtk"
    )
    with pytest.raises(ExportError, match=r"^exporter 'liggghts' writes 3D packings of spheres"):
        LiggghtsExporter().export(packing_from_polygons([[[0, 0], [1, 0], [0, 1]]]), flat)


def test_the_command_writes_both_files(spheres, tmp_path, capsys) -> None:
    file = tmp_path / "packing.npz"
    save(spheres, file)
    assert main(["export", str(file), "--to", "liggghts", "--set", "liggghts.steps=500"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'packing.data'}"
    assert "\nvariable steps index 500\n" in (tmp_path / "packing.in").read_text()


# ---------------------------------------------------------------------------
# The real program


def run_liggghts(path: Path, **variables: float) -> dict:
    """Run ``liggghts -in <stem>.in`` beside ``path``; return its thermo output and final dump."""
    if LIGGGHTS is None:
        pytest.skip("the liggghts executable is not on PATH (Debian: apt-get install liggghts)")
    args = [LIGGGHTS, "-in", script_path(path).name, "-log", "none", "-echo", "none"]
    for name, value in variables.items():
        args += ["-var", name, repr(value)]
    done = subprocess.run(
        args,
        cwd=path.parent,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=60,
        check=False,
    )
    out = done.stdout + done.stderr
    assert done.returncode == 0 and "ERROR" not in out, out[-2000:]
    assert "WARNING" not in out, out[-2000:]
    thermo = out.split("Step    Atoms         KinEng             Dt", 1)[1]
    rows = [line.split() for line in thermo.split("Loop time", 1)[0].strip().splitlines()]
    lines = dump_path(path).read_text().splitlines()
    assert lines[8].split()[
        2:
    ] == "id type x y z radius mass c_disp[1] c_disp[2] c_disp[3]".split() + ["c_disp[4]"]
    table = np.array([line.split() for line in lines[9:]], dtype=float)
    return {
        "step": [int(r[0]) for r in rows],
        "atoms": [int(r[1]) for r in rows],
        "ke": [float(r[2]) for r in rows],
        "dt": float(rows[0][3]),
        "natoms": int(lines[3]),
        "final": table,
        "output": out,
    }


def check_read_back(report: dict, packing: Packing, density: float | np.ndarray = 3.1) -> None:
    """LIGGGHTS read every sphere of the packing with its mineral, radius and mass."""
    final = report["final"]
    idx = np.flatnonzero(packing.placed)
    assert report["natoms"] == final.shape[0] == idx.size == packing.n_placed > 200
    assert set(report["atoms"]) == {idx.size}  # no atom lost at any thermo step
    np.testing.assert_array_equal(final[:, 0], np.arange(1, idx.size + 1))
    np.testing.assert_array_equal(final[:, 1], packing.mineral[idx] + 1)
    radius = packing.solids.rounding_radius[idx]
    np.testing.assert_allclose(final[:, 5], radius, rtol=1e-14)
    np.testing.assert_allclose(final[:, 6], 4 / 3 * np.pi * radius**3 * density, rtol=1e-12)
    assert np.isfinite(final).all() and np.isfinite(report["ke"]).all()


def test_liggghts_holds_the_packing_still_without_gravity(spheres, tmp_path) -> None:
    """1 000 steps: every atom stays, nothing is NaN, nothing moves 1 % of d_min."""
    cfg = LiggghtsConfig(mineral_density={"pyroxene": 3.4, "glass": 2.4})
    path = LiggghtsExporter(cfg).export(spheres, tmp_path / "p.data")
    report = run_liggghts(path, steps=1000)
    idx = np.flatnonzero(spheres.placed)
    by_name = dict(zip(spheres.mineral_names, (3.1, 3.4, 2.4), strict=True))
    density = np.array([by_name[spheres.mineral_names[k]] for k in spheres.mineral[idx]])
    check_read_back(report, spheres, density)
    assert report["step"][-1] == 1000
    d_min = 2 * spheres.solids.rounding_radius[idx].min()
    final = report["final"]
    moved = np.linalg.norm(final[:, 2:5] - spheres.centre[idx], axis=1)
    assert moved.max() < 0.01 * d_min
    np.testing.assert_allclose(final[:, 10], moved, atol=1e-9 * d_min)  # LIGGGHTS' own |d|
    # the time step: a fifth of the shortest Rayleigh time, that of a glass grain
    rayleigh = rayleigh_time(2 * spheres.solids.rounding_radius[idx], density, cfg)
    assert report["dt"] == pytest.approx(0.2 * rayleigh.min(), rel=1e-7)
    assert density[np.argmin(rayleigh)] == 2.4


def test_liggghts_settles_the_packing_inside_its_walls_under_gravity(spheres, tmp_path) -> None:
    path = LiggghtsExporter().export(spheres, tmp_path / "p.data")
    g, steps = 0.05, 3000
    report = run_liggghts(path, g=g, steps=steps)
    check_read_back(report, spheres)
    final = report["final"]
    drop = spheres.centre[spheres.placed, 2] - final[:, 4]
    assert np.median(drop) > 0.5  # gravity acts ...
    assert drop.max() < 0.5 * g * (steps * report["dt"]) ** 2  # ... no faster than free fall
    r = final[:, 5:6]
    lo, hi = spheres.domain.bounds().reshape(3, 2).T
    slack = 0.05 * r.min()  # the Hertz contacts let a sphere into a wall by a little
    assert np.all(final[:, 2:5] - r > lo - slack) and np.all(final[:, 2:5] + r < hi + slack)
    assert (final[:, 4] - r[:, 0]).min() < lo[2] + 0.01  # the bottom spheres rest on the floor
    # read back: every sphere where LIGGGHTS left it, the packing's own otherwise
    file = tmp_path / "packing.npz"
    save(spheres, file)
    assert main(["settled", str(file), str(dump_path(path)), "--from", "liggghts"]) == 0
    settled = regopack.load(dump_path(path).with_suffix(".npz"))
    np.testing.assert_allclose(settled.centre[spheres.placed], final[:, 2:5], rtol=1e-15)
    assert settled.stats["settled_steps"] == steps
    np.testing.assert_array_equal(settled.radius, spheres.radius)
    with pytest.raises(PackingFileError, match="radii are not those"):
        regopack.settled(spheres, dump_path(path), "liggghts", params={"units": "si"})


def test_liggghts_runs_a_periodic_box(periodic, tmp_path) -> None:
    path = LiggghtsExporter().export(periodic, tmp_path / "p.data")
    script = script_path(path).read_text()
    assert "\nboundary     p p p\n" in script and "wall/gran" not in script
    atoms = data_atoms(path.read_text())
    lo, hi = periodic.domain.bounds().reshape(3, 2).T
    assert np.all(atoms[:, 4:] >= lo) and np.all(atoms[:, 4:] < hi)
    report = run_liggghts(path, steps=1000)
    check_read_back(report, periodic)
    d_min = atoms[:, 2].min()
    assert report["final"][:, 10].max() < 0.01 * d_min
