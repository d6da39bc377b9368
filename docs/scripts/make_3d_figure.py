"""Draw the 3D picture: a box of random polyhedra, a vertical section and a shaded view.

Run from the repository root (needs the ``docs`` extra, i.e. matplotlib)::

    python docs/scripts/make_3d_figure.py                     # packs a 45 µm box first (~15 s)
    python docs/scripts/make_3d_figure.py --packing runs/bench3d-seed1/packing.npz

The packed scene is that of the asv suite's 3D benchmarks (the six minerals
of Table 1 as ``polyhedron`` shapes, sizes 2-12 µm). The picture is written to
``docs/images/packing3d.png`` unless ``--out`` says otherwise.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

import regopack
from regopack.packing.core import Packing
from regopack.packing.drawing import draw_section, draw_view

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE.parent / "images" / "packing3d.png"
PHASES = [
    ("pyroxene", 0.343, 0.25),
    ("feldspar", 0.315, 0.5),
    ("glass", 0.161, 1.0),
    ("olivine", 0.091, 2.0),
    ("ilmenite", 0.052, 15.0),
    ("others", 0.038, 0.8),
]


def pack(side: float, seed: int) -> Packing:
    """Pack a cube of side ``side`` with the Table-1 minerals as polyhedra."""
    scene = {
        "name": "box3d",
        "seed": seed,
        "domain": {"kind": "box", "width": side, "height": side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0, "d0": 16.0, "alpha": 6.9},
        "phases": [
            {"name": n, "fraction": f, "shape": {"kind": "polyhedron", "psi": p}}
            for n, f, p in PHASES
        ],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }
    packing = regopack.pack(scene)
    assert packing.dimension == 3
    return packing


def main() -> None:
    """Draw the picture (``--help`` lists the options)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--packing", type=Path, help="a saved 3D packing (default: pack one)")
    parser.add_argument("--side", type=float, default=45.0, help="box side when packing (µm)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args()
    packing = regopack.load(args.packing) if args.packing else pack(args.side, args.seed)
    if packing.dimension != 3:
        raise SystemExit(f"{args.packing}: not a 3D packing")
    plt.rcParams.update({"font.size": 9})
    fig = plt.figure(figsize=(9.0, 3.9))
    section = fig.add_subplot(1, 2, 1)
    draw_section(packing, section, axis=1)
    section.set_title("section y = 0", fontsize=9)
    view = fig.add_subplot(1, 2, 2, projection="3d")
    shown = draw_view(packing, view)
    side = packing.domain.size[0]
    view.set_title(
        f"{packing.n_placed} polyhedra in a {side:g} µm box, φ = {packing.phi:.3f}\n"
        f"(the {shown} near the three visible faces)",
        fontsize=9,
    )
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=150)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
