"""The same box and the same spheres packed by regopack and by YADE, side by side.

Draws one population of spheres with regopack (Chang'e-5 sizes cut to
2-12 µm, the six minerals of Table 2 as spheres, a walled cube of side
``--side`` µm, ``count = "auto"``) and packs it three times with regopack:
by the homogeneous sweep (``order = "sweep"``, columns of 45 µm) with the
tail closing and with the paced closing (``dem3d``'s), and in the paper's
order. In one YADE process (``yade -n -x``, Debian package ``yade``) the
same box is then filled

* by ``pack.SpherePack.makeCloud`` with the population's size distribution
  (``psdSizes``/``psdCumm`` by number at 64 quantiles, no ``num``: random
  sequential addition of drawn sizes until one sphere finds no room);
* by ``makeCloud`` given also ``num`` = the population's count (YADE then
  scales every size down until ``num`` spheres fit; the scale is printed);
* by ``pack.randomDensePack`` with a periodic cell (``spheresInCell`` = the
  population's count); it takes no size distribution, only radii uniform in
  ``radius (1 ± rRelFuzz)``, given here the span of the population's radii;
* by the periodic compression that ``randomDensePack`` runs (``PeriIsoCompressor``,
  its materials and settings), started from the population's own radii as a
  gas at solid fraction 0.25 (placed by this script, largest first), then
  tiled over and cut to the box as ``randomDensePack`` does; and the same
  without friction (``frictionAngle = 0`` instead of 0.5 rad), the densest
  state this compression reaches.

YADE works in SI units: lengths go to it in metres (µm × 10⁻⁶) and come back
in µm. Every result is loaded into a regopack sphere packing, so the same
analyzers give φ (interior, outside a wall margin of ``d_max``, and the whole
box) and the interior coordination number Z, and the same exact oracle
(``regopack.verify``) counts the overlapping pairs (a lens volume above 10⁻⁹
of the smaller sphere) and the spheres beyond a wall. Times are wall times
in this one run: regopack's after a warm-up that loads its compiled kernels,
YADE's inside its process (its start-up, a few seconds, is printed apart).
Without YADE the script says why and prints regopack's rows. Run from the
repository root:

    python benchmarks/peers_yade.py
    python benchmarks/peers_yade.py --side 80 --seed 2 --yade makeCloud randomDensePack
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import regopack
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.verification.polyhedra import Report3D

METRE = 1e-6
"""One µm in metres: the scale of every length handed to YADE and back."""

PHASES = (
    ("pyroxene", 0.343),
    ("feldspar", 0.315),
    ("glass", 0.161),
    ("olivine", 0.091),
    ("ilmenite", 0.052),
    ("others", 0.038),
)

REGOPACK = (
    ("sweep, tail closing", "sweep", "tail"),
    ("sweep, paced closing", "sweep", "paced"),
    ("paper's order", "paper", ""),
)
"""regopack's rows: label, ``insertion.order`` and the sweep's ``closing``."""

METHODS = (
    "makeCloud",
    "makeCloud_num",
    "randomDensePack",
    "compression",
    "compression_frictionless",
)
"""YADE's ways to fill the box, in the order they run."""

