"""The number of strips (2D) or columns per side (3D) of the sweep order."""

from __future__ import annotations

import pytest

from regopack.plugins.common.strips import strip_count


@pytest.mark.parametrize(
    ("width", "strip", "expected"),
    [
        (800.0, 0.0, 1),  # no strips: one zone
        (800.0, -5.0, 1),
        (0.0, 10.0, 1),
        (800.0, 800.0, 1),
        (800.0, 1e9, 1),
        (800.0, 799.0, 1),  # strips are at least the width asked for
        (800.0, 400.0, 2),
        (800.0, 270.0, 2),
        (800.0, 5e-324, 64),  # width / strip overflows: the most
        (1e300, 1e-300, 64),
        (800.0, 1.0, 64),
    ],
)
def test_strip_count(width: float, strip: float, expected: int) -> None:
    assert strip_count(width, strip, 64) == expected
