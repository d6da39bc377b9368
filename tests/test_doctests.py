"""The examples in the docstrings run."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = [
    "regopack._toml",
    "regopack.analysis",
    "regopack.api",
    "regopack.colours",
    "regopack.compilation",
    "regopack.drawing",
    "regopack.experiment_plots",
    "regopack.exporting",
    "regopack.results",
    "regopack.manager",
    "regopack.messages",
    "regopack.outdir",
    "regopack.packing",
    "regopack.scene_model",
    "regopack.testing",
    "regopack.verification",
    "regopack.verification3d",
    "regopack.plugins.change5",
    "regopack.plugins.octagon",
    "regopack.plugins.eta",
    "regopack.plugins.rsa",
    "regopack.plugins.analysis.figures",
    "regopack.plugins.analysis.rdf_peak",
    "regopack.plugins.analysis.segment",
    "regopack.plugins.analysis.figure_specs",
    "regopack.plugins.csv_export",
    "regopack.plugins.rounded_bodies",
    "regopack.plugins.polyhedra.directions",
    "regopack.plugins.polyhedra.generator",
    "regopack.plugins.polyhedra.rotations",
    "regopack.plugins.available_surface.polyhedron",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
