from __future__ import annotations

import sys
import types
import warnings

import pluggy
import pytest
from fakes import FakePlugin, ShapeConfig, SizeConfig, UniformDiameter, fake_registry

from regopack.base.errors import DeprecatedNameWarning, PluginError
from regopack.registry.hookspecs import hookimpl
from regopack.registry.manager import (
    BUILTIN_PLUGINS,
    DISABLE_AUTOLOAD_ENV,
    HOOK_OF_KIND,
    Registry,
    build_plugin_manager,
    default_registry,
)
from regopack.registry.plugin_types import KINDS, PluginSpec, ShapeSpec, SizeDistributionSpec


class OtherSizes:
    @hookimpl
    def regopack_size_distributions(self):
        return [SizeDistributionSpec("change5", SizeConfig, UniformDiameter)]


def test_builtin_plugins_are_the_plugin_modules():
    assert BUILTIN_PLUGINS == (
        "regopack.plugins.sizes.change5",
        "regopack.plugins.shapes.octagon",
        "regopack.plugins.inserters.available_arc",
        "regopack.plugins.density.eta",
        "regopack.plugins.density.target",
        "regopack.plugins.analyzers",
        "regopack.plugins.sizes.distributions",
        "regopack.plugins.shapes.polygons",
        "regopack.plugins.shapes.disk",
        "regopack.plugins.shapes.sphere",
        "regopack.plugins.shapes.polyhedra.shape",
        "regopack.plugins.shapes.solid_templates.shape",
        "regopack.plugins.inserters.available_surface.inserter",
        "regopack.plugins.inserters.rsa",
        "regopack.plugins.exporters",
        "regopack.plugins.exporters.image_export",
        "regopack.plugins.exporters.gsd_export",
    )


def test_hooks_cover_every_kind():
    assert set(HOOK_OF_KIND) == set(KINDS)


def test_registry_collects_fake_plugin():
    reg = fake_registry()
    assert reg.names("size") == ["change5"]
    assert reg.names("shape") == ["octagon"]
    assert reg.names("insertion") == ["available-arc"]
    assert reg.names("density") == ["eta"]
    assert reg.names("analysis") == []
    assert isinstance(reg.get("shape", "octagon"), ShapeSpec)
    assert ("shape", "octagon") in reg
    assert ("shape", "nope") not in reg


def test_origin_names_the_plugin():
    pm = build_plugin_manager(autoload=False, builtins=())
    plugin = FakePlugin()
    pm.register(plugin, name="my-plugin")
    reg = Registry.from_manager(pm)
    assert reg.origin("shape", "octagon") == "my-plugin"


def test_duplicate_name_names_both_plugins():
    pm = build_plugin_manager(autoload=False, builtins=())
    pm.register(FakePlugin(), name="first-plugin")
    pm.register(OtherSizes(), name="second-plugin")
    with pytest.raises(PluginError) as info:
        Registry.from_manager(pm)
    msg = str(info.value)
    assert "'change5'" in msg
    assert "first-plugin" in msg
    assert "second-plugin" in msg
    assert "\n" not in msg


def test_unknown_name_lists_known_sorted():
    class MoreShapes:
        @hookimpl
        def regopack_shapes(self):
            return [ShapeSpec("zigzag", ShapeConfig, lambda c: None)]

    reg = fake_registry(MoreShapes())
    with pytest.raises(PluginError) as info:
        reg.get("shape", "octagn")
    assert (
        str(info.value)
        == "unknown shape kind 'octagn'; did you mean 'octagon'? known kinds: octagon, zigzag"
    )


def test_unknown_name_with_nothing_registered():
    reg = Registry.from_manager(build_plugin_manager(autoload=False, builtins=()))
    with pytest.raises(PluginError, match=r"known kinds: \(none\)"):
        reg.get("analysis", "rdf")


def test_unknown_plugin_kind():
    with pytest.raises(PluginError, match="unknown plugin kind 'colour'"):
        fake_registry().names("colour")


def test_wrong_record_type_is_rejected():
    class Wrong:
        @hookimpl
        def regopack_shapes(self):
            return [SizeDistributionSpec("square", SizeConfig, UniformDiameter)]

    with pytest.raises(PluginError, match="returned a SizeDistributionSpec, expected ShapeSpec"):
        fake_registry(Wrong())


