"""Scenes know their dimension: 3D domains, and one-line refusals of mixed dimensions."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import pydantic
import pytest

from regopack.base.errors import ConfigError
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import InsertionStrategy
from regopack.registry.plugin_types import InserterSpec
from regopack.scenes.model import Domain, load_scene, resolve_scene
from regopack.testing import make_registry

SCENE_3D = """\
name = "s3"
count = 10
[domain]
kind = "box"
width = 50.0
height = 40.0
depth = 30.0
[size]
kind = "monodisperse"
d = 4.0
[[phases]]
name = "glass"
fraction = 1.0
shape = { kind = "sphere" }
[insertion]
kind = "flat3d"
[density]
kind = "eta"
"""


class _Config(pydantic.BaseModel):
    model_config = pydantic.ConfigDict(extra="forbid")


class _Flat3D(InsertionStrategy):
    def __init__(self, config: _Config) -> None:
        self.config = config

    def pack(self, population, domain, controller, rng, progress=None):  # type: ignore[no-untyped-def]
        raise NotImplementedError


class _Plugin:
    @hookimpl
    def regopack_inserters(self) -> Iterable[InserterSpec]:
        return [InserterSpec(name="flat3d", config_model=_Config, factory=_Flat3D, dimensions=(3,))]


@pytest.fixture
def registry():  # type: ignore[no-untyped-def]
    return make_registry(_Plugin())


def _error(path: str | Path, registry, overrides: tuple[str, ...] = ()) -> str:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError) as info:
        resolve_scene(load_scene(str(path), list(overrides)), registry)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def test_a_box_makes_the_scene_3d(tmp_path, registry) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "s3.toml"
    path.write_text(SCENE_3D, encoding="utf-8")
    resolved = resolve_scene(load_scene(str(path)), registry)
    d = resolved.scene.domain
    assert d.dimension == 3 and d.center == (0.0, 0.0, 0.0)
    assert d.to_box().size == (50.0, 30.0, 40.0)  # width x, depth y, height z
    assert resolved.domain == d.to_box() and resolved.domain.dimension == 3
    assert resolved.to_dict()["domain"] == {
        "kind": "box",
        "width": 50.0,
        "height": 40.0,
        "depth": 30.0,
        "center": [0.0, 0.0, 0.0],
    }


def test_a_2d_shape_in_a_3d_scene_is_refused_naming_the_file(tmp_path, registry) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "s3.toml"
    path.write_text(SCENE_3D.replace('kind = "sphere"', 'kind = "octagon"'), encoding="utf-8")
    msg = _error(path, registry)
    assert msg.startswith(f"{path}: phases.0.shape.kind = 'octagon' is a 2D shape")
    assert "domain.kind = 'box' makes the scene 3D; 3D shapes: polyhedron, sphere" in msg


def test_a_3d_domain_set_on_a_2d_scene_blames_the_option(registry) -> None:  # type: ignore[no-untyped-def]
    msg = _error("small", registry, ("domain.kind=box", "domain.center=[0, 0, 0]"))
    assert msg.startswith("--set: phases.0.shape.kind = 'octagon' is a 2D shape")


def test_a_3d_shape_in_a_2d_scene_lists_the_2d_shapes(registry) -> None:  # type: ignore[no-untyped-def]
    msg = _error("small", registry, ("phases.0.shape={kind='sphere'}",))
    assert "phases.0.shape.kind = 'sphere' is a 3D shape" in msg
    assert "2D shapes: disk, octagon" in msg


def test_an_inserter_of_the_other_dimension_is_refused(tmp_path, registry) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "s3.toml"
    path.write_text(SCENE_3D.replace('kind = "flat3d"', 'kind = "available-arc"'), encoding="utf-8")
    msg = _error(path, registry)
    assert "insertion.kind = 'available-arc' is a 2D inserter" in msg
    assert "3D inserters: available-surface, flat3d" in msg
    msg = _error("small", registry, ("insertion={kind='flat3d'}",))
    assert "insertion.kind = 'flat3d' is a 3D inserter, but domain.kind = 'rectangle'" in msg


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"kind": "box", "center": [1.0, 2.0]}, "kind 'box' takes 3 coordinates"),
        ({"kind": "rectangle", "center": [1.0, 2.0, 3.0]}, "kind 'rectangle' takes 2 coordinates"),
        ({"kind": "rectangle", "depth": 3.0}, "depth does not apply to kind 'rectangle'"),
        ({"kind": "periodic-box", "radius": 3.0}, "radius does not apply to kind 'periodic-box'"),
        ({"kind": "box", "width": 1e200, "height": 1e200, "depth": 1e200}, "overflows"),
        ({"kind": "box", "depth": 0.0}, "greater than 0"),
    ],
)
def test_bad_box_fields_are_refused(fields: dict[str, object], message: str) -> None:
    with pytest.raises(pydantic.ValidationError, match=message):
        Domain.model_validate(fields)


def test_2d_domains_are_unchanged() -> None:
    d = Domain.model_validate({"kind": "rectangle", "center": [1.0, 2.0]})
    assert d.dimension == 2 and d.center == (1.0, 2.0)
    assert d.to_domain().bounds().tolist() == [-399.0, 401.0, -398.0, 402.0]


def test_a_cylinder_scene_is_three_dimensional() -> None:
    from regopack.geometry.domain import Cylinder
    from regopack.scenes.model import Domain as DomainSpec

    d = DomainSpec(kind="cylinder", radius=20.0, height=50.0, center=(1.0, 2.0, 3.0))
    assert d.dimension == 3
    assert d.to_domain() == Cylinder(1.0, 2.0, 20.0, -22.0, 28.0)
    with pytest.raises(ValueError, match="depth does not apply to kind 'cylinder'"):
        DomainSpec(kind="cylinder", radius=20.0, depth=5.0)
    with pytest.raises(ValueError, match="kind 'cylinder' needs radius"):
        DomainSpec(kind="cylinder", height=5.0)
