"""Parameters that the available-arc and available-surface inserters share.

Each field type carries its bounds and description, so that both config
models declare it alike (``zone: SweepZone = 0.0``) and the two dimensions
cannot drift apart.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

__all__ = ["ZONE_PER_RADIUS", "ScreeningCoefficient", "SweepLag", "SweepZone", "sweep_zone"]

ZONE_PER_RADIUS = 6.0
"""Default sweep zone height over the largest equivalent radius (three diameters)."""

ScreeningCoefficient = Annotated[float, Field(gt=0, le=1, allow_inf_nan=False)]
"""The screening coefficient ``t`` in (0, 1]; each model gives its default and description."""

SweepZone = Annotated[
    float,
    Field(
        ge=0,
        allow_inf_nan=False,
        description=(
            "Height of the sweep's zone (length units); 0: three times the largest "
            "particle's equivalent diameter. Ignored by order = 'paper'."
        ),
    ),
]
"""Height of the sweep's zone, 0 for the default of :func:`sweep_zone`."""

SweepLag = Annotated[
    Literal["pilot", "none"],
    Field(
        description=(
            "When the sweep offers each particle: 'pilot' (after the front has risen by "
            "the depth below the zone top at which particles of its size land in the "
            "steady state, measured by a small pilot sweep first: no band of fine "
            "particles at the bottom, at the cost of the pilot) or 'none' (at its turn "
            "in the stream). Ignored by order = 'paper'."
        ),
    ),
]
"""When the sweep offers each particle (see ``regopack.plugins.inserters.available_arc.lag``)."""


def sweep_zone(zone: float, radius: NDArray[np.float64]) -> float:
    """Return the zone height asked for, or for 0 :data:`ZONE_PER_RADIUS` times the largest radius.

    Parameters
    ----------
    zone
        The ``zone`` parameter (length units, 0 for the default).
    radius
        Equivalent radius of every particle; with none the default is 1.

    Examples
    --------
    >>> import numpy as np
    >>> sweep_zone(0.0, np.array([1.0, 2.5]))
    15.0
    >>> sweep_zone(4.0, np.array([1.0, 2.5]))
    4.0
    """
    if zone > 0.0:
        return zone
    return ZONE_PER_RADIUS * float(radius.max()) if radius.shape[0] else 1.0
