"""Spheres of the sweep at scale: insertion time and peak memory of one cube.

Packs `dem3d`'s population as spheres (sizes 2-12 µm, columns 45 µm wide,
tail closing, no fabric block), the scene of the asv benchmark
`packing.SweepScale3D`, in a cube of the given side, once, after a tiny
packing that loads the kernels; prints the spheres drawn and placed, the
insertion time, the analyses and the peak resident memory of the process.
Run from the repository root (a 550 µm cube holds about 10^6 spheres):

    python benchmarks/bench_sphere_scale.py 120
    python benchmarks/bench_sphere_scale.py 550
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import regopack
from benchmarks import common


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("side", type=float, help="side of the cube (µm)")
    side = parser.parse_args().side
    if not (math.isfinite(side) and side > 0):
        parser.error(f"side must be a positive length in µm, not {side}")
    common.warm_3d("spheres")
    scene = common.scene_3d(
        "spheres",
        side,
        base="dem3d",
        **{"insertion.closing": "tail", "insertion.strip": 45.0, "outputs.fabric": False},
    )
    start = time.perf_counter()
    packing = regopack.pack(scene, verify=False)
    wall = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        json.dumps(
            {
                "side_um": side,
                "drawn": int(packing.n_particles),
                "placed": int(packing.n_placed),
                "insertion_s": round(float(packing.stats["insert_time_s"]), 2),
                "pack_s": round(wall, 2),
                "analyses": int(packing.stats["candidate_analyses"]),
                "peak_MB": round(peak),
            }
        )
    )


if __name__ == "__main__":
    main()
