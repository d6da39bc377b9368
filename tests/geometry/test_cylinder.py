"""The walled cylinder: measure, window, containment and its record."""

from __future__ import annotations

import math

import numpy as np
import pytest

from regopack.base.errors import GeometryError
from regopack.geometry.domain import Cylinder, domain_from_dict


def test_measure_bounds_and_centre() -> None:
    c = Cylinder.centred(2.0, 6.0, (1.0, -1.0, 3.0))
    assert c.volume == pytest.approx(math.pi * 4.0 * 6.0)
    assert c.bounds().tolist() == [-1.0, 3.0, -3.0, 1.0, 0.0, 6.0]
    assert c.center == (1.0, -1.0, 3.0)
    assert c.size == (4.0, 4.0, 6.0)


def test_contains_is_strict_and_nan_outside() -> None:
    c = Cylinder(0.0, 0.0, 1.0, 0.0, 2.0)
    pts = np.array(
        [[0, 0, 1], [0.99, 0, 1], [1.0, 0, 1], [0.8, 0.8, 1], [0, 0, 0], [0, 0, 2], [np.nan, 0, 1]]
    )
    assert c.contains(pts).tolist() == [True, True, False, False, False, False, False]


def test_interior_window_and_its_collapse() -> None:
    c = Cylinder(0.0, 0.0, 3.0, 0.0, 10.0)
    w = c.interior(1.0)
    assert (w.radius, w.zmin, w.zmax) == (2.0, 1.0, 9.0)
    empty = c.interior(6.0)
    assert empty.radius == 0.0 and empty.zmin == empty.zmax == 5.0 and empty.volume == 0.0


def test_record_round_trip_is_exact() -> None:
    c = Cylinder(0.1, 0.2, 0.3, -0.7, 1.1)
    assert domain_from_dict(c.to_dict(), 3) == c


@pytest.mark.parametrize(
    ("record", "words"),
    [
        ({"kind": "cylinder", "axis": [0, 0], "radius": 0, "z": [0, 1]}, "radius"),
        ({"kind": "cylinder", "axis": [0, 0], "radius": 1, "z": [1, 0]}, "zmin < zmax"),
        ({"kind": "cylinder", "axis": [0], "radius": 1, "z": [0, 1]}, "axis"),
        ({"kind": "cylinder", "axis": [0, 0], "radius": "1", "z": [0, 1]}, "radius"),
        ({"kind": "cylinder", "axis": [0, math.inf], "radius": 1, "z": [0, 1]}, "axis"),
    ],
)
def test_bad_records_are_refused(record: dict[str, object], words: str) -> None:
    with pytest.raises((GeometryError, ValueError, TypeError), match=words):
        domain_from_dict(record, 3)


def test_a_cylinder_is_not_a_plane_domain() -> None:
    record = Cylinder(0.0, 0.0, 1.0, 0.0, 1.0).to_dict()
    with pytest.raises(ValueError, match="3D domain kind"):
        domain_from_dict(record, 2)
