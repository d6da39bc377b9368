"""How many strips (2D) or columns per side (3D) the sweep order cuts a domain into."""

from __future__ import annotations

import math


def strip_count(width: float, strip: float, most: int) -> int:
    """Return how many equal strips of about ``strip`` fit across ``width``.

    At least one and at most ``most``; ``strip <= 0`` (or a width that is not
    positive) gives one.
    """
    if not (strip > 0 and width > 0):
        return 1
    ratio = width / strip
    if not math.isfinite(ratio):
        return most
    return int(min(most, max(1, math.floor(ratio))))
