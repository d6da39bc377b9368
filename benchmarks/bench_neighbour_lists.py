"""Neighbour lists on and off: insertion time and the lists' memory, same packing.

Both settings run in one process, alternating, on the same population and
generator state, so that a machine whose speed drifts (a shared virtual
machine) affects both alike; the minimum and the median of the repeats are
printed. Run from the repository root:

    python benchmarks/bench_neighbour_lists.py --size 800 --repeats 6
    python benchmarks/bench_neighbour_lists.py --size 1600 --repeats 2
    python benchmarks/bench_neighbour_lists.py --size 800 --repeats 2 --set domain.kind=periodic

``--set`` takes scene overrides as on the command line (a periodic box,
disks: ``--set "phases.0.shape={kind = 'disk'}"`` for each phase).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from regopack.manager import default_registry
from regopack.plugins.available_arc.state import ArcState
from regopack.run import draw_population
from regopack.scene_model import ResolvedScene, load_scene, resolve_scene


def _scene(size: float, seed: int, extra: list[str] | None = None) -> ResolvedScene:
    overrides = [f"domain.width={size}", f"domain.height={size}", f"seed={seed}", *(extra or [])]
    return resolve_scene(load_scene("table1", overrides), default_registry())


def _pack(scene: ResolvedScene, lists: bool) -> tuple[float, ArcState]:
    rng = np.random.default_rng(scene.seed)
    pop = draw_population(scene, rng)
    cfg = scene.insertion.config
    state = ArcState(
        pop,
        scene.scene.domain.to_domain(),
        t=cfg.t,
        tau=None,
        linear=False,
        neighbour_lists=lists,
    )
    started = time.perf_counter()
    state.pack_range(0, len(pop), rng)
    return time.perf_counter() - started, state


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size", type=float, default=800.0, help="domain side L (um)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=4)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}")
    warm = _scene(200.0, args.seed, args.overrides)
    _pack(warm, True)  # compile (or load the cache) outside the timings
    _pack(warm, False)
    scene = _scene(args.size, args.seed, args.overrides)
    times: dict[bool, list[float]] = {True: [], False: []}
    packings: dict[bool, bytes] = {}
    memory = 0.0
    for r in range(args.repeats):
        for lists in (True, False) if r % 2 == 0 else (False, True):
            seconds, state = _pack(scene, lists)
            times[lists].append(seconds)
            p = state.packed
            packings[lists] = p.cx.tobytes() + p.cy.tobytes() + p.order.tobytes()
            if lists:
                arrays = (
                    p.nb_o,
                    p.nb_gap,
                    p.nb_dx,
                    p.nb_dy,
                    p.nb_n,
                    p.nb_reach,
                    p.nb_row,
                    p.nb_free,
                )
                memory = sum(a.nbytes for a in arrays) / 2**20
    same = packings[True] == packings[False]
    n = len(state.outlines.req)
    extra = " ".join(args.overrides)
    print(f"scene: table1 {extra}, L = {args.size:g}, {n} particles, {args.repeats} runs each")
    print(f"{'lists':>6} {'min s':>7} {'median s':>9} {'list MB':>8}")
    for lists in (True, False):
        v = sorted(times[lists])
        print(
            f"{'on' if lists else 'off':>6} {v[0]:7.2f} {v[len(v) // 2]:9.2f} "
            f"{memory if lists else 0.0:8.1f}"
        )
    print(f"time off / on (min): {min(times[False]) / min(times[True]):.2f}; same packing: {same}")


if __name__ == "__main__":
    main()
