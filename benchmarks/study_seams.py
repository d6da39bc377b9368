"""The solid fraction across the seams of a tiled sphere packing, against one packing.

Packs a cube of spheres (Chang'e-5 sizes cut to 2-8 µm, the 3D sweep with
columns of 45 µm) once without tiles and once in tiles of the given side,
for each seed, and prints the solid fraction of slabs across x: the exact
volume of each sphere between two planes, over the spheres whose centres lie
in the middle half of the height, divided by the slab's volume in that band
(seams of the tiles fall on slab edges when the tiles are a whole number of
slabs wide). Run from the repository root:

    python benchmarks/study_seams.py 120 --tile 60 --seeds 1 2 3
    python benchmarks/study_seams.py 120 --tile 60 --seeds 1 2 3 --walled
"""

from __future__ import annotations

import argparse
import copy
import json
import math

import numpy as np

from regopack.api.functions import pack_and_summarise


def scene(side: float, seed: int, walled: bool, closing: str) -> dict[str, object]:
    return {
        "name": "seams",
        "seed": seed,
        "count": "auto",
        "domain": {
            "kind": "box" if walled else "periodic-box",
            "width": side,
            "height": 0.75 * side,
            "depth": side,
        },
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 8.0, "d0": 16.0, "alpha": 6.9},
        "phases": [{"name": "a", "fraction": 1.0, "shape": {"kind": "sphere"}}],
        "insertion": {
            "kind": "available-surface",
            "order": "sweep",
            "closing": closing,
            "strip": 45.0,
        },
        "density": {"kind": "eta", "eta": 0.0},
        "outputs": {"fabric": False},
    }


def _cap(r: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Volume of the cap of height ``h`` (clipped to ``[0, 2r]``) of spheres of radius ``r``."""
    h = np.clip(h, 0.0, 2.0 * r)
    out: np.ndarray = np.pi * h * h * (3.0 * r - h) / 3.0
    return out


def slab_profile(centre: np.ndarray, radius: np.ndarray, side: float, slabs: int) -> np.ndarray:
    """Solid fraction of ``slabs`` slabs across x of the middle half of the height."""
    height = 0.75 * side
    band = np.abs(centre[:, 2]) < height / 4
    c, r = centre[band], radius[band]
    edges = np.linspace(-side / 2, side / 2, slabs + 1)
    phi = np.zeros(slabs)
    for shift in (-side, 0.0, side):  # images across a periodic side (none reach in a box)
        x = c[:, 0] + shift
        for b in range(slabs):
            low = x - r
            phi[b] += float(np.sum(_cap(r, edges[b + 1] - low) - _cap(r, edges[b] - low)))
    return phi / ((edges[1] - edges[0]) * side * height / 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("side", type=float, help="side of the cube (µm)")
    parser.add_argument("--tile", type=float, required=True, help="side of the tiles (µm)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--slabs", type=int, default=48)
    parser.add_argument("--walled", action="store_true", help="a walled box, not a periodic one")
    parser.add_argument("--closing", default="paced")
    args = parser.parse_args()
    if not (math.isfinite(args.side) and args.side > 0):
        parser.error(f"side must be a positive length in µm, not {args.side}")
    if not (math.isfinite(args.tile) and args.tile > 0):
        parser.error(f"--tile must be a positive length in µm, not {args.tile}")
    if args.slabs < 1:
        parser.error(f"--slabs must be 1 or more, not {args.slabs}")
    for tiles in (None, args.tile):
        profiles = []
        for seed in args.seeds:
            data = copy.deepcopy(scene(args.side, seed, args.walled, args.closing))
            if tiles is not None:
                data["tiles"] = {"side": tiles}
            outcome = pack_and_summarise(data, verify=False)
            p = outcome.packing
            placed = p.placed
            prof = slab_profile(p.centre[placed], p.rounding_radius[placed], args.side, args.slabs)
            profiles.append(prof)
            row = {
                "tiles": tiles,
                "seed": seed,
                "placed": int(p.n_placed),
                "phi_interior": round(float(outcome.summary["phi_interior"]), 4),
            }
            print(json.dumps(row), flush=True)
        mean = np.mean(profiles, axis=0)
        print(f"tiles {tiles}: slabs " + " ".join(f"{v:.3f}" for v in mean), flush=True)


if __name__ == "__main__":
    main()
