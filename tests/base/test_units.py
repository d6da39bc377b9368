"""The scene's length unit and the reference diameter of the default lengths."""

from __future__ import annotations

import pytest

import regopack
from regopack.base.errors import ConfigError
from regopack.base.units import (
    BUILTIN_D_MIN,
    check_length_unit,
    decimals,
    length_scale,
    length_unit,
    reference_diameter,
)
from regopack.scenes.model import load_scene
from regopack.testing import packing_from_polygons, scaled_packing


@pytest.mark.parametrize(
    ("given", "unit"), [("m", "m"), ("mm", "mm"), ("µm", "µm"), ("um", "µm"), ("nm", "nm")]
)
def test_a_scene_names_its_length_unit(given, unit):
    scene = load_scene("small", overrides=[f"length_unit={given}"])
    assert scene.length_unit == unit
    assert regopack.scene("small", length_unit=given).to_dict()["length_unit"] == unit


def test_the_default_unit_is_the_micrometre_and_is_written_with_the_scene():
    assert load_scene("small").length_unit == "µm"
    assert regopack.scene("small").to_dict()["length_unit"] == "µm"


@pytest.mark.parametrize("bad", ["ft", "MM", "", "micrometre"])
def test_another_unit_is_refused_in_one_line_naming_source_field_value_and_choices(bad):
    with pytest.raises(ConfigError) as info:
        load_scene("small", overrides=[f'length_unit="{bad}"'])
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith("--set: length_unit = ")
    assert repr(bad).strip("'") in text
    assert "'m', 'cm', 'mm', 'µm', 'nm'" in text


def test_a_packing_without_a_unit_is_in_micrometres_and_a_bad_one_is_refused():
    square = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
    assert length_unit(square) == "µm"
    assert length_unit({"length_unit": "um"}) == "µm"
    with pytest.raises(ConfigError, match=r"the packing's scene: length_unit = 'ft': not a"):
        length_unit({"length_unit": "ft"})
    with pytest.raises(ConfigError, match=r"length_unit = 3 \(int\)"):
        check_length_unit(3)


def test_the_reference_diameter_is_the_scenes_d_min_else_the_smallest_particle():
    square = packing_from_polygons(
        [[(0, 0), (1, 0), (1, 1), (0, 1)], [(2, 0), (4, 0), (4, 2), (2, 2)]]
    )
    assert reference_diameter(square) == pytest.approx(2.0 / 3.141592653589793**0.5)
    square.scene["size"] = {"kind": "change5", "d_min": 2.0}
    assert reference_diameter(square) == 2.0 == BUILTIN_D_MIN
    assert length_scale(square) == 1.0
    assert length_scale(scaled_packing(square, 1e-3)) == pytest.approx(1e-3, rel=1e-15)
    square.scene["size"] = {"kind": "monodisperse", "d": 3.0}
    assert reference_diameter(square) == pytest.approx(2.0 / 3.141592653589793**0.5)


def test_fixed_decimals_follow_the_scale():
    assert [decimals(s, 2) for s in (1.0, 1e-3, 1e3, 2.0, float("nan"))] == [2, 5, 0, 2, 2]
