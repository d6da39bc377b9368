"""Screening: the max-tree returns exactly what the linear scan returns."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.inserters.available_arc.candidates import first_candidate, tree_set, tree_size


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


@given(
    updates=st.lists(
        st.tuples(
            st.integers(0, 40),
            st.one_of(st.floats(0.5, 2.0), st.just(float("inf")), st.just(float("-inf"))),
        ),
        min_size=1,
        max_size=200,
    ),
    r=st.floats(0.4, 2.1),
    start=st.integers(0, 41),
)
@settings(max_examples=300, deadline=None)
def test_tree_stays_the_maxima_of_its_leaves_under_any_updates(updates, r, start) -> None:
    """Lowering, raising, hiding (-inf) and showing leaves again, in any order: every node
    holds the maximum of its children after each update (the update stops early)."""
    n = 41
    leaves = tree_size(n)
    tree = np.full(2 * leaves, -np.inf)
    values = np.full(leaves, -np.inf)
    for k, v in updates:
        tree_set(tree, leaves, k, v)
        values[k] = v
        full = np.full(2 * leaves, -np.inf)
        full[leaves:] = values
        for node in range(leaves - 1, 0, -1):
            full[node] = max(full[2 * node], full[2 * node + 1])
        np.testing.assert_array_equal(tree, full)
    expected = next((k for k in range(start, n) if r < 0.999 * values[k]), -1)
    assert first_candidate(tree, leaves, start, n, r, 0.999, False) == expected
