"""Draw the settling round trip: a packing of spheres before and after YADE settles it.

Run from the repository root (needs the ``docs`` extra and the ``yade`` program)::

    python docs/scripts/make_settle_figure.py               # packs a 60 µm box of spheres first
    python docs/scripts/make_settle_figure.py --packing runs/spheres40/packing.npz

The packing is exported with ``--to yade``, run by YADE under gravity
(``--gravity``, ``--steps``), read back with ``regopack.settled``, and both
are measured by the same analyses. The table of the two is printed, and the
picture (a vertical section of each, the solid fraction by height, g(r)) is
written to ``docs/images/settle-yade.png`` unless ``--out`` says otherwise.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np

import regopack
from regopack.packing.core import Packing
from regopack.packing.drawing import draw_section
from regopack.registry.manager import default_registry
from regopack.run.fabric import fabric_summary

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE.parent / "images" / "settle-yade.png"
PHASES = [("plagioclase", 0.5), ("pyroxene", 0.3), ("glass", 0.2)]


def pack(side: float, seed: int) -> Packing:
    """Pack a walled cube of side ``side`` with spheres of Chang'e-5 sizes 2-12 µm."""
    scene = {
        "name": "spheres3d",
        "seed": seed,
        "domain": {"kind": "box", "width": side, "height": side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0},
        "phases": [{"name": n, "fraction": f, "shape": {"kind": "sphere"}} for n, f in PHASES],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }
    return regopack.pack(scene)


def settle(packing: Packing, steps: int, gravity: float, folder: Path) -> Packing:
    """Export ``packing`` to YADE, run it under ``gravity``, and read it back."""
    script = regopack.export(packing, "yade", folder / "packing.py")
    done = subprocess.run(
        ["yade", "-f1", "-n", "-x", script.name, "--run", str(steps), "--gravity", repr(gravity)],
        cwd=folder,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        sys.exit(f"yade failed:\n{(done.stdout + done.stderr)[-2000:]}")
    return regopack.settled(packing, folder / "packing.final.txt", "yade")


def measures(packing: Packing) -> dict[str, float]:
    """φ, Z, the rattlers and the fabric's anisotropy of ``packing``."""
    found = regopack.analyze(packing, ["density", "homogeneity", "rdf"])
    scalars = found.scalars()
    fabric = fabric_summary(packing, default_registry())
    placed = packing.placed
    top = float((packing.centre[placed, 2] + packing.solids.rounding_radius[placed]).max())
    return {
        "phi_interior": scalars["density"]["phi_interior"],
        "bed_top": top,
        "z": fabric["z"],
        "z_mechanical": fabric["z_mechanical"],
        "rattler_fraction": fabric["rattler_fraction"],
        "anisotropy": fabric["anisotropy"],
        "anisotropy_error": fabric["anisotropy_error"],
        "layers": found.analyzers["homogeneity"].tables()["homogeneity_layers"],
        "rdf": found.analyzers["rdf"].tables()["rdf_near"],
    }


def main() -> None:
    """Draw the picture (``--help`` lists the options)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packing", type=Path, help="a 3D packing of spheres (default: pack)")
    parser.add_argument("--side", type=float, default=60.0, help="side of the box packed (µm)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--steps", type=int, default=20000, help="YADE steps")
    parser.add_argument("--gravity", type=float, default=1e5, help="m/s² along -z")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args()
    if shutil.which("yade") is None:
        sys.exit("the yade program is not on PATH (Debian: apt-get install yade)")
    before = regopack.load(args.packing) if args.packing else pack(args.side, args.seed)
    with tempfile.TemporaryDirectory() as folder:
        after = settle(before, args.steps, args.gravity, Path(folder))
    rows = [measures(before), measures(after)]
    print("| | before | after |\n|---|---:|---:|")
    for key in ("phi_interior", "bed_top", "z", "z_mechanical", "rattler_fraction"):
        print(f"| {key} | {rows[0][key]:.3f} | {rows[1][key]:.3f} |")
    print(
        "| anisotropy | "
        + " | ".join(f"{r['anisotropy']:.3f} ± {r['anisotropy_error']:.3f}" for r in rows)
        + " |"
    )
    draw(before, after, rows, args)


def draw(before: Packing, after: Packing, rows: list[dict], args: argparse.Namespace) -> None:
    """Draw the picture: the two sections, φ by height and g(r)."""
    fig, axes = plt.subplots(1, 4, figsize=(15, 4.0), constrained_layout=True)
    for ax, packing, title in ((axes[0], before, "packed"), (axes[1], after, "settled in YADE")):
        draw_section(packing, ax, axis=1)
        ax.set_title(f"{title}: section y = middle")
    for row, label, style in ((rows[0], "packed", "-"), (rows[1], "settled", "--")):
        layers = row["layers"]
        middle = (np.asarray(layers["z_lo"]) + np.asarray(layers["z_hi"])) / 2
        axes[2].errorbar(
            layers["phi"], middle, xerr=layers["phi_err"], fmt="o" + style, capsize=3, label=label
        )
        rdf = row["rdf"]
        axes[3].plot(rdf["r"], rdf["total"], style, label=label)
    axes[2].set_xlabel("solid fraction of the layer")
    axes[2].set_ylabel("height z (µm)")
    axes[2].set_title("φ by height (interior, ± 1 s.e.)")
    axes[3].set_xlabel("centre distance r (µm)")
    axes[3].set_ylabel("g(r)")
    axes[3].set_title("radial distribution (interior)")
    axes[3].legend(loc="lower right")  # the same lines in both panels
    fig.suptitle(
        f"{after.n_placed} spheres in a {args.side:g} µm box; YADE: {args.steps} steps under "
        f"g = {args.gravity:.0e} m/s²"
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
