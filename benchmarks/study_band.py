"""The sweep's band at the bottom wall: where each size lands, and what the lags change.

Two measurements of the scene ``dem`` (Table-1 materials) in a tall domain:

``depths``
    One sweep without lags; for every particle placed while its zone is at
    full height (and its top farther than two zone heights from both walls),
    the depth of its centre below the zone's top, in zone heights, per √2
    class: the share landing above the top, in each tenth of the zone, and
    below its bottom.
``profile``
    Sweeps with each ``insertion.lag`` given, seed by seed; per height band
    (the wall layer, the first zone heights, the top), the number of placed
    particles of each √2 class over the bulk's (the middle of the height),
    centres farther than 40 µm from the side walls. Also prints the pilot's
    figures and the times.

Run from the repository root::

    python benchmarks/study_band.py depths --seeds 1 2 3
    python benchmarks/study_band.py profile --seeds 1 2 3 4 --lags none pilot
    python benchmarks/study_band.py profile --set 'insertion.closing="tail"'
"""

from __future__ import annotations

import argparse
import itertools
import math
import platform
import time

import numpy as np

from regopack.api.functions import pack_and_summarise
from regopack.plugins.inserters.available_arc import sweep
from regopack.plugins.inserters.available_arc.state import ArcState
from regopack.registry.manager import default_registry
from regopack.run.pipeline import draw_population
from regopack.scenes.model import load_scene, resolve_scene

MARGIN = 40.0
"""Distance from the side walls within which centres are left out (d_max)."""


def _overrides(width: float, height: float, extra: list[str]) -> list[str]:
    return [f"domain.width={width}", f"domain.height={height}", "domain.center=[0.0, 0.0]", *extra]


def _edges(d_min: float, top: float) -> np.ndarray:
    k = math.ceil(2.0 * math.log2(top / d_min)) + 1
    return d_min * np.sqrt(2.0) ** np.arange(k)


def depths(args: argparse.Namespace) -> None:
    """Print the landing depth of each size class in the steady state of a sweep without lags."""
    edges = _edges(2.0, 45.0)
    bins = np.array([-np.inf, 0.0, *np.linspace(0.1, 1.0, 10), np.inf])
    hist = np.zeros((len(edges) - 1, len(bins) - 1))
    for seed in args.seeds:
        extra = [*args.set, f"seed={seed}"]
        scene = resolve_scene(
            load_scene("dem", _overrides(args.width, args.height, extra)), default_registry()
        )
        rng = np.random.default_rng(scene.seed)
        pop = draw_population(scene, rng)
        domain = scene.scene.domain.to_domain()
        cfg = scene.insertion.config
        st = ArcState(pop, domain, t=cfg.t, tau=None, linear=False, pool_rows=4096)
        zone = cfg.zone or 6.0 * float(pop.radius.max())
        sw = sweep.Sweep(len(pop), domain.height, zone, closing=cfg.closing, width=domain.width)
        n = len(pop)
        for begin in range(0, n, 256):
            st.reserve_rows(256)
            sw.run(begin, min(n, begin + 256), st.outlines, st.packed, st.work, rng, st.rounded)
        top = sw.lags.top_at[:n]
        ymin = float(domain.bounds()[2])
        y = st.packed.cy[:n] - ymin
        zt = (top + 1.0) * sw.delta  # the zone top's height
        keep = (top >= 0) & (zt > 2.0 * zone) & (zt < domain.height - 2.0 * zone)
        depth = (zt[keep] - y[keep]) / zone
        d = 2.0 * pop.radius[:n][keep]
        cls = np.searchsorted(edges, d, side="right") - 1
        for c in range(len(edges) - 1):
            hist[c] += np.histogram(depth[cls == c], bins)[0]
        print(f"seed {seed}: {int(keep.sum())} placements measured", flush=True)
    print()
    head = ["above", *[f"{a:.1f}–{b:.1f}" for a, b in itertools.pairwise(bins[1:-1])]]
    print("| d (µm) | placements | " + " | ".join(head) + " | below |")
    print("|---|---:|" + "---:|" * (len(head) + 1))
    for c in range(len(edges) - 1):
        total = hist[c].sum()
        if total < 50:
            continue
        shares = " | ".join(f"{100 * v / total:.1f}" for v in hist[c])
        print(f"| {edges[c]:.2f}–{edges[c + 1]:.2f} | {int(total)} | {shares} |")


