"""Mineral colours follow the names, not the order of the phases."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from regopack.colours import MINERAL_COLOURS, mineral_colours

TABLE1 = ["pyroxene", "feldspar", "glass", "olivine", "ilmenite", "others"]


def test_known_minerals_keep_their_colour_in_any_order():
    forward = dict(zip(TABLE1, mineral_colours(TABLE1), strict=True))
    backward = dict(zip(TABLE1[::-1], mineral_colours(TABLE1[::-1]), strict=True))
    assert forward == backward
    assert forward["glass"] == MINERAL_COLOURS["glass"]
    assert len(set(forward.values())) == len(TABLE1)


@given(st.lists(st.text(min_size=1, max_size=8), min_size=1, max_size=10, unique=True))
def test_colours_depend_on_the_set_of_names_only(names):
    colours = dict(zip(names, mineral_colours(names), strict=True))
    again = dict(zip(names[::-1], mineral_colours(names[::-1]), strict=True))
    assert colours == again
    if len(names) <= 10:
        assert len(set(colours.values())) == len(names)
