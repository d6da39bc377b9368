"""The parameters that the available-arc and available-surface inserters share."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from regopack.plugins.inserters.available_arc import AvailableArcConfig
from regopack.plugins.inserters.available_surface.inserter import AvailableSurfaceConfig
from regopack.plugins.inserters.options import ZONE_PER_RADIUS, sweep_zone

CONFIGS = [AvailableArcConfig, AvailableSurfaceConfig]


def test_the_default_zone_is_three_diameters_of_the_largest_particle() -> None:
    assert ZONE_PER_RADIUS == 6.0
    assert sweep_zone(0.0, np.array([0.5, 2.0, 1.0])) == 12.0
    assert sweep_zone(3.5, np.array([0.5, 2.0, 1.0])) == 3.5
    assert sweep_zone(0.0, np.empty(0)) == 1.0


@pytest.mark.parametrize("config", CONFIGS)
def test_both_inserters_bound_and_describe_the_zone_alike(config: type) -> None:
    field = config.model_json_schema()["properties"]["zone"]
    assert field == AvailableArcConfig.model_json_schema()["properties"]["zone"]
    assert field["minimum"] == 0 and field["default"] == 0.0
    assert "three times the largest" in field["description"]
    assert config(zone=2.5).zone == 2.5
    for bad in (-1.0, float("inf"), float("nan")):
        with pytest.raises(ValidationError):
            config(zone=bad)


@pytest.mark.parametrize("config", CONFIGS)
def test_both_inserters_take_a_screening_coefficient_in_the_unit_interval(config: type) -> None:
    assert config().t == 0.999
    assert config(t=1.0).t == 1.0
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(ValidationError):
            config(t=bad)
    assert "Screening coefficient" in config.model_json_schema()["properties"]["t"]["description"]
