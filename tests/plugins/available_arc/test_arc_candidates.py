"""Screening: the max-tree returns exactly what the linear scan returns."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.available_arc.candidates import first_candidate, tree_set, tree_size


@given(
    values=st.lists(st.one_of(st.floats(0.5, 2.0), st.just(float("inf"))), min_size=1, max_size=70),
    r=st.floats(0.4, 2.1),
    t=st.sampled_from([1.0, 0.999, 0.99, 0.5]),
    start=st.integers(0, 75),
)
@settings(max_examples=300, deadline=None)
def test_tree_matches_linear_scan(values, r, t, start) -> None:
    n = len(values)
    leaves = tree_size(n + 3)
    tree = np.full(2 * leaves, -np.inf)
    for k, v in enumerate(values):
        tree_set(tree, leaves, k, v)
    expected = next((k for k in range(start, n) if r < t * values[k]), -1)
    assert first_candidate(tree, leaves, start, n, r, t, False) == expected
    assert first_candidate(tree, leaves, start, n, r, t, True) == expected


def test_tree_size_is_power_of_two() -> None:
    assert [tree_size(n) for n in (0, 1, 2, 3, 5, 1024, 1025)] == [1, 1, 2, 4, 8, 1024, 2048]
