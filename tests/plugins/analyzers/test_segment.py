"""The equivalent circular segment solver."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.analyzers.segment import equivalent_segment, segment_ratio, solve_theta


def test_round_trip_over_the_whole_range() -> None:
    theta = np.concatenate(
        [
            np.geomspace(1e-8, 1.0, 400),
            np.linspace(1.0, 2 * np.pi - 1.0, 400),
            2 * np.pi - np.geomspace(1.0, 1e-8, 400),
        ]
    )
    back = solve_theta(segment_ratio(theta))
    assert np.all(np.isfinite(back))
    lower = theta <= np.pi
    assert np.allclose(back[lower], theta[lower], rtol=1e-10, atol=0)
    # above pi the input itself carries an absolute rounding error of ~1e-15
    assert np.allclose(back[~lower], theta[~lower], rtol=0, atol=1e-13)


def test_known_segments() -> None:
    theta, radius, depth = equivalent_segment(np.pi / 2, 2.0)
    assert (
        theta == pytest.approx(np.pi)
        and radius == pytest.approx(1.0)
        and depth == pytest.approx(1.0)
    )
    # a segment of a unit circle with theta = pi / 2
    t = np.pi / 2
    area = 0.5 * (t - np.sin(t))
    chord = 2 * np.sin(t / 2)
    theta, radius, depth = equivalent_segment(area, chord)
    assert theta == pytest.approx(t, rel=1e-12)
    assert radius == pytest.approx(1.0, rel=1e-12)
    assert depth == pytest.approx(1 - np.cos(t / 2), rel=1e-12)


@given(ratio=st.floats(1e-15, 1e15), chord=st.floats(1e-6, 1e6))
@settings(max_examples=300, deadline=None)
def test_never_nan_or_negative(ratio: float, chord: float) -> None:
    theta, radius, depth = equivalent_segment(ratio * chord * chord, chord)
    assert np.isfinite(theta) and np.isfinite(radius) and np.isfinite(depth)
    assert 0 < theta < 2 * np.pi
    assert depth >= 0 and radius > 0


def test_small_ratio_series() -> None:
    area, chord = 1e-15, 1.0
    theta, _, depth = equivalent_segment(area, chord)
    assert theta == pytest.approx(12 * area / chord**2, rel=1e-9)
    assert depth == pytest.approx(1.5 * area / chord, rel=1e-9)


def test_bad_ratio_is_rejected() -> None:
    with pytest.raises(ValueError, match="positive"):
        solve_theta(np.array([0.0]))
    with pytest.raises(ValueError, match="positive"):
        solve_theta(np.array([math.nan]))
