"""The examples in the docstrings run."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = [
    "regopack.base.toml",
    "regopack.analysis.pipeline",
    "regopack.api.functions",
    "regopack.base.colours",
    "regopack.run.compilation",
    "regopack.packing.drawing",
    "regopack.experiments.plots",
    "regopack.exports.pipeline",
    "regopack.analysis.results",
    "regopack.registry.manager",
    "regopack.base.messages",
    "regopack.base.outdir",
    "regopack.packing.core",
    "regopack.scenes.model",
    "regopack.testing",
    "regopack.verification.polygons",
    "regopack.verification.polyhedra",
    "regopack.plugins.sizes.change5",
    "regopack.plugins.shapes.octagon",
    "regopack.plugins.density.eta",
    "regopack.plugins.inserters.rsa",
    "regopack.plugins.analyzers.figures",
    "regopack.plugins.analyzers.rdf_peak",
    "regopack.plugins.analyzers.segment",
    "regopack.plugins.analyzers.figure_specs",
    "regopack.plugins.exporters.csv_export",
    "regopack.plugins.exporters.rounded_bodies",
    "regopack.plugins.shapes.polyhedra.directions",
    "regopack.plugins.shapes.polyhedra.generator",
    "regopack.plugins.shapes.polyhedra.rotations",
    "regopack.plugins.inserters.available_surface.polyhedron",
    "regopack.plugins.common.kernel_random",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
