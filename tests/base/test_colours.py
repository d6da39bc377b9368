"""Mineral colours follow the names, not the order of the phases."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from regopack.base.colours import MINERAL_COLOURS, mineral_colours

TABLE1 = ["pyroxene", "feldspar", "glass", "olivine", "ilmenite", "others"]
names = st.lists(st.text(min_size=1, max_size=8), min_size=1, max_size=16, unique=True)


def test_known_minerals_keep_their_colour_in_any_order():
    forward = dict(zip(TABLE1, mineral_colours(TABLE1), strict=True))
    backward = dict(zip(TABLE1[::-1], mineral_colours(TABLE1[::-1]), strict=True))
    assert forward == backward
    assert forward["glass"] == MINERAL_COLOURS["glass"]
    assert len(set(forward.values())) == len(TABLE1)


def test_another_name_keeps_its_colour_from_scene_to_scene():
    basalt = {mineral_colours([other, "basalt"])[1] for other in ("pyroxene", "glass", "x")}
    assert len(basalt) == 1
    assert basalt.isdisjoint(MINERAL_COLOURS.values())


def test_two_names_of_one_colour_are_told_apart():
    assert len(set(mineral_colours(["feldspar", "plagioclase"]))) == 2
    assert len(set(mineral_colours(["glass", "Glass"]))) == 2


@given(names)
def test_colours_depend_on_the_set_of_names_only_and_differ(names):
    colours = dict(zip(names, mineral_colours(names), strict=True))
    again = dict(zip(names[::-1], mineral_colours(names[::-1]), strict=True))
    assert colours == again
    assert len(set(colours.values())) == len(names)


@given(st.lists(st.sampled_from([*TABLE1, "Glass", "plagioclase", "basalt", "x"]), unique=True))
def test_mixtures_of_known_and_other_names_differ(names):
    assert len(set(mineral_colours(names))) == len(names)
