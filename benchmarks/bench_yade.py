"""Time the YADE hand-off: export a 3D packing with ``--to yade`` and run its script in YADE.

Prints the export time, YADE's time to build the scene, the time per step of
``--steps`` steps on each thread count of ``--threads``, and whether every
body came back finite and still (the largest displacement in smallest
diameters). Needs the ``yade`` program (Debian: ``apt-get install yade``).

    python benchmarks/bench_yade.py --packing runs/dem3d-40/packing.npz --steps 200 --threads 1 2
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import regopack
from regopack.plugins.exporters.yade_export import YadeExporter, state_path


def _yade(script: Path, threads: int = 1, steps: int = 0) -> float:
    """Seconds ``yade`` takes to build the scene of ``script`` and run ``steps`` steps."""
    command = ["yade", "-j", str(threads), "-f1", "-n", "-x", script.name]
    start = time.perf_counter()
    done = subprocess.run(
        [*command, *(["--run", str(steps)] if steps else [])],
        cwd=script.parent,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        sys.exit(f"bench_yade: yade failed:\n{(done.stdout + done.stderr)[-2000:]}")
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packing", type=Path, required=True, help="a 3D packing file")
    parser.add_argument("--steps", type=int, default=200, help="steps of each timed run")
    parser.add_argument("--threads", type=int, nargs="+", default=[1], help="yade -j values")
    args = parser.parse_args(argv)
    if shutil.which("yade") is None:
        sys.exit("bench_yade: the yade program is not on PATH (Debian: apt-get install yade)")
    packing = regopack.load(args.packing)
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        script = YadeExporter().export(packing, Path(folder) / "packing.py")
        print(f"export: {time.perf_counter() - start:.2f} s, {packing.n_placed} bodies")
        build = _yade(script)
        print(f"build (yade start, read, hulls): {build:.2f} s")
        d_min = float(re.search(r"^VOLUMETRIC_LENGTH = (\S+)", script.read_text(), re.M)[1])
        for threads in args.threads:
            seconds = _yade(script, threads, args.steps)
            table = np.loadtxt(state_path(script), comments="#", skiprows=1, ndmin=2)
            moved = np.linalg.norm(table[:, 4:7], axis=1).max() / d_min
            print(
                f"{threads} thread(s): {args.steps} steps in {seconds - build:.1f} s "
                f"({(seconds - build) / max(args.steps, 1) * 1e3:.0f} ms/step), "
                f"finite {bool(np.isfinite(table).all())}, max displacement {moved:.3g} d_min"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
