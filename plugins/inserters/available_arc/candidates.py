"""Candidate search: the first inserted particle, in insertion order, that passes screening.

Candidate ``k`` passes when ``r_new < t * rmin_k``. The reference mode scans
``rmin`` linearly as the paper does; the indexed mode descends a max-tree over
``rmin`` by insertion index. Both evaluate the same floating-point predicate on
the same values (multiplication by ``t > 0`` is monotone under rounding), so
they return the same candidate.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]


def tree_size(n: int) -> int:
    """Return the number of leaves of the max-tree for ``n`` particles (a power of two)."""
    size = 1
    while size < max(n, 1):
        size *= 2
    return size


@numba.njit(cache=True)
def tree_set(tree: FloatArray, leaves: int, k: int, value: float) -> None:
    """Set ``rmin`` of insertion index ``k`` and update the maxima above it.

    The update stops at the first node whose maximum does not change: every
    node above it holds the maximum of its children already.
    """
    node = k + leaves
    tree[node] = value
    node >>= 1
    while node >= 1:
        a = tree[2 * node]
        b = tree[2 * node + 1]
        m = a if a >= b else b
        if tree[node] == m:
            return
        tree[node] = m
        node >>= 1


@numba.njit(cache=True)
def first_candidate(
    tree: FloatArray, leaves: int, start: int, count: int, r: float, t: float, linear: bool
) -> int:
    """Smallest insertion index ``k`` in ``[start, count)`` with ``r < t * rmin_k``, or -1."""
    if start >= count:
        return -1
    if linear:
        for k in range(start, count):
            if r < t * tree[leaves + k]:
                return k
        return -1
    node = start + leaves
    while True:
        if r < t * tree[node]:
            while node < leaves:
                if r < t * tree[2 * node]:
                    node = 2 * node
                else:
                    node = 2 * node + 1
            k = node - leaves
            return k if k < count else -1
        while node & 1:
            node >>= 1
        if node == 0:
            return -1
        node += 1