YADE_SCRIPT = r"""
import json, sys, time
from yade import pack, utils
from yade.wrapper import *  # the engines and materials (yade -x imports them too)
from yade.minieigenHP import Vector3

cfg = json.load(open(sys.argv[1]))
lo, hi = Vector3(*cfg["lo"]), Vector3(*cfg["hi"])
box = pack.inAlignedBox(lo, hi)
out = {}
switched = []  # the scene compression() runs in, while it runs


def record(name, sp, seconds, **extra):
    out[name] = {"seconds": seconds, "centres": [list(c) for c, r in sp],
                 "radii": [r for c, r in sp], **extra}


def makeCloud():
    t = time.perf_counter()
    sp = pack.SpherePack()
    sp.makeCloud(lo, hi, psdSizes=cfg["psd_sizes"], psdCumm=cfg["psd_cumm"],
                 distributeMass=False, seed=cfg["seed"])
    record("makeCloud", sp, time.perf_counter() - t, psd_scaling=sp.appliedPsdScaling)


def makeCloud_num():
    t = time.perf_counter()
    sp = pack.SpherePack()
    sp.makeCloud(lo, hi, psdSizes=cfg["psd_sizes"], psdCumm=cfg["psd_cumm"],
                 num=cfg["count"], distributeMass=False, seed=cfg["seed"])
    record("makeCloud_num", sp, time.perf_counter() - t, psd_scaling=sp.appliedPsdScaling)


def randomDensePack():
    t = time.perf_counter()
    sp = pack.randomDensePack(box, radius=cfg["r_mean"], rRelFuzz=cfg["r_fuzz"],
                              spheresInCell=cfg["count"], returnSpherePack=True,
                              seed=cfg["seed"])
    record("randomDensePack", sp, time.perf_counter() - t)


def compression(name="compression", friction=0.5):
    # randomDensePack's periodic branch, started from the population's own radii
    t = time.perf_counter()
    radii = cfg["radii"]
    size = [h - l for h, l in zip(cfg["hi"], cfg["lo"])]
    O.switchScene()
    switched.append(True)
    O.resetThisScene()
    O.periodic = True
    O.cell.setBox(Vector3(*cfg["cloud_cell"]))
    mean = sum(radii) / len(radii)
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()], verletDist=0.05 * mean),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                        [Law2_ScGeom_FrictPhys_CundallStrack()]),
        PeriIsoCompressor(charLen=2 * mean, stresses=[-100e9, -1e8], maxUnbalanced=1e-2,
                          doneHook="O.pause();", globalUpdateInt=5, keepProportions=True),
        NewtonIntegrator(damping=0.6),
    ]
    O.materials.append(FrictMat(young=30e9, frictionAngle=friction, poisson=0.3, density=1e3))
    for c, r in zip(cfg["cloud"], radii):
        O.bodies.append(utils.sphere(Vector3(*c), r))
    O.dt = utils.PWaveTimeStep()
    O.run()
    O.wait()
    steps = O.iter
    sp = pack.SpherePack()
    sp.fromSimulation()
    periodic_phi = sum(4.0 / 3.0 * 3.141592653589793 * r**3 for c, r in sp) / O.cell.volume
    O.switchScene()
    switched.clear()
    sp.cellFill(Vector3(*size))
    sp = pack.filterSpherePack(box, sp, returnSpherePack=True)
    record(name, sp, time.perf_counter() - t, steps=steps, cell_phi=periodic_phi)


def compression_frictionless():
    compression("compression_frictionless", 0.0)


for name in cfg["methods"]:
    try:
        globals()[name]()
    except Exception as exc:  # one method failing leaves the others their row
        if switched:
            O.switchScene()
            switched.clear()
        out[name] = {"error": f"{type(exc).__name__}: {exc}"}

json.dump(out, open(sys.argv[2], "w"))
"""


def scene(side: float, seed: int, order: str, closing: str = "tail") -> dict[str, Any]:
    """Spheres in a walled cube of ``side`` µm, packed in ``order`` (a sweep with ``closing``)."""
    insertion: dict[str, Any] = {"kind": "available-surface", "order": order}
    if order == "sweep":
        insertion.update(closing=closing, strip=45.0)
    return {
        "name": "peers",
        "seed": seed,
        "count": "auto",
        "domain": {"kind": "box", "width": side, "height": side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0, "d0": 16.0, "alpha": 6.9},
        "phases": [
            {"name": name, "fraction": fraction, "shape": {"kind": "sphere"}}
            for name, fraction in PHASES
        ],
        "insertion": insertion,
        "density": {"kind": "eta", "eta": 0.0},
    }


def sphere_packing(centres: ArrayLike, radii: ArrayLike, domain: Box) -> Packing:
    """A regopack packing of the spheres ``radii`` at ``centres`` in ``domain``, all placed."""
    return Packing.of_spheres(centres, radii, domain)


