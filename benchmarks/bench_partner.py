"""What the sweep's partner thread gains: one thread against two, alternating in one process.

Packs the `dem` scene (by default with the tail closing and strips of 800 µm,
as the speed targets are measured) in an L x L domain, alternately with one
thread (no partner, no batches) and with two (the partner analyses the
screened search's next candidates; the exact scans run in batches), and
prints each insertion time and whether every pair of packings is the same
bit for bit. ``--busy`` starts a
process that keeps one core busy for the whole run. Run from the repository
root:

    python benchmarks/bench_partner.py --size 800 --reps 4
    python benchmarks/bench_partner.py --size 800 --reps 3 --busy
    python benchmarks/bench_partner.py --size 800 --reps 2 --paced
"""

from __future__ import annotations

import argparse
import multiprocessing
import platform
import time

import numba
import numpy as np

from regopack.manager import default_registry
from regopack.run import run_scene
from regopack.scene_model import load_scene, resolve_scene


def _spin(seconds: float) -> None:
    """Keep one core busy."""
    end = time.monotonic() + seconds
    x = 0
    while time.monotonic() < end:
        x += 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=800.0)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--paced", action="store_true", help="the scene's own (paced) closing")
    parser.add_argument("--busy", action="store_true", help="one busy process beside the run")
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    registry = default_registry()
    base = [] if args.paced else ['insertion.closing="tail"', "insertion.strip=800"]
    most = numba.get_num_threads()
    for threads in (1, 2):  # compile both
        numba.set_num_threads(min(threads, most))
        warm = ["domain.width=60", "domain.height=60", *base, *args.overrides]
        run_scene(resolve_scene(load_scene("dem", warm), registry), None)
    overrides = [
        f"domain.width={args.size}",
        f"domain.height={args.size}",
        f"seed={args.seed}",
        *base,
        *args.overrides,
    ]
    scene = resolve_scene(load_scene("dem", overrides), registry)
    busy = None
    if args.busy:
        busy = multiprocessing.get_context("spawn").Process(target=_spin, args=(36000.0,))
        busy.start()
    print(f"machine: {platform.machine()}, Python {platform.python_version()}, cores {most}")
    print(f"dem, L = {args.size:g}, seed {args.seed}, {' '.join(base + args.overrides)}")
    print(f"busy process beside: {'yes' if busy else 'no'}")
    times: dict[int, list[float]] = {1: [], 2: []}
    keys: set[bytes] = set()
    try:
        for _ in range(args.reps):
            for threads in (1, 2):
                numba.set_num_threads(min(threads, most))
                outcome = run_scene(scene, None)
                s = outcome.summary
                p = outcome.packing
                keys.add(p.centre.tobytes() + np.asarray(p.insertion_index).tobytes())
                times[threads].append(float(s["insert_time_s"]))
                print(
                    f"threads {threads}: placed {s['placed']}, insertion "
                    f"{s['insert_time_s']:.3f} s, analyses {s['candidate_analyses']}, "
                    f"partner {'yes' if s.get('partner') else 'no'}",
                    flush=True,
                )
    finally:
        numba.set_num_threads(most)
        if busy is not None:
            busy.terminate()
            busy.join()
    one, two = min(times[1]), min(times[2])
    print(f"best: one thread {one:.3f} s, two {two:.3f} s, ratio {one / two:.2f}")
    print(f"same packing on one and two threads: {len(keys) == 1}")


if __name__ == "__main__":
    main()
