"""Ring-to-ring homogeneity of a scene at a chosen size, with rings as wide as asked.

The ``homogeneity`` analyzer's default rings are 2 d_max wide, so its inner
rings hold a few hundred particles whatever the domain's size, and their
sampling errors (about 5 %) hide a deviation of 3 %. Wider rings on a larger
domain hold thousands each: this script packs the scene for each seed and
prints, per ring, its particles, its number-density and mean-diameter
deviations from the window's values with their sampling errors, and the
radial trends. With ``--slab``, it also counts the particles in horizontal
slabs that high in the bounding box's top and bottom ``--band`` (centres
farther than ``--margin`` from the side walls), each slab's number density
and mean diameter against those of the middle half of the height: the bands
that the walls and the closing leave; ``--columns N`` counts the slabs
in N columns of equal width (one per strip of ``dem``, for instance), and
each slab's share of the finest √2 class (equivalent diameter under
2√2 µm) against the middle's. ``--height`` sets a domain height other
than the size, ``--count`` a number of particles drawn other than the
scene's; ``--psd`` adds the ``psd`` analyzer's worst size classes
and the counts of refused and not offered particles. Run from the
repository root::

    python benchmarks/study_homogeneity.py --size 3200 --ring-width 390 --seeds 1 2 3
    python benchmarks/study_homogeneity.py --size 3200 --ring-width 390 --slab 40 --seeds 1
    python benchmarks/study_homogeneity.py --scene table1 --size 800 --ring-width 90
    python benchmarks/study_homogeneity.py --size 3200 --height 800 --ring-width 390 \
        --slab 80 --band 120 --columns 4 --seeds 1 2 3 4
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
    parser.add_argument("--slab", type=float, default=0.0, help="slab height; 0: no slabs")
    parser.add_argument("--band", type=float, default=160.0, help="height counted at each end")
    parser.add_argument("--margin", type=float, default=40.0, help="from the side walls")
    parser.add_argument("--height", type=float, default=0.0, help="domain height; 0: the size")
    parser.add_argument("--columns", type=int, default=1, help="slabs counted per column")
    parser.add_argument("--psd", action="store_true", help="also the size classes' errors")
    parser.add_argument("--count", type=int, default=0, help="particles drawn; 0: the scene's")
    args = parser.parse_args()
    if not (
        args.size > 0
        and args.ring_width > 0
        and min(args.slab, args.band, args.margin, args.height) >= 0
        and np.isfinite([args.slab, args.band, args.margin, args.height]).all()
    ):
        parser.error(
            "--size and --ring-width must be positive; --slab, --band, --margin, --height"
            " 0 or more (all finite)"
        )
    if args.count < 0:
        parser.error("--count must be 0 or more")
    if args.columns < 1:
        parser.error("--columns must be 1 or more")
    height = args.height or args.size
    _check_scene(parser, args, height)
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"{args.scene}, {args.size:g} × {height:g} µm, rings {args.ring_width:g} wide")
    from regopack.base.errors import RegopackError

    try:
        for seed in args.seeds:
            study_seed(args, seed, height)
    except RegopackError as exc:  # a mistake only the packing finds: one line
        parser.exit(2, f"{parser.prog}: error: {exc}\n")


def study_seed(args: argparse.Namespace, seed: int, height: float) -> None:
    """Pack one seed and print its rings, and its slabs and size classes when asked."""
    extra = {"count": args.count} if args.count else {}
    p = regopack.pack(
        args.scene, seed=seed, domain__width=args.size, domain__height=height, **extra
    )
    h = regopack.analyze(p, "homogeneity", homogeneity__ring_width=args.ring_width)["homogeneity"]
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
    if args.psd:
        q = regopack.analyze(p, "psd")["psd"].scalars
        print(
            f"  refused {p.stats['refused']}, not offered {p.stats['not_offered']}; "
            f"worst class by number {100 * q['worst_number_rel_error']:+.2f} %, "
            f"by mass {100 * q['worst_mass_rel_error']:+.2f} %, KS {q['ks_number']:.4f}"
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
    print(
        f"  tiles chi2/dof: number density {r['tile_density_chi2_dof'] or float('nan'):.2f},"
        f" mean diameter {r['tile_mean_d_chi2_dof'] or float('nan'):.2f}"
    )
    print("  ring  particles  density dev (err) %  mean d dev (err) %")
    for k in range(len(dens)):
        print(
            f"  {k:4d}  {int(rings['n'][k]):9d}  {dens_dev[k]:+6.2f} ({dens_err[k]:.2f})"
            f"            {diam_dev[k]:+6.2f} ({diam_err[k]:.2f})"
        )
    if args.slab > 0:
        xmin, xmax = (float(v) for v in p.domain.bounds()[:2])
        step = (xmax - xmin) / args.columns
        for c in range(args.columns):
            left, right = xmin + c * step, xmin + (c + 1) * step
            if args.columns > 1:
                print(f"  column {c} (x from {left:.0f} to {right:.0f})")
            print_slabs(p, args.slab, args.band, args.margin, left, right)


def _check_scene(parser: argparse.ArgumentParser, args: argparse.Namespace, height: float) -> None:
    """Stop with regopack's one line unless the scene builds at this size and count."""
    from regopack.base.errors import RegopackError
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import load_scene, resolve_scene

    settings = [f"domain.width={args.size}", f"domain.height={height}"]
    if args.count:
        settings.append(f"count={args.count}")
    try:
        resolve_scene(load_scene(args.scene, settings), default_registry())
    except RegopackError as exc:
        parser.error(str(exc))


def print_slabs(
    p: regopack.Packing, slab: float, band: float, margin: float, left: float, right: float
) -> None:
    """Slabs ``slab`` high in the top and bottom ``band`` against the middle half.

    Counted between ``left + margin`` and ``right - margin``.
    """
    ymin, ymax = (float(v) for v in p.domain.bounds()[2:])
    centre = p.centre[p.placed]
    diameter = 2.0 * p.radius[p.placed]
    keep = (centre[:, 0] > left + margin) & (centre[:, 0] < right - margin)
    y, d = centre[keep, 1], diameter[keep]
    fine = d < 2.0 * np.sqrt(2.0)
    width = right - left - 2.0 * margin
    quarter = 0.25 * (ymax - ymin)
    middle = (y > ymin + quarter) & (y < ymax - quarter)
    dens0 = middle.sum() / (width * 2.0 * quarter)
    diam0 = d[middle].mean()
    fine0 = fine[middle].mean()
    print("  slab (y from, to)   particles  density dev %  mean d dev %  finest share dev %")
    starts = list(np.arange(ymin, ymin + band, slab)) + list(np.arange(ymax - band, ymax, slab))
    for lo in starts:
        if lo + slab > ymax + 1e-9 * (ymax - ymin):
            continue  # a slab that would reach past the top
        sel = (y >= lo) & (y < lo + slab)
        n = int(sel.sum())
        dev = 100 * (n / (width * slab) / dens0 - 1)
        ddev = 100 * (d[sel].mean() / diam0 - 1) if n else float("nan")
        fdev = 100 * (fine[sel].mean() / fine0 - 1) if n else float("nan")
        print(f"  {lo:8.0f} {lo + slab:8.0f}  {n:9d}  {dev:+12.1f}  {ddev:+12.1f}  {fdev:+17.1f}")


if __name__ == "__main__":
    main()
