"""One packing in tiles: time on one and on several workers against one process.

Packs `dem3d`'s population as spheres (sizes 2-12 µm, columns 45 µm wide,
tail closing, no fabric block; the scene of `bench_sphere_scale.py`) in a
cube of the given side: once in one process without tiles, then cut into
tiles of the given side (or x and y sides: a side as long as the cube gives
strips) on each number of
local workers given (one kernel thread each); prints the placed count,
the wall time of `regopack.pack`, the insertion time and the solid fraction
of the interior, the peak memory of this process and of the largest
worker so far, and checks that the tiled packings are the same whatever
the workers. Run from the repository root (a 550 µm cube holds about 10^6
spheres):

    python benchmarks/bench_tiles.py 150 --tile 37.5 150 --workers 1 2
    python benchmarks/bench_tiles.py 550 --tile 137.5 550 --workers 2 1
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchmarks import common
from regopack.api.functions import pack_and_summarise


def _digest(packing: object) -> str:
    centre = np.ascontiguousarray(packing.centre)  # type: ignore[attr-defined]
    index = np.ascontiguousarray(packing.insertion_index)  # type: ignore[attr-defined]
    return hashlib.sha256(centre.tobytes() + index.tobytes()).hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("side", type=float, help="side of the cube (µm)")
    parser.add_argument(
        "--tile", type=float, nargs="+", required=True, help="side of the tiles (µm), or x and y"
    )
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--no-whole", action="store_true", help="skip the run without tiles")
    args = parser.parse_args()
    if not (math.isfinite(args.side) and args.side > 0):
        parser.error(f"side must be a positive length in µm, not {args.side}")
    if not all(math.isfinite(t) and t > 0 for t in args.tile) or len(args.tile) > 2:
        parser.error(f"--tile must be one or two positive lengths in µm, not {args.tile}")
    tile: float | list[float] = args.tile[0] if len(args.tile) == 1 else list(args.tile)
    if any(w < 1 for w in args.workers):
        parser.error(f"--workers must be 1 or more, not {args.workers}")
    common.warm_3d("spheres")
    base = {"insertion.closing": "tail", "insertion.strip": 45.0, "outputs.fabric": False}
    rows = []
    runs: list[tuple[str, dict[str, object], int | None]] = []
    if not args.no_whole:
        runs.append(("one process, no tiles", {}, None))
    for w in args.workers:
        runs.append((f"tiles, {w} worker(s)", {"tiles.side": tile}, w))
    digests = set()
    for label, extra, workers in runs:
        scene = common.scene_3d("spheres", args.side, base="dem3d", **base, **extra)
        start = time.perf_counter()
        outcome = pack_and_summarise(
            scene, verify=False, workers=workers, threads_per_worker=1 if workers else None
        )
        wall = time.perf_counter() - start
        p, s = outcome.packing, outcome.summary
        if workers is not None:
            digests.add(_digest(p))
        rows.append(
            {
                "run": label,
                "placed": int(p.n_placed),
                "pack_s": round(wall, 1),
                "insertion_s": round(float(s.get("insert_time_s", math.nan)), 1),
                "phi_interior": round(float(s["phi_interior"]), 4),
                "tiles": int(s.get("tiles", 0)),
                # peak resident memory so far: this process, and the largest worker that ended
                "peak_MB": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
                "worker_peak_MB": round(
                    resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
                ),
            }
        )
        print(json.dumps(rows[-1]), flush=True)
    if len(digests) > 1:
        raise SystemExit(f"the tiled packings differ between worker counts: {sorted(digests)}")
    if digests:
        print(f"tiled packings identical on {args.workers} workers: {digests.pop()}")


if __name__ == "__main__":
    main()
