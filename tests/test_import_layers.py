"""Imports flow one way: from the command line down to the base, and from plugins into the core.

The core's modules sit in layers (:data:`LAYERS`); a module imports only its
own layer and those below, whether at import time or inside a function, and
no two modules import each other through any chain. Plugins import the core
up to the packing and verification layer, never the run, analysis, export
or API modules. The
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
            # 0 base: errors, files, units, limits, kernels' cache and threads
            "_version _compat _exports base",
            # 1 geometry: domains, particle batches, volumes
            "geometry",
            # 2 the plugin contract: interfaces, specs, hooks, the registry
            "registry",
            # 3 scenes and the analyses they plan
            "scenes",
            # 4 packings (their files, pictures and measures) and their verification
            "packing verification",
            # 5 writing analyses and exports
            "analysis exports",
            # 6 the run pipeline
            "run",
            # 7 the Python API, experiments, tiled packings, helpers for plugin authors
            "api experiments testing tiling",
            # 8 the command line
            "cli __main__",
        ]
    )
    for name in [f"regopack.{n}" for n in names.split()]
}
"""Layer of each sub-package (and of the modules directly under the root)."""
LAYERS["regopack"] = 9  # the package root re-exports the API
PLUGIN_LAYER = 4.5
"""Plugins sit between packings (which they import) and the analysis pipeline (which they don't)."""

KNOWN: set[tuple[str, str]] = {
    # the packing draws itself (plot, notebook display): drawing joins the packing's layer
    ("regopack.packing.core", "regopack.packing.drawing"),
}
"""Imports that break the layering or close a cycle, still to be removed."""


def _graph() -> tuple[list[str], list[Edge]]:
    modules, edges = build_graph()
    return sorted(modules), [e for e in edges if e.kind != "typing"]


def _layer(name: str) -> float | None:
    """Layer of a module: its sub-package's; a plugin's is :data:`PLUGIN_LAYER`, both ways."""
    if name.startswith("regopack.plugins"):
        return PLUGIN_LAYER
    if name == "regopack":
        return LAYERS[name]
    return LAYERS.get(".".join(name.split(".")[:2]))


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
    assert [m for m in core if _layer(m) is None] == []


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
        Edge("regopack.packing.core", "regopack.api.functions", "local", 1),
        Edge("regopack.plugins.x", "regopack.run.pipeline", "local", 1),
        Edge("regopack.plugins.x", "regopack.geometry.domain", "module", 1),
        Edge("regopack.cli.commands", "regopack.api.functions", "module", 1),
    ]
    assert [(e.src, e.dst) for e in _upward(edges)] == [
        ("regopack.packing.core", "regopack.api.functions"),
        ("regopack.plugins.x", "regopack.run.pipeline"),
    ]


def test_every_kind_of_import_is_an_edge() -> None:
    _, edges = build_graph()
    found = {(e.src, e.dst, e.kind) for e in edges}
    # module level, inside a function, under TYPE_CHECKING, and relative
    assert ("regopack.run.pipeline", "regopack.packing.core", "module") in found
    assert ("regopack.packing.drawing", "regopack.scenes.analysis_plan", "local") in found
    assert ("regopack.registry.interfaces", "regopack.packing.core", "typing") in found
    assert any(e.src.startswith("regopack.plugins.") and e.kind == "module" for e in edges)


def test_a_core_module_below_the_plugins_importing_a_plugin_is_upward() -> None:
    """Plugins sit at PLUGIN_LAYER: the core below it must not import them."""
    edges = [
        Edge("regopack.base.threads", "regopack.plugins.analyzers.density", "local", 1),
        Edge("regopack.packing.core", "regopack.plugins.inserters.rsa", "module", 1),
        Edge("regopack.analysis.pipeline", "regopack.plugins.common.walls", "local", 1),
        Edge("regopack.cli.commands", "regopack.plugins.inserters.rsa", "local", 1),
        Edge("regopack.plugins.x", "regopack.plugins.y", "module", 1),
    ]
    assert [(e.src, e.dst) for e in _upward(edges)] == [
        ("regopack.base.threads", "regopack.plugins.analyzers.density"),
        ("regopack.packing.core", "regopack.plugins.inserters.rsa"),
    ]
