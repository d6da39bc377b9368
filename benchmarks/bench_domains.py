"""Packing speed and density of the Table-1 population in every domain kind.

Each domain has the area of the Table-1 square (800 x 800 um), so every run
draws the same particles: the walled square, the periodic square, a circle and
a regular hexagon. Prints one row per kind: placed particles, packing time,
particles per second, phi over the domain and over the interior window, and
the verification time. Run from the repository root:

    python benchmarks/bench_domains.py
    python benchmarks/bench_domains.py --side 400 --inserter rsa
    python benchmarks/bench_domains.py --shape disk      # every particle an exact disk
    python benchmarks/bench_domains.py --shape mixed     # pyroxene, glass, ilmenite as disks
"""

from __future__ import annotations

import argparse
import math
import platform
import time

from regopack.manager import default_registry
from regopack.run import run_scene
from regopack.scene_model import load_scene, resolve_scene
from regopack.verification import verify


def domains(side: float) -> dict[str, str]:
    """``--set`` values of a domain of area ``side**2`` for every kind."""
    radius = side / math.sqrt(math.pi)
    hexa = side * math.sqrt(2.0 / (3.0 * math.sqrt(3.0)))  # circumradius of the hexagon
    corners = ", ".join(
        f"[{hexa * math.cos(k * math.pi / 3):.9g}, {hexa * math.sin(k * math.pi / 3):.9g}]"
        for k in range(6)
    )
    return {
        "rectangle": f"domain={{kind = 'rectangle', width = {side}, height = {side}}}",
        "periodic": f"domain={{kind = 'periodic', width = {side}, height = {side}}}",
        "circle": f"domain={{kind = 'circle', radius = {radius:.9g}}}",
        "polygon": f"domain={{kind = 'polygon', vertices = [{corners}]}}",
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--side", type=float, default=800.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--inserter", choices=["available-arc", "rsa"], default="available-arc")
    parser.add_argument("--shape", choices=["octagon", "disk", "mixed"], default="octagon")
    args = parser.parse_args()
    registry = default_registry()
    extra = [] if args.inserter == "available-arc" else ["insertion={kind = 'rsa'}"]
    disks = {"octagon": (), "disk": range(6), "mixed": (0, 2, 4)}[args.shape]
    extra += [f"phases.{p}.shape={{kind = 'disk'}}" for p in disks]
    # compile (or load the cached kernels) outside the timed runs
    for value in domains(60.0).values():
        run_scene(resolve_scene(load_scene("table1", [value, *extra]), registry), None)
    print(
        f"machine: {platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}; inserter {args.inserter}; shapes {args.shape}; "
        f"area {args.side:g}^2 um^2"
    )
    print(
        f"{'kind':<10} {'tried':>7} {'placed':>7} {'pack s':>8} {'part/s':>9} "
        f"{'phi':>7} {'phi int':>7} {'verify s':>8}"
    )
    for kind, value in domains(args.side).items():
        scene = load_scene("table1", [value, *extra], seed=args.seed)
        outcome = run_scene(resolve_scene(scene, registry), None)
        s = outcome.summary
        t = time.perf_counter()
        report = verify(outcome.packing)
        t_verify = time.perf_counter() - t
        assert report.ok, str(report)
        pack = s["insert_time_s"]
        print(
            f"{kind:<10} {s['tried']:>7} {s['placed']:>7} {pack:>8.2f} "
            f"{s['placed'] / pack:>9.0f} {s['phi_domain']:>7.4f} {s['phi_interior']:>7.4f} "
            f"{t_verify:>8.2f}"
        )


if __name__ == "__main__":
    main()
