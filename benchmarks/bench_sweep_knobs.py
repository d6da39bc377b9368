"""The sweep's knobs and the exact refusals, measured in one process.

For each setting, the Table-1 scene at side L is packed for every seed, the
settings alternating seed by seed so that machine drift hits all alike.
Prints, per setting, the mean over seeds of the particles placed, refused
and not offered, φ over the domain and the interior window, the insertion
time and the candidate analyses. Run from the repository root:

    python benchmarks/bench_sweep_knobs.py zone --size 800 --seeds 1 2 3
    python benchmarks/bench_sweep_knobs.py screening --size 400 --seeds 1 2 3
"""

from __future__ import annotations

import argparse
import platform
import statistics

from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

SETTINGS = {
    "zone": {
        "zone 80": ["insertion.order=sweep", "insertion.zone=80"],
        "zone 120": ["insertion.order=sweep", "insertion.zone=120"],
        "zone 160": ["insertion.order=sweep", "insertion.zone=160"],
    },
    "closing": {
        "paced": ["insertion.order=sweep", "insertion.closing=paced"],
        "prompt": ["insertion.order=sweep", "insertion.closing=prompt"],
    },
    "screening": {
        "paper": ["insertion.screening=paper"],
        "exact": ["insertion.screening=exact"],
    },
}
KEYS = ("placed", "refused", "not_offered", "rescued", "phi_domain", "phi_interior")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("knob", choices=sorted(SETTINGS))
    parser.add_argument("--size", type=float, default=800.0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    args = parser.parse_args()
    registry = default_registry()
    settings = SETTINGS[args.knob]
    size = [f"domain.width={args.size}", f"domain.height={args.size}"]
    for overrides in settings.values():  # compile outside the timed runs
        tiny = ["domain.width=60", "domain.height=60", *overrides[:1]]
        run_scene(resolve_scene(load_scene("table1", tiny), registry), None)
    rows: dict[str, list[dict[str, float]]] = {name: [] for name in settings}
    for seed in args.seeds:
        for name, overrides in settings.items():
            scene = load_scene("table1", [*size, f"seed={seed}", *overrides])
            s = run_scene(resolve_scene(scene, registry), None).summary
            rows[name].append(
                {
                    **{k: float(s.get(k, 0.0)) for k in KEYS},
                    "time_s": float(s["insert_time_s"]),
                    "analyses": float(s["candidate_analyses"]),
                }
            )
            print(f"seed {seed} {name}: placed {s['placed']} time {s['insert_time_s']:.2f} s")
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"L = {args.size:g} µm, seeds {args.seeds}")
    cols = [*KEYS, "time_s", "analyses"]
    print("| setting | " + " | ".join(cols) + " |")
    print("|---|" + "---:|" * len(cols))
    for name, runs in rows.items():
        cells = []
        for c in cols:
            m = statistics.fmean(r[c] for r in runs)
            cells.append(f"{m:.4f}" if c.startswith("phi") else f"{m:.1f}")
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
