"""Where the candidate analyses of the available-arc method go, and what could skip them.

Replays the insertion of the Table-1 scene (side ``--size``) candidate by
candidate from Python, with the compiled analysis, and checks that it places
the same particles as the compiled run. It prints:

- the empty analyses (no free arc) per candidate;
- the ratio ``r_i / rmin_k`` at which candidates are analysed, for the
  analyses that place the particle and for the empty ones (the screening
  coefficient ``t`` skips every analysis with a ratio of ``t`` or more);
- how many placements happen at a candidate that already had ``K`` or more
  empty analyses (what a rule that retires candidates after ``K`` failures
  would change);
- for a random sample of the empty analyses (``--sample``, a fraction), whether
  a disk of the new particle's inradius still fits, free and inside the walls,
  with its centre within the particle's reach of the candidate. Where no such
  disk fits, no placement of the particle touching the candidate exists, so a
  free-disk certificate could skip the analysis without changing the packing.
  The disks are tested with shapely buffers (inscribed polygons of the true
  offsets), which can only overstate the free space.

Run from the repository root (about a minute at the default size):

    python benchmarks/study_screening.py --size 400 --sample 0.02
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from regopack.plugins.inserters.available_arc import kernel
from regopack.plugins.inserters.available_arc.candidates import first_candidate, tree_set
from regopack.plugins.inserters.available_arc.state import ArcState
from regopack.registry.manager import default_registry
from regopack.run.pipeline import draw_population, run_scene
from regopack.scenes.model import load_scene, resolve_scene

RATIO_BINS = (0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.999)
RETIRE_AFTER = (1, 2, 4, 8, 16, 24, 32)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size", type=float, default=400.0, help="domain side L (um)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--sample", type=float, default=0.02, help="share of empty analyses")
    args = parser.parse_args()
    started = time.perf_counter()

    registry = default_registry()
    overrides = [f"domain.width={args.size}", f"domain.height={args.size}", f"seed={args.seed}"]
    scene = resolve_scene(load_scene("table1", overrides), registry)
    t = float(scene.insertion.config.t)
    rng = np.random.default_rng(scene.seed)
    pop = draw_population(scene, rng)
    domain = scene.scene.domain.to_domain()
    st = ArcState(pop, domain, t=t, tau=None, linear=False)
    n = len(pop)
    radius = pop.radius
    leaves = int(st.packed.ipar[kernel.I_LEAVES])
    tree = st.packed.tree
    sampler = np.random.default_rng(12345)

    empty = np.zeros(n, dtype=np.int64)
    placed_after: list[int] = []  # empty analyses of the candidate at each placement
    ratio_hit: list[float] = []
    ratio_empty: list[float] = []
    sample: list[tuple[int, int, int]] = []  # (candidate particle, new particle, count then)
    for i in range(n):
        if st.count == 0:
            st.place_first(i, rng)
            continue
        mq = st.begin_particle(i)
        r = float(radius[i])
        k = first_candidate(tree, leaves, 0, st.count, r, t, False)
        while k >= 0:
            pk = int(st.packed.order[k])
            arcs = kernel.analyze_candidate(pk, i, mq, st.outlines, st.packed, st.work, None)
            ratio = r / tree[leaves + k]
            if arcs.shape[0] > 0:
                placed_after.append(int(empty[k]))
                ratio_hit.append(ratio)
                x, y = st.locate(k, i, mq, float(kernel.sample_angle(arcs, rng.random())))
                st.insert(i, x, y)
                break
            empty[k] += 1
            ratio_empty.append(ratio)
            if sampler.random() < args.sample:
                sample.append((pk, i, st.count))
            tree_set(tree, leaves, k, r)
            k = first_candidate(tree, leaves, k + 1, st.count, r, t, False)

    compiled = run_scene(scene, None).summary
    count = st.count
    assert count == compiled["placed"], (count, compiled["placed"])
    assert empty.sum() == compiled["empty_analyses"], (empty.sum(), compiled["empty_analyses"])
    per = empty[:count]
    print(f"scene: table1, L = {args.size:g}, seed {args.seed}, t = {t}")
    print(
        f"tried {n}, placed {count}, analyses {per.sum() + len(placed_after)}, "
        f"empty {per.sum()} (same as the compiled run)"
    )
    print(
        f"empty analyses per candidate: mean {per.mean():.1f}, median {np.median(per):.0f}, "
        f"90% {np.percentile(per, 90):.0f}, max {per.max()}"
    )

    hit = np.asarray(ratio_hit)
    miss = np.asarray(ratio_empty)
    print("\nr_i / rmin_k of the analyses (rmin_k = +inf gives 0)")
    print(f"{'ratio':>13} {'placing':>8} {'empty':>8}")
    for lo, hi in zip(RATIO_BINS, (*RATIO_BINS[1:], 1.0), strict=True):
        print(
            f"[{lo:.3f},{hi:.3f}) {np.sum((hit >= lo) & (hit < hi)):8d} "
            f"{np.sum((miss >= lo) & (miss < hi)):8d}"
        )

    after = np.asarray(placed_after)
    print("\nretiring a candidate after K empty analyses")
    print(f"{'K':>4} {'empty left':>11} {'placements moved':>17}")
    for k_ in RETIRE_AFTER:
        moved = int(np.sum(after >= k_))
        share = 100 * moved / len(after)
        print(f"{k_:4d} {int(np.minimum(per, k_).sum()):11d} {moved:9d} ({share:4.1f} %)")

    fits = _disk_certificate(st, pop, domain.bounds(), sample)
    print(
        f"\nfree-disk certificate on {len(sample)} sampled empty analyses: a disk of the "
        f"particle's inradius still fits in {100 * fits.mean():.1f} % of them"
    )
    print(
        f"(so an exact certificate of this kind could skip at most "
        f"{100 * (1 - fits.mean()):.1f} % of the empty analyses)"
    )
    print(f"study wall time: {time.perf_counter() - started:.1f} s")


def _disk_certificate(
    st: ArcState, pop: object, bounds: tuple[float, float, float, float], sample: list
) -> np.ndarray:
    """For each sampled ``(pk, i, count)``: does a free disk of ``i``'s inradius fit near ``pk``?"""
    shapes = pop.shapes  # type: ignore[attr-defined]
    off, verts = shapes.offsets, shapes.vertices
    cx, cy, order = st.packed.cx, st.packed.cy, st.packed.order
    circum = st.outlines.circum
    cache: dict[int, Polygon] = {}

    def placed(p: int) -> Polygon:
        if p not in cache:
            cache[p] = Polygon(verts[off[p] : off[p + 1]] + [cx[p], cy[p]])
        return cache[p]

    out = np.zeros(len(sample), dtype=bool)
    for s, (pk, i, count) in enumerate(sample):
        local = verts[off[i] : off[i + 1]]
        seg = shapely.maximum_inscribed_circle(Polygon(local), 1e-6 * circum[i])
        rho = seg.length
        reach = float(np.sqrt(((local - np.asarray(seg.coords[0])) ** 2).sum(1)).max())
        before = order[:count]
        dist = np.hypot(cx[before] - cx[pk], cy[before] - cy[pk])
        near = before[(dist < circum[pk] + circum[before] + reach + rho) & (before != pk)]
        zone = placed(pk).buffer(reach)
        blocked = shapely.union_all([placed(int(p)).buffer(rho, 16) for p in (pk, *near)])
        inner = box(bounds[0] + rho, bounds[2] + rho, bounds[1] - rho, bounds[3] - rho)
        out[s] = zone.intersection(inner).difference(blocked).area > 0.0
    return out


if __name__ == "__main__":
    main()
