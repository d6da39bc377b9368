"""3D domains: volume, windows, containment, periodic wrapping and the file record."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.domain3d import Box, PeriodicBox, domain3d_from_dict
from regopack.errors import GeometryError


def test_centred_box_puts_height_on_z() -> None:
    box = Box.centred(4.0, 2.0, 3.0, center=(1.0, 1.0, 1.0))
    assert box.size == (4.0, 3.0, 2.0)
    assert box.volume == pytest.approx(24.0)
    assert box.center == (1.0, 1.0, 1.0)
    assert box.bounds().tolist() == [-1.0, 3.0, -0.5, 2.5, 0.0, 2.0]


@pytest.mark.parametrize(
    "bounds",
    [
        (0, 0, 0, 1, 0, 1),
        (0, 1, 1, 0, 0, 1),
        (0, 1, 0, 1, 0, float("nan")),
        (0, 1, 0, 1, 0, float("inf")),
    ],
)
def test_degenerate_or_non_finite_boxes_are_refused(bounds: tuple[float, ...]) -> None:
    with pytest.raises(GeometryError):
        Box(*bounds)


def test_contains_is_strict_and_nan_is_outside() -> None:
    box = Box(0, 1, 0, 1, 0, 1)
    pts = [[0.5, 0.5, 0.5], [0.0, 0.5, 0.5], [0.5, 0.5, 1.0], [np.nan, 0.5, 0.5], [2, 0.5, 0.5]]
    assert box.contains(pts).tolist() == [True, False, False, False, False]


def test_interior_window_and_its_collapse() -> None:
    box = Box(0, 10, 0, 4, 0, 6)
    w = box.interior(1.0)
    assert w.bounds().tolist() == [1, 9, 1, 3, 1, 5]
    collapsed = box.interior(2.5)  # y collapses to its centre
    assert collapsed.bounds().tolist() == [2.5, 7.5, 2.0, 2.0, 2.5, 3.5]
    assert collapsed.volume == 0.0


def test_periodic_box_wraps_into_its_cell_and_has_no_walls() -> None:
    box = PeriodicBox(0, 2, 0, 3, 0, 4)
    assert box.interior(1.0) is box
    wrapped = box.wrap([[2.0, -0.5, 9.0], [-1e-18, 3.0, 0.0]])
    assert (wrapped >= [0, 0, 0]).all() and (wrapped < [2, 3, 4]).all()
    assert wrapped[0].tolist() == [0.0, 2.5, 1.0]
    assert box.minimum_image([[1.5, -2.0, 3.0]]).tolist() == [[-0.5, 1.0, -1.0]]
    assert box.contains([[100.0, -5.0, 0.0], [np.nan, 0, 0]]).tolist() == [True, False]


@settings(max_examples=50, deadline=None)
@given(
    lo=st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3),
    size=st.lists(st.floats(1e-6, 1e6), min_size=3, max_size=3),
    periodic=st.booleans(),
)
def test_file_record_round_trips(lo: list[float], size: list[float], periodic: bool) -> None:
    cls = PeriodicBox if periodic else Box
    hi = [a + s for a, s in zip(lo, size, strict=True)]
    if any(not a < b for a, b in zip(lo, hi, strict=True)):
        return  # the size vanished in rounding
    box = cls(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    back = domain3d_from_dict(box.to_dict())
    assert type(back) is cls
    assert back == box


@pytest.mark.parametrize(
    ("record", "error"),
    [
        ({"kind": "rectangle", "bounds": [0, 1, 0, 1]}, ValueError),
        ({"kind": "box", "bounds": [0, 1, 0, 1]}, ValueError),
        ({"kind": "box", "bounds": [0, 1, 0, 1, 0, "2"]}, TypeError),
        ({"kind": "box", "bounds": [0, 1, 0, 1, 0, float("inf")]}, ValueError),
        ({"kind": "box", "bounds": [0, 1, 0, 1, 2, 1]}, GeometryError),
        ({"kind": "box"}, KeyError),
    ],
)
def test_bad_file_records_are_refused(record: dict[str, object], error: type[Exception]) -> None:
    with pytest.raises(error):
        domain3d_from_dict(record)
