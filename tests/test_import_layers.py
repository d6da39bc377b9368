"""Imports flow one way: from the command line down to the base, and from plugins into the core.

The core's modules sit in layers (:data:`LAYERS`); a module imports only its
own layer and those below, whether at import time or inside a function, and
no two modules import each other through any chain. Plugins import the core
up to the drawing layer, never the run, analysis, export or API modules. The
exceptions still to be removed are listed in :data:`KNOWN`; the list may only
shrink (an entry that no longer occurs fails too).
"""

from __future__ import annotations

import pytest
from import_graph import Edge, build_graph, cycles

LAYERS: dict[str, int] = {
    name: layer
    for layer, names in enumerate(
        [
            # 0 base: errors, files, units, limits, kernels' compilation and threads
            "_version _compat errors _toml messages units limits colours threads jit outdir "
            "sphere_volume compilation",
            # 1 the plugin contract: geometry records, interfaces, specs, hooks, registry
            "domain population solids interfaces plugin_types hookspecs manager",
            # 2 scenes
            "scene_model schema scenes",
            # 3 packings, their checks and measures; planning analyses
            "packing packing3d sieve voids verification verification3d solid_fraction "
            "analysis_plan",
            # 4 pictures of a packing
            "drawing drawing3d",
            # 5 writing analyses and exports
            "analysis analysis3d exporting results",
            # 6 the run pipeline
            "run run3d",
            # 7 the Python API, experiments, helpers for plugin authors
            "api warmup progress experiment experiment_api experiment_file experiment_grid "
            "experiment_plots experiment_results experiment_run experiment_workers experiments "
            "testing",
            # 8 the command line
            "cli cli_args sweep_cli __main__",
        ]
    )
    for name in [f"regopack.{n}" for n in names.split()]
}
LAYERS["regopack"] = 9  # the package root re-exports the API
PLUGIN_LAYER = 4
"""Plugins import core modules up to this layer."""

KNOWN: set[tuple[str, str]] = {
    # the packing draws itself (plot, notebook display): drawing joins the packing's layer
    ("regopack.packing", "regopack.drawing"),
    # the 3D run borrows the 2D run's steps: one run pipeline for both dimensions ends these
    ("regopack.analysis3d", "regopack.run"),
    ("regopack.run", "regopack.run3d"),
    ("regopack.run3d", "regopack.run"),
    # the figure modules share their style helpers through figures.py
    ("regopack.plugins.analysis.figure_specs", "regopack.plugins.analysis.figures"),
    ("regopack.plugins.analysis.figure_specs", "regopack.plugins.analysis.figures3d"),
    ("regopack.plugins.analysis.figures", "regopack.plugins.analysis.homogeneity_figure"),
    ("regopack.plugins.analysis.figures", "regopack.plugins.analysis.local_fraction_figure"),
    ("regopack.plugins.analysis.figures", "regopack.plugins.analysis.psd_figure"),
    ("regopack.plugins.analysis.figures3d", "regopack.plugins.analysis.psd_figure"),
}
"""Imports that break the layering or close a cycle, still to be removed."""


def _graph() -> tuple[list[str], list[Edge]]:
    modules, edges = build_graph()
    return sorted(modules), [e for e in edges if e.kind != "typing"]


def _layer(name: str) -> int | None:
    """Layer of a module: a plugin's is :data:`PLUGIN_LAYER`, as importer and as imported."""
    if name.startswith("regopack.plugins"):
        return PLUGIN_LAYER
    return LAYERS.get(name)


def _upward(edges: list[Edge]) -> list[Edge]:
    out = []
    for e in edges:
        src, dst = _layer(e.src), _layer(e.dst)
        if src is not None and dst is not None and dst > src:
            out.append(e)
    return out


def test_every_core_module_has_a_layer() -> None:
    modules, _ = _graph()
    core = [m for m in modules if not m.startswith("regopack.plugins")]
    assert [m for m in core if m not in LAYERS] == []


def test_no_module_imports_a_higher_layer() -> None:
    _, edges = _graph()
    bad = [str(e) for e in _upward(edges) if (e.src, e.dst) not in KNOWN]
    assert bad == []


def test_no_import_cycle() -> None:
    _, edges = _graph()
    kept = [e for e in edges if (e.src, e.dst) not in KNOWN]
    assert [sorted(c) for c in cycles(kept)] == []


def test_the_known_exceptions_still_occur() -> None:
    """An exception that was removed leaves the list, so that it cannot come back."""
    _, edges = _graph()
    pairs = {(e.src, e.dst) for e in edges}
    assert sorted(KNOWN - pairs) == []


@pytest.mark.parametrize(
    ("edges", "expected"),
    [
        ([Edge("a", "b", "module", 1), Edge("b", "a", "local", 2)], [{"a", "b"}]),
        ([Edge("a", "b", "module", 1), Edge("b", "c", "module", 2)], []),
        (
            [Edge("a", "b", "local", 1), Edge("b", "c", "local", 2), Edge("c", "a", "local", 3)],
            [{"a", "b", "c"}],
        ),
    ],
)
def test_cycles_are_found(edges: list[Edge], expected: list[set[str]]) -> None:
    assert cycles(edges) == expected


def test_an_upward_import_is_found() -> None:
    edges = [
        Edge("regopack.packing", "regopack.api", "local", 1),
        Edge("regopack.plugins.x", "regopack.run", "local", 1),
        Edge("regopack.plugins.x", "regopack.domain", "module", 1),
        Edge("regopack.cli", "regopack.api", "module", 1),
    ]
    assert [(e.src, e.dst) for e in _upward(edges)] == [
        ("regopack.packing", "regopack.api"),
        ("regopack.plugins.x", "regopack.run"),
    ]


def test_every_kind_of_import_is_an_edge() -> None:
    _, edges = build_graph()
    found = {(e.src, e.dst, e.kind) for e in edges}
    # module level, inside a function, under TYPE_CHECKING, and relative
    assert ("regopack.run", "regopack.packing", "module") in found
    assert ("regopack.drawing", "regopack.analysis_plan", "local") in found
    assert ("regopack.interfaces", "regopack.packing", "typing") in found
    assert any(e.src.startswith("regopack.plugins.") and e.kind == "module" for e in edges)


def test_a_core_module_below_the_plugins_importing_a_plugin_is_upward() -> None:
    """Plugins sit at PLUGIN_LAYER: the core below it must not import them."""
    edges = [
        Edge("regopack.threads", "regopack.plugins.analysis.density", "local", 1),
        Edge("regopack.packing", "regopack.plugins.rsa", "module", 1),
        Edge("regopack.drawing", "regopack.plugins.walls", "local", 1),
        Edge("regopack.cli", "regopack.plugins.rsa", "local", 1),
        Edge("regopack.plugins.x", "regopack.plugins.y", "module", 1),
    ]
    assert [(e.src, e.dst) for e in _upward(edges)] == [
        ("regopack.threads", "regopack.plugins.analysis.density"),
        ("regopack.packing", "regopack.plugins.rsa"),
    ]