def measure(packing: Packing) -> dict[str, Any]:
    """φ interior and whole box, Z interior, overlapping pairs and spheres outside."""
    res = regopack.analyze(packing, ["density", "coordination"])
    report = regopack.verify(packing)
    assert isinstance(report, Report3D)
    return {
        "placed": packing.n_placed,
        "phi_interior": res["density"]["phi_interior"],
        "phi_domain": res["density"]["phi_domain"],
        "z_interior": res["coordination"]["z_interior"],
        "overlaps": report.n_overlapping_pairs,
        "worst_overlap": report.worst_overlap_fraction,
        "outside": report.n_outside,
    }


def psd(radii: ArrayLike, points: int = 64) -> tuple[list[float], list[float]]:
    """Sieve diameters and cumulative number fractions of ``radii``, at ``points`` quantiles."""
    d = np.sort(2.0 * np.asarray(radii, dtype=float))
    cumm = np.linspace(0.0, 1.0, points)
    sizes = np.quantile(d, cumm)
    return sizes.tolist(), cumm.tolist()


def periodic_cloud(
    radii: NDArray[np.float64], size: ArrayLike, solid: float, seed: int, tries: int = 10_000
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A gas of ``radii`` in a periodic cell of the proportions of ``size`` at fraction ``solid``.

    The cell holds the spheres' volume at the solid fraction ``solid`` (0.25
    in ``randomDensePack``); the spheres go in largest first at uniform random
    points, a point refused while it overlaps a sphere already in (nearest
    periodic image). Returns the cell's sides and the centres, in the order of ``radii``.
    """
    rng = np.random.default_rng(seed)
    shape = np.asarray(size, dtype=float)
    volume = float(np.sum(4.0 / 3.0 * np.pi * radii**3))
    cell = shape * (volume / solid / float(np.prod(shape))) ** (1.0 / 3.0)
    centres = np.full((radii.size, 3), np.nan)
    done: list[int] = []
    for k in np.argsort(-radii, kind="stable"):
        for _ in range(tries):
            x = rng.random(3) * cell
            if done:
                delta = centres[done] - x
                delta -= cell * np.round(delta / cell)
                if np.any(np.einsum("ij,ij->i", delta, delta) < (radii[done] + radii[k]) ** 2):
                    continue
            centres[k] = x
            done.append(int(k))
            break
        else:
            raise RuntimeError(f"no room for sphere {k} in the periodic cloud after {tries} tries")
    return cell, centres


def yade_config(
    population: NDArray[np.float64], domain: Box, seed: int, methods: list[str]
) -> dict[str, Any]:
    """What the YADE script needs, every length in metres."""
    r = population * METRE
    sizes, cumm = psd(r)
    b = domain.bounds()
    cell, cloud = periodic_cloud(r, [b[1] - b[0], b[3] - b[2], b[5] - b[4]], 0.25, seed)
    r_min, r_max = float(r.min()), float(r.max())
    return {
        "lo": [b[0] * METRE, b[2] * METRE, b[4] * METRE],
        "hi": [b[1] * METRE, b[3] * METRE, b[5] * METRE],
        "psd_sizes": sizes,
        "psd_cumm": cumm,
        "r_mean": 0.5 * (r_min + r_max),
        "r_fuzz": (r_max - r_min) / (r_max + r_min),
        "count": int(r.size),
        "radii": r.tolist(),
        "cloud_cell": cell.tolist(),
        "cloud": cloud.tolist(),
        "seed": seed,
        "methods": methods,
    }


def run_yade(cfg: dict[str, Any], timeout: float) -> tuple[dict[str, Any] | None, str, float]:
    """Run the YADE script on ``cfg``: its results (lengths in µm), a reason, its wall time."""
    yade = shutil.which("yade")
    if yade is None:
        return None, "no `yade` on PATH (Debian: apt-get install yade)", 0.0
    with tempfile.TemporaryDirectory() as tmp:
        script, cfg_path, out_path = (Path(tmp) / n for n in ("s.py", "c.json", "o.json"))
        script.write_text(YADE_SCRIPT)
        cfg_path.write_text(json.dumps(cfg))
        t = time.perf_counter()
        try:
            done = subprocess.run(
                [yade, "-n", "-x", str(script), str(cfg_path), str(out_path)],
                capture_output=True, text=True, timeout=timeout,
            )  # fmt: skip
        except subprocess.TimeoutExpired:
            return None, f"yade took longer than --timeout {timeout:g} s", timeout
        wall = time.perf_counter() - t
        if done.returncode or not out_path.exists():
            tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
            return None, f"yade failed ({done.returncode}): {' | '.join(tail)}", wall
        out = json.loads(out_path.read_text())
    for row in out.values():
        row["centres"] = np.asarray(row["centres"], dtype=float).reshape(-1, 3) / METRE
        row["radii"] = np.asarray(row["radii"], dtype=float) / METRE
    return out, "", wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=float, default=60.0, help="side of the cube (µm)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--yade",
        nargs="*",
        default=list(METHODS),
        choices=list(METHODS),
        help="YADE methods to run (none: regopack only)",
    )
    parser.add_argument("--timeout", type=float, default=1800.0, help="for YADE (s)")
    args = parser.parse_args()
    if not (args.side > 12.0 and np.isfinite(args.side)):
        parser.error("--side must be a finite number above 12 (µm)")

    for _, order, closing in REGOPACK:  # load the compiled kernels
        regopack.pack(scene(20.0, args.seed, order, closing), verify=False)
    rows: list[tuple[str, float, dict[str, Any]]] = []
    population: NDArray[np.float64] | None = None
    for label, order, closing in REGOPACK:
        t = time.perf_counter()
        packing = regopack.pack(scene(args.side, args.seed, order, closing), verify=False)
        seconds = time.perf_counter() - t
        rows.append((f"regopack {label}", seconds, measure(packing)))
        if population is None:
            population = packing.radius.copy()
        assert np.array_equal(population, packing.radius)  # one drawn population
        domain = packing.domain
    assert population is not None
    d = 2.0 * population
    print(
        f"population: {population.size} spheres drawn, d {d.min():.2f}-{d.max():.2f} µm, "
        f"number-mean d {d.mean():.2f} µm, box {args.side:g} µm cube (seed {args.seed})"
    )
    if args.yade:
        cfg = yade_config(population, domain, args.seed, args.yade)
        print(
            f"YADE in SI units (1 µm = 1e-6 m): randomDensePack rMean "
            f"{cfg['r_mean'] / METRE:.2f} µm, rRelFuzz {cfg['r_fuzz']:.3f}, "
            f"spheresInCell {cfg['count']}"
        )
        out, reason, wall = run_yade(cfg, args.timeout)
        if out is None:
            print(f"YADE skipped: {reason}")
        else:
            inside = sum(r["seconds"] for r in out.values())
            print(f"YADE process: {wall:.1f} s wall, of which {wall - inside:.1f} s start-up")
            for name in args.yade:
                row = out[name]
                if "error" in row:
                    print(f"  {name} failed: {row['error']}")
                    continue
                extra = {k: v for k, v in row.items() if k not in ("centres", "radii", "seconds")}
                if extra:
                    print(f"  {name}: {extra}")
                packing = sphere_packing(row["centres"], row["radii"], domain)
                rows.append((f"YADE {name}", row["seconds"], measure(packing)))
    else:
        print("YADE skipped: no method asked (--yade with no name)")
    print()
    print("| method | particles | time (s) | φ interior | φ whole box | Z interior | "
          "overlapping pairs | worst overlap | outside |")  # fmt: skip
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, seconds, m in rows:
        phi_in, phi, z = (
            _cell(m[k], f)
            for k, f in (("phi_interior", ".3f"), ("phi_domain", ".3f"), ("z_interior", ".2f"))
        )
        print(
            f"| {name} | {m['placed']:,} | {seconds:.3g} | {phi_in} | {phi} | {z} | "
            f"{m['overlaps']:,} | {m['worst_overlap']:.2g} | {m['outside']} |"
        )


def _cell(value: float | None, spec: str) -> str:
    """``value`` formatted by ``spec``, or a dash when there is none (an empty interior)."""
    return "–" if value is None else format(value, spec)


if __name__ == "__main__":
    main()
