"""The exporter interface: one for both dimensions, a suffix per dimension, the old 3D name."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import ClassVar

import pytest
from packings3d import cube_and_sphere
from pydantic import BaseModel, ConfigDict

from regopack.base.errors import PluginError
from regopack.exports.pipeline import build_exporter, export_packing, output_path
from regopack.registry import interfaces
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Exporter
from regopack.registry.manager import Registry, build_plugin_manager
from regopack.registry.plugin_types import ExporterSpec


class NoConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Both(Exporter):
    suffix = ".two"
    suffixes: ClassVar[Mapping[int, str]] = {3: ".three"}

    def __init__(self, config: object = None) -> None:
        pass

    def export(self, packing, path, *, analyses=None):  # type: ignore[no-untyped-def]
        Path(path).write_text(f"{packing.domain.dimension}\n")
        return Path(path)


def test_the_suffix_is_the_2d_one_unless_a_dimension_has_its_own() -> None:
    assert Both().suffix_for(2) == ".two" and Both().suffix_for(3) == ".three"

    class Plain(Both):
        suffixes: ClassVar[Mapping[int, str]] = {}

    assert Plain().suffix_for(3) == ".two"
    assert output_path(Both(), Path("a/p.npz"), dimension=3) == Path("a/p.three")
    assert output_path(Both(), Path("a/p.npz")) == Path("a/p.two")


def registry_of(*specs: ExporterSpec) -> Registry:
    class Plugin:
        @hookimpl
        def regopack_exporters(self):  # type: ignore[no-untyped-def]
            return list(specs)

    return Registry.from_manager(
        build_plugin_manager(autoload=False, builtins=(), extra=[Plugin()])
    )


def test_an_exporter_written_against_the_old_3d_interface_still_works(tmp_path) -> None:
    with pytest.warns(
        DeprecationWarning, match=r"interfaces\.SolidExporter is deprecated.*Exporter"
    ):
        from regopack.registry.interfaces import SolidExporter

    class Old(SolidExporter):
        suffix = ".old"

        def __init__(self, config: object = None) -> None:
            pass

        def export(self, packing, path, *, analyses=None):  # type: ignore[no-untyped-def]
            Path(path).write_text("old\n")
            return Path(path)

    assert issubclass(SolidExporter, Exporter)
    registry = registry_of(ExporterSpec("old", NoConfig, Old, dimensions=(3,)))
    path = export_packing(cube_and_sphere(), "old", tmp_path / "p.old", registry=registry)
    assert path.read_text() == "old\n"


def test_a_plugin_that_builds_no_exporter_is_one_error() -> None:
    registry = registry_of(
        ExporterSpec("odd", NoConfig, lambda config: object(), dimensions=(2, 3))
    )
    with pytest.raises(PluginError, match=r"built a object, not an Exporter$"):
        build_exporter(registry, "odd")


def test_other_names_of_the_module_are_still_missing() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchExporter'"):
        interfaces.NoSuchExporter  # noqa: B018
