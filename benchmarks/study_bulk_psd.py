"""Size fidelity of the sweep order in the bulk: the placed size mix below the closing band.

The sweep order leaves out coarse particles only while it closes the packing
under the top wall. This study packs the ``dem`` scene for several seeds and
compares, per √2 class holding at least ``--min-count`` drawn particles, the
number and mass (area) shares of the placed particles against those of the
drawn population: over the whole packing, and over the bulk window that
leaves out a margin at the side walls and the bottom and the closing band at
the top. Run::

    python benchmarks/study_bulk_psd.py --seeds 1 2 3 --size 800
"""

from __future__ import annotations

import argparse
import time
import tomllib

import numpy as np

import regopack
from regopack.packing.sieve import class_of, reference_diameter, sieve_edges


def shares(d: np.ndarray, edges: np.ndarray, n_classes: int) -> tuple[np.ndarray, np.ndarray]:
    k = class_of(d, edges)
    number = np.bincount(k, minlength=n_classes)[:n_classes].astype(float)
    mass = np.bincount(k, weights=d * d, minlength=n_classes)[:n_classes]
    return number / number.sum(), mass / mass.sum()


def worst(placed: np.ndarray, drawn: np.ndarray, keep: np.ndarray) -> tuple[float, int]:
    rel = np.where(keep, placed / np.where(drawn > 0, drawn, 1.0) - 1.0, 0.0)
    i = int(np.argmax(np.abs(rel)))
    return float(rel[i]), i


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--size", type=float, default=800.0)
    parser.add_argument("--min-count", type=int, default=100)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    args = parser.parse_args()
    extra = {
        k: tomllib.loads(f"v = {v}")["v"] for k, v in (s.split("=", 1) for s in args.overrides)
    }
    print(
        "seed  placed  phi_int  top-band phi  time_s  |  whole: worst number  worst mass"
        "  |  bulk: n  worst number  worst mass"
    )
    rows = []
    for seed in args.seeds:
        scene = regopack.scene(
            "dem", seed=seed, domain__width=args.size, domain__height=args.size, **extra
        )
        start = time.perf_counter()
        outcome = regopack.pack_and_summarise(scene)
        elapsed = time.perf_counter() - start
        p = outcome.packing
        d_all = 2.0 * p.radius
        edges = sieve_edges(d_all, reference_diameter(p))
        n_classes = len(edges) - 1
        counts = np.bincount(class_of(d_all, edges), minlength=n_classes)[:n_classes]
        keep = counts >= args.min_count
        drawn_n, drawn_m = shares(d_all, edges, n_classes)
        placed = p.placed
        whole_n, whole_m = shares(d_all[placed], edges, n_classes)
        zone = float(scene.insertion.config.zone or 3.0 * 2.0 * float(p.radius.max()))
        margin = 2.0 * float(np.max(p.radius))
        xmin, xmax, ymin, ymax = (float(b) for b in p.domain.bounds())
        c = p.centre
        bulk = (
            placed
            & (c[:, 0] > xmin + margin)
            & (c[:, 0] < xmax - margin)
            & (c[:, 1] > ymin + margin)
            & (c[:, 1] < ymax - zone)
        )
        bulk_n, bulk_m = shares(d_all[bulk], edges, n_classes)
        import shapely
        from shapely.geometry import box

        top_band = box(xmin, ymax - 0.1 * (ymax - ymin), xmax, ymax)
        top_phi = shapely.union_all(p.to_shapely()).intersection(top_band).area / top_band.area
        wn, _ = worst(whole_n, drawn_n, keep)
        wm, _ = worst(whole_m, drawn_m, keep)
        bn, _ = worst(bulk_n, drawn_n, keep)
        bm, _ = worst(bulk_m, drawn_m, keep)
        rows.append((wn, wm, bn, bm))
        print(
            f"{seed:4d}  {p.n_placed:6d}  {outcome.summary['phi_interior']:.4f}  {top_phi:12.3f}"
            f"  {elapsed:6.1f}  |  {100 * wn:+19.1f} %  {100 * wm:+8.1f} %"
            f"  |  {int(bulk.sum()):5d}  {100 * bn:+10.1f} %  {100 * bm:+8.1f} %"
        )
    arr = np.array(rows)
    mean, sd = arr.mean(axis=0), arr.std(axis=0, ddof=1) if len(rows) > 1 else np.zeros(4)
    labels = ("whole, number", "whole, mass", "bulk, number", "bulk, mass")
    for label, m, s, a in zip(labels, mean, sd, np.abs(arr).max(axis=0), strict=True):
        print(
            f"{label:14s}: worst class error {100 * m:+.1f} ± {100 * s:.1f} %"
            f" (largest {100 * a:.1f} %)"
        )


if __name__ == "__main__":
    main()