def profile(args: argparse.Namespace) -> None:
    """Print class-by-class number ratios of height bands to the bulk, for each lag setting."""
    w, h = args.width, args.height
    bands = [(0.0, 40.0), (40.0, 120.0), (120.0, 200.0), (200.0, 280.0)]
    bands += [(h - 200.0, h - 100.0), (h - 100.0, h - MARGIN)]
    bulk = (0.25 * h, 0.75 * h)
    edges = _edges(2.0, 45.0)
    for lag in args.lags:
        acc = np.zeros((len(bands) + 1, len(edges) - 1))
        for seed in args.seeds:
            extra = [*args.set, f"insertion.lag={lag!r}".replace("'", '"')]
            started = time.perf_counter()
            out = pack_and_summarise(
                "dem", seed=seed, **_as_kwargs(_overrides(w, h, extra)), figures=False
            )
            took = time.perf_counter() - started
            p, s = out.packing, out.summary  # type: ignore[union-attr]
            c = p.centre[p.placed]
            d = 2.0 * p.radius[p.placed]
            y = c[:, 1] - float(p.domain.bounds()[2])
            inner = np.abs(c[:, 0] - float(np.mean(p.domain.bounds()[:2]))) < 0.5 * w - MARGIN
            for k, (a, b) in enumerate([*bands, bulk]):
                sel = inner & (y >= a) & (y < b)
                acc[k] += np.histogram(d[sel], edges)[0] / (b - a)
            print(
                f"lag {lag}, seed {seed}: placed {p.n_placed}, refused {s.get('refused')}, "
                f"not offered {s.get('not_offered')}, lagged {s.get('lagged')}, "
                f"largest lag {s.get('lag_max', 0.0):.1f} µm, pilot "
                f"{s.get('pilot_time_s', 0.0):.2f} s, insertion {s['insert_time_s']:.2f} s, "
                f"run {took:.1f} s",
                flush=True,
            )
        print()
        span = f"{bulk[0]:.0f}–{bulk[1]:.0f} µm"
        print(f"lag = {lag}: particles per µm of height over the bulk's ({span})")
        cols = [f"{a:.1f}–{b:.1f}" for a, b in itertools.pairwise(edges)]
        print("| height (µm) | all | " + " | ".join(f"d {c}" for c in cols) + " |")
        print("|---|---:|" + "---:|" * len(cols))
        ref = acc[-1]
        for k, (a, b) in enumerate(bands):
            ratio = np.where(ref > 0, acc[k] / np.where(ref > 0, ref, 1.0), np.nan)
            cells = " | ".join(f"{ratio[j]:.2f}" if ref[j] > 0 else "" for j in range(len(cols)))
            print(f"| {a:.0f}–{b:.0f} | {acc[k].sum() / ref.sum():.3f} | {cells} |")
        print()


def _as_kwargs(overrides: list[str]) -> dict[str, object]:
    import tomllib

    out: dict[str, object] = {}
    for item in overrides:
        key, value = item.split("=", 1)
        out[key] = tomllib.loads(f"v = {value}")["v"]
    return out


def main() -> None:
    """Parse the command line and run one of the measurements."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("what", choices=["depths", "profile"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--width", type=float, default=800.0)
    parser.add_argument("--height", type=float, default=1600.0)
    parser.add_argument("--lags", nargs="+", default=["none", "pilot"])
    parser.add_argument("--set", action="append", default=[], help="scene override, as in --set")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"scene: dem, {args.width:g} x {args.height:g} µm, seeds {args.seeds}, {args.set}")
    started = time.perf_counter()
    (depths if args.what == "depths" else profile)(args)
    print(f"benchmark wall time: {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()