def test_plain_plugin_spec_is_rejected():
    class Wrong:
        @hookimpl
        def regopack_shapes(self):
            return [PluginSpec("square", ShapeConfig, lambda c: None)]

    with pytest.raises(PluginError, match="expected ShapeSpec"):
        fake_registry(Wrong())


def test_non_iterable_result_is_rejected():
    class Wrong:
        @hookimpl
        def regopack_shapes(self):
            return ShapeSpec("square", ShapeConfig, lambda c: None)

    with pytest.raises(PluginError, match="must return an iterable of ShapeSpec"):
        fake_registry(Wrong())


def test_config_model_must_be_pydantic():
    class Wrong:
        @hookimpl
        def regopack_shapes(self):
            return [ShapeSpec("square", dict, lambda c: None)]  # type: ignore[arg-type]

    with pytest.raises(PluginError, match="not a pydantic model"):
        fake_registry(Wrong())


def test_none_result_is_empty():
    class Nothing:
        @hookimpl
        def regopack_shapes(self):
            return None

    assert fake_registry(Nothing()).names("shape") == ["octagon"]


def test_unknown_hook_is_rejected():
    class Typo:
        @hookimpl
        def regopack_shape(self):
            return []

    with pytest.raises(PluginError, match="regopack_shape"):
        build_plugin_manager(autoload=False, builtins=(), extra=[Typo()])


def test_registering_twice_is_an_error():
    plugin = FakePlugin()
    with pytest.raises(PluginError):
        build_plugin_manager(autoload=False, builtins=(), extra=[plugin, plugin])


def test_builtins_are_imported_by_module_name(monkeypatch):
    module = types.ModuleType("fake_builtin_module")

    @hookimpl
    def regopack_shapes():
        return [ShapeSpec("hexagon", ShapeConfig, lambda c: None)]

    module.regopack_shapes = regopack_shapes  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "fake_builtin_module", module)
    pm = build_plugin_manager(autoload=False, builtins=("fake_builtin_module",))
    reg = Registry.from_manager(pm)
    assert reg.names("shape") == ["hexagon"]
    assert reg.origin("shape", "hexagon") == "fake_builtin_module"


@pytest.mark.parametrize(
    ("env", "autoload", "expected"),
    [
        (None, None, True),
        ("", None, True),
        ("1", None, False),
        (None, False, False),
        ("1", True, True),
    ],
)
def test_entry_point_autoload(monkeypatch, env, autoload, expected):
    calls = []
    monkeypatch.setattr(
        pluggy.PluginManager, "load_setuptools_entrypoints", lambda self, group: calls.append(group)
    )
    if env is None:
        monkeypatch.delenv(DISABLE_AUTOLOAD_ENV, raising=False)
    else:
        monkeypatch.setenv(DISABLE_AUTOLOAD_ENV, env)
    build_plugin_manager(autoload=autoload, builtins=())
    assert calls == (["regopack"] if expected else [])


def test_info_of_builtin_plugins_names_regopack():
    import regopack
    from regopack.registry.manager import PluginInfo

    reg = Registry.from_manager(
        build_plugin_manager(autoload=False, builtins=("regopack.plugins.density.eta",))
    )
    assert reg.info("density", "eta") == PluginInfo(
        plugin="regopack.plugins.density.eta",
        module="regopack.plugins.density.eta",
        distribution="regopack",
        version=regopack.__version__,
    )
    assert reg.info("density", "eta").package == f"regopack {regopack.__version__}"


def test_info_of_a_plugin_object_without_a_distribution():
    reg = fake_registry()
    info = reg.info("shape", "octagon")
    assert (info.module, info.distribution, info.version, info.package) == (
        "fakes",
        None,
        None,
        "-",
    )
    with pytest.raises(PluginError, match="unknown shape kind 'nope'"):
        reg.info("shape", "nope")


