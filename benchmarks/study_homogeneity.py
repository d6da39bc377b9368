"""Ring-to-ring homogeneity of a scene at a chosen size, with rings as wide as asked.

The ``homogeneity`` analyzer's default rings are 2 d_max wide, so its inner
rings hold a few hundred particles whatever the domain's size, and their
sampling errors (about 5 %) hide a deviation of 3 %. Wider rings on a larger
domain hold thousands each: this script packs the scene for each seed and
prints, per ring, its particles, its number-density and mean-diameter
deviations from the window's values with their sampling errors, and the
radial trends. Run from the repository root::

    python benchmarks/study_homogeneity.py --size 3200 --ring-width 390 --seeds 1 2 3
    python benchmarks/study_homogeneity.py --scene table1 --size 800 --ring-width 90
"""

from __future__ import annotations

import argparse
import platform

import numpy as np

import regopack


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="dem")
    parser.add_argument("--size", type=float, default=3200.0)
    parser.add_argument("--ring-width", type=float, default=390.0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"{args.scene}, L = {args.size:g}, rings {args.ring_width:g} wide")
    for seed in args.seeds:
        p = regopack.pack(args.scene, seed=seed, domain__width=args.size, domain__height=args.size)
        h = regopack.analyze(p, "homogeneity", homogeneity__ring_width=args.ring_width)[
            "homogeneity"
        ]
        r = h.scalars
        rings = h.tables["homogeneity_rings"]
        dens = np.asarray(rings["number_density"])
        diam = np.asarray(rings["mean_d"])
        dens_dev = 100 * (dens / r["number_density"] - 1)
        dens_err = 100 * np.asarray(rings["number_density_err"]) / dens
        diam_dev = 100 * (diam / r["mean_d"] - 1)
        diam_err = 100 * np.asarray(rings["mean_d_err"]) / diam
        print(
            f"seed {seed}: placed {p.n_placed}, insertion {p.stats['insert_time_s']:.1f} s; "
            f"largest ring deviation: number density {100 * r['density_max_rel_dev']:.2f} %, "
            f"mean diameter {100 * r['mean_d_max_rel_dev']:.2f} %"
        )
        if r["density_slope_per_100"] is None or r["mean_d_slope_per_100"] is None:
            print("  trends: not defined (too few rings; narrow them)")
        else:
            print(
                f"  trends per 100 µm: number density "
                f"({1e3 * r['density_slope_per_100']:.4f} ± {1e3 * r['density_slope_err']:.4f})"
                f" 1e-3 µm^-2 (chi2/dof {r['density_trend_chi2_dof'] or float('nan'):.2f}),"
                f" mean diameter ({r['mean_d_slope_per_100']:.4f}"
                f" ± {r['mean_d_slope_err']:.4f}) µm"
                f" (chi2/dof {r['mean_d_trend_chi2_dof'] or float('nan'):.2f})"
            )
        print("  ring  particles  density dev (err) %  mean d dev (err) %")
        for k in range(len(dens)):
            print(
                f"  {k:4d}  {int(rings['n'][k]):9d}  {dens_dev[k]:+6.2f} ({dens_err[k]:.2f})"
                f"            {diam_dev[k]:+6.2f} ({diam_err[k]:.2f})"
            )


if __name__ == "__main__":
    main()
