"""Per-call time of the 3D available-surface kernels, after compilation.

Times :func:`minkowski_envelope` for two random polyhedra (convex hulls of
``--points`` random points: 24 give about 30 faces, 9 about 14) and
:func:`free_surface` for a candidate with 20 interferers around it: random
polyhedra of about the same size, each touching the candidate or up to 30 %
further out (they may overlap each other), so that their envelopes cover
most of the candidate's. Each kernel runs in a compiled loop (the cost
inside an inserter) and from Python (plus the boxing of the named tuples);
the minimum over the repeats is printed, as the machine may be shared. Run
from the repository root:

    python benchmarks/bench_surface_kernels.py
    python benchmarks/bench_surface_kernels.py --points 9 --interferers 20
"""

from __future__ import annotations

import argparse
import platform
import time
from collections.abc import Callable

import numba
import numpy as np

from regopack.plugins.inserters.available_surface.envelope import minkowski_envelope
from regopack.plugins.inserters.available_surface.free_surface import (
    FreeSurface,
    Interferers,
    free_surface,
    interferers_from,
    sample_free_point,
)
from regopack.plugins.inserters.available_surface.polyhedron import (
    Polyhedron,
    polyhedron_from_points,
)


def random_polyhedron(rng: np.random.Generator, n: int, scale: float = 1.0) -> Polyhedron:
    """Convex hull of ``n`` points at radius in ``[0.5, 1] * scale``, random directions."""
    while True:
        d = rng.normal(size=(n, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        try:
            return polyhedron_from_points(d * rng.uniform(0.5, 1.0, size=(n, 1)) * scale)
        except ValueError:
            continue


def scene(
    rng: np.random.Generator, points: int, interferers: int
) -> tuple[Polyhedron, Polyhedron, Polyhedron, Interferers]:
    """A candidate ``P_k``, a new particle ``Q``, ``E_k`` and interferers around ``E_k``.

    Interferer ``j`` sits in a random direction ``u`` at a distance that puts
    ``P_j`` just against ``P_k`` (on the boundary of ``P_k ⊕ (-P_j)``) times
    ``[1, 1.3]``, so that its envelope overlaps ``E_k``.
    """
    pk = random_polyhedron(rng, points)
    q = random_polyhedron(rng, points, 0.6)
    ek = minkowski_envelope(pk, q)
    envs: list[Polyhedron] = []
    centres = []
    for _ in range(interferers):
        pj = random_polyhedron(rng, points, rng.uniform(0.6, 1.2))
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        contact = minkowski_envelope(pk, pj)  # P_j's centres touching P_k: its boundary
        cos = contact.normals @ u
        reach = float(np.min(contact.support[cos > 0] / cos[cos > 0]))
        centres.append(u * reach * rng.uniform(1.0, 1.3))
        envs.append(minkowski_envelope(pj, q))
    return pk, q, ek, interferers_from(envs, np.array(centres))


@numba.njit
def _loop_envelope(p: Polyhedron, q: Polyhedron, n: int) -> int:
    s = 0
    for _ in range(n):
        s += minkowski_envelope(p, q).normals.shape[0]
    return s


@numba.njit
def _loop_free(e: Polyhedron, c: np.ndarray, it: Interferers, lo: np.ndarray,
               hi: np.ndarray, n: int) -> float:  # fmt: skip
    s = 0.0
    for _ in range(n):
        s += free_surface(e, c, it, lo, hi, np.zeros((0, 4))).area
    return s


@numba.njit
def _loop_sample(fs: FreeSurface, n: int) -> float:
    s = 0.0
    for i in range(n):
        s += sample_free_point(fs, (i * 0.618034) % 1.0, (i * 0.414214) % 1.0, 0.5)[0]
    return s


def best_us(call: Callable[[], object], per: int, repeats: int) -> float:
    """Minimum over ``repeats`` of the time per call, in microseconds."""
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        call()
        best = min(best, (time.perf_counter() - t) / per * 1e6)
    return float(best)


def measure(
    pk: Polyhedron, q: Polyhedron, ek: Polyhedron, it: Interferers, repeats: int
) -> dict[str, float]:
    """Microseconds per call of each kernel on one scene (minimum over the repeats)."""
    lo = np.full(3, -np.inf)
    hi = np.full(3, np.inf)
    origin = np.zeros(3)
    fs = free_surface(ek, origin, it, lo, hi, np.zeros((0, 4)))
    _loop_envelope(pk, q, 1)
    _loop_free(ek, origin, it, lo, hi, 1)
    _loop_sample(fs, 1)
    n = 200
    return {
        "envelope": best_us(lambda: _loop_envelope(pk, q, n), n, repeats),
        "envelope_py": best_us(lambda: minkowski_envelope(pk, q), 1, 20 * repeats),
        "free": best_us(lambda: _loop_free(ek, origin, it, lo, hi, n), n, repeats),
        "free_py": best_us(
            lambda: free_surface(ek, origin, it, lo, hi, np.zeros((0, 4))), 1, 20 * repeats
        ),
        "sample": best_us(lambda: _loop_sample(fs, 10 * n), 10 * n, repeats),
        "free_fraction": fs.area / _area(ek),
        "pieces": len(fs.cumulative),
    }


def main() -> None:
    """Time the kernels on a few random scenes and print the results."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--points", type=int, default=24, help="points per random polyhedron")
    ap.add_argument("--interferers", type=int, default=20)
    ap.add_argument("--scenes", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"{platform.processor() or platform.machine()}, numba {numba.__version__}")
    for s in range(args.scenes):
        pk, q, ek, it = scene(rng, args.points, args.interferers)
        t = measure(pk, q, ek, it, args.repeats)
        print(
            f"scene {s}: P {len(pk.normals)} faces, Q {len(q.normals)} faces, "
            f"E {len(ek.normals)} faces; free {t['free_fraction']:.3f} of E's area "
            f"in {t['pieces']} pieces\n"
            f"  envelope      {t['envelope']:7.1f} us compiled loop, "
            f"{t['envelope_py']:7.1f} us from Python\n"
            f"  free surface  {t['free']:7.1f} us compiled loop, "
            f"{t['free_py']:7.1f} us from Python\n"
            f"  sample point  {t['sample']:7.2f} us"
        )


def _area(poly: Polyhedron) -> float:
    from regopack.plugins.inserters.available_surface.polyhedron import face_area

    return sum(face_area(poly, f) for f in range(len(poly.normals)))


if __name__ == "__main__":
    main()
