"""The sweep's ``even`` closing in 3D: the particles not placed spread over the sizes."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import regopack
from regopack.plugins.inserters.available_surface.sweep import (
    EVEN_MIN_OFFERED,
    held_back,
    size_classes,
)


def test_size_classes_are_sqrt2_classes_with_the_sparse_coarse_tail_pooled() -> None:
    r = np.array([1.0, 1.2, 1.5, 2.0, 3.0, 3.0, 3.0, 6.0])
    # sqrt(2) classes from the smallest radius: [1, 1.41), [1.41, 2), [2, 2.83), ...
    np.testing.assert_array_equal(size_classes(r, 1), [0, 0, 1, 2, 3, 3, 3, 5])
    # a class of fewer than `fewest` joins the one below, from the coarsest down
    np.testing.assert_array_equal(size_classes(r, 2), [0, 0, 1, 2, 3, 3, 3, 3])
    np.testing.assert_array_equal(size_classes(r, 5), [0, 0, 1, 2, 2, 2, 2, 2])
    assert size_classes(np.zeros(0)).shape == (0,)


def test_a_class_placed_above_the_least_placed_share_is_held_back() -> None:
    m = EVEN_MIN_OFFERED
    offered = np.array([4 * m, 2 * m, m])
    placed = np.array([4 * m, 2 * m - 1, m - 10])  # the coarsest: 10 refused
    assert held_back(offered, placed, 0)  # at 1.0, above the coarsest's share
    assert held_back(offered, placed, 1)
    assert not held_back(offered, placed, 2)  # the least placed class itself
    # a class offered fewer than EVEN_MIN_OFFERED does not set the floor
    assert not held_back(np.array([m, m - 1]), np.array([m, 0]), 0)
    # at the floor's share exactly: offered
    assert not held_back(np.array([2 * m, 4 * m]), np.array([m, 2 * m]), 0)
    assert not held_back(np.array([0, 2 * m]), np.array([0, m]), 0)  # none offered yet


def scene(closing: str, seed: int) -> dict[str, Any]:
    """Spheres of 1-6 in a box four largest diameters wide: most of the run is the closing."""
    return {
        "name": "even",
        "seed": seed,
        "count": "auto",
        "domain": {"kind": "box", "width": 24.0, "height": 24.0, "depth": 24.0},
        "size": {"kind": "uniform", "d_min": 1.0, "d_max": 6.0},
        "phases": [{"name": "a", "fraction": 1.0, "shape": {"kind": "sphere"}}],
        "insertion": {
            "kind": "available-surface",
            "order": "sweep",
            "zone": 8.0,
            "strip": 12.0,
            "closing": closing,
        },
        "density": {"kind": "eta"},
    }


@pytest.mark.parametrize("closing", ["paced", "even"])
def test_the_even_closing_places_every_size_class_in_the_same_share(closing: str) -> None:
    packing = regopack.pack(scene(closing, 1), verify=False)
    cls = size_classes(packing.radius)
    drawn = np.bincount(cls)
    share = np.bincount(cls[packing.placed], minlength=drawn.shape[0]) / drawn
    stats = packing.stats
    if closing == "paced":
        # the paced closing refuses the coarse under the top and places the fine
        assert share[-1] < share[0] - 0.3
        assert "held" not in stats
        return
    # every class within a few particles of the same share; the coarse refused are few
    assert np.ptp(share) < 0.12
    assert stats["held"] > stats["refused"]
    assert stats["held"] + stats["refused"] + stats["not_offered"] + packing.n_placed == len(cls)
