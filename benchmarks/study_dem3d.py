"""Size classes, layers and fabric of `dem3d` packings, one JSON line per seed.

Packs the built-in scene `dem3d` (or another with ``--scene``) for each
seed with the given ``--set`` overrides, runs the ``psd`` and
``homogeneity`` analyses, and prints the insertion time, the particles
drawn and placed, φ of the domain and of the interior, the fabric
(anisotropy with its error, Z, rattler share), the worst size class by
number and by mass with how many classes are within the tolerance, and the
layers' number density, mean diameter and φ from the floor up, with the
candidates analysed and the particles refused. The rows of
`docs/development/2026-12-07-dem3d-zone-and-count.md` and of
`docs/development/2026-12-07-3d-kernel-loops.md` come from it. Run
from the repository root::

    python benchmarks/study_dem3d.py --seeds 1 2 3
    python benchmarks/study_dem3d.py --seeds 1 --set insertion.zone=60 --set count=5900
    python benchmarks/study_dem3d.py --seeds 1 --set insertion.zone=60 \
        --set 'insertion.closing="even"'
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import regopack
from regopack.api.functions import pack_and_summarise
from regopack.base.errors import RegopackError
from regopack.registry.manager import default_registry
from regopack.scenes.model import load_scene, resolve_scene


def row(scene: str, seed: int, overrides: list[str]) -> dict[str, Any]:
    """Pack ``scene`` with ``seed`` and ``--set`` ``overrides``; return the measured values."""
    resolved = resolve_scene(load_scene(scene, [*overrides, f"seed={seed}"]), default_registry())
    out = pack_and_summarise(resolved, verify=False)
    packing, summary = out.packing, out.summary
    results = regopack.analyze(packing, ["psd", "homogeneity"])
    psd, layers = results["psd"].scalars, results["homogeneity"].scalars
    fabric = summary.get("fabric") or {}
    return {
        "seed": seed,
        "set": overrides,
        "insertion_s": round(float(packing.stats["insert_time_s"]), 1),
        "drawn": int(packing.n_particles),
        "placed": int(packing.n_placed),
        "analyses": int(packing.stats.get("candidate_analyses", 0)),
        "refused": int(packing.stats.get("refused", 0)),
        "phi_domain": summary.get("phi_domain"),
        "phi_interior": summary.get("phi_interior"),
        "anisotropy": fabric.get("anisotropy"),
        "anisotropy_error": fabric.get("anisotropy_error"),
        "z": fabric.get("z"),
        "rattler_fraction": fabric.get("rattler_fraction"),
        "worst_number": psd["worst_number_rel_error"],
        "worst_number_class": psd["worst_number_class"],
        "worst_mass": psd["worst_mass_rel_error"],
        "classes_within": f"{psd['n_classes_within']}/{psd['n_classes_checked']}",
        "density_layers": layers["density_layers"],
        "mean_diameter_layers": layers["mean_diameter_layers"],
        "phi_layers": layers["phi_layers"],
        "layer_mean_d_max_rel_dev": layers["layer_mean_d_max_rel_dev"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="dem3d")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1])
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    args = parser.parse_args()
    for seed in args.seeds:
        try:
            values = row(args.scene, seed, args.overrides)
        except RegopackError as error:
            print(f"study_dem3d.py: error: {error}", file=sys.stderr)
            raise SystemExit(2) from None
        print(json.dumps(values, default=float), flush=True)


if __name__ == "__main__":
    main()