def test_info_defaults_to_the_origin_for_a_hand_made_registry():
    spec = ShapeSpec("hexagon", ShapeConfig, lambda c: None)
    reg = Registry({"shape": {"hexagon": (spec, "my-plugin")}})
    info = reg.info("shape", "hexagon")
    assert (info.plugin, info.module, info.distribution) == ("my-plugin", "my-plugin", None)


def test_the_builtin_figure_specs_follow_the_analyzers():
    reg = default_registry(autoload=False)
    assert [f.analyzer for f in reg.figures()] == [
        "density",
        "network",
        "contacts",
        "coordination",
        "rdf",
        "homogeneity",
        "psd",
        "local_fraction",
        "contacts3d",
        "coordination3d",
        "rdf3d",
        "psd3d",
        "homogeneity3d",
    ]
    assert {f.analyzer for f in reg.figures()} <= {*reg.names("analysis"), *reg.aliases("analysis")}
    assert reg.figures("coordination")[0].captions.keys() == {
        "z-vs-tol",
        "z-per-mineral",
        "z-vs-tol-3d",
        "z-per-mineral-3d",
    }
    assert reg.figures("nothing") == ()


def test_a_figure_hook_returning_other_records_is_refused():
    class BadFigures:
        @hookimpl
        def regopack_analysis_figures(self):
            return [ShapeSpec("zigzag", ShapeConfig, lambda c: None)]

    with pytest.raises(PluginError, match="returned a ShapeSpec, expected FigureSpec"):
        fake_registry(BadFigures())


# ---------------------------------------------------------------------------
# old names (aliases)


class OldShapeNames:
    @hookimpl
    def regopack_shapes(self):
        return [ShapeSpec("hexagon", ShapeConfig, lambda c: None, aliases=("hexagon2d", "hex"))]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_an_old_name_of_any_kind_gives_the_spec_and_warns_once(kind):
    spec = KINDS[kind]("new", ShapeConfig, lambda c: None, "one", aliases=("old",))
    reg = Registry({kind: {"new": (spec, "my-plugin")}})
    with pytest.warns(
        DeprecatedNameWarning, match=rf"the {kind} kind 'old' is deprecated .*use 'new'"
    ):
        assert reg.get(kind, "old") is spec
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert reg.get(kind, "old") is spec  # once per registry
        assert reg.get(kind, "new") is spec
        assert reg.canonical(kind, "old") == "new" and reg.origin(kind, "old") == "my-plugin"
    assert (kind, "old") in reg and reg.names(kind) == ["new"]
    assert reg.aliases(kind) == {"old": "new"}


def test_old_names_come_from_the_hooks_and_stay_out_of_the_listings():
    reg = fake_registry(OldShapeNames())
    assert reg.names("shape") == ["hexagon", "octagon"]
    assert reg.aliases("shape") == {"hex": "hexagon", "hexagon2d": "hexagon"}
    assert reg.info("shape", "hex") == reg.info("shape", "hexagon")
    with pytest.raises(PluginError, match=r"^unknown shape kind 'hexagn'; did you mean 'hexagon'"):
        reg.canonical("shape", "hexagn")


def test_an_old_name_that_names_another_spec_is_refused():
    class Taken:
        @hookimpl
        def regopack_shapes(self):
            return [ShapeSpec("square", ShapeConfig, lambda c: None, aliases=("octagon",))]

    with pytest.raises(PluginError, match=r"^shape kind 'octagon' is an old name of 'square' \("):
        fake_registry(Taken())


def test_aliases_must_be_a_tuple_of_names():
    class Listed:
        @hookimpl
        def regopack_shapes(self):
            return [ShapeSpec("square", ShapeConfig, lambda c: None, aliases=["box"])]

    with pytest.raises(PluginError, match=r"the aliases of ShapeSpec 'square' must be a tuple"):
        fake_registry(Listed())


def test_the_builtin_3d_names_are_old_names_of_the_analyzers():
    reg = default_registry(autoload=False)
    assert reg.aliases("analysis") == {
        f"{name}3d": name
        for name in ("contacts", "coordination", "density", "homogeneity", "network", "psd", "rdf")
    }
    assert "local_fraction" in reg.names("analysis")
    assert reg.get("analysis", "local_fraction").dimensions == (2,)
