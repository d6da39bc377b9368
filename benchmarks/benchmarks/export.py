"""Exports (``regopack.export``) of the shared packings to every built-in format.

2D: ``table1`` at 800 µm (15 261 particles); 3D: the polyhedra of the 60 µm
cube. Each call writes into a new file of a temporary folder.
"""

from __future__ import annotations

import importlib.util
import tempfile
from pathlib import Path
from typing import Any

import regopack

from . import common

NEEDS = {"gsd": "gsd"}
"""Exporters that need an optional package (``pip install gsd``); skipped without it."""


class _Export:
    setup_cache = staticmethod(common.shared_packings)
    timeout = 600.0
    rounds = common.QUICK["rounds"]
    repeat = common.QUICK["repeat"]
    warmup_time = common.QUICK["warmup_time"]
    key = "reference"
    tiny: Any = None

    def setup(self, cache: dict[str, Any], exporter: str) -> None:
        needed = NEEDS.get(exporter)
        if needed and importlib.util.find_spec(needed) is None:
            raise NotImplementedError(f"{exporter} needs the package {needed}")
        path = cache[self.key]["path"]
        self.packing = common.once(("load", path), lambda: regopack.load(path))
        self.tmp = tempfile.TemporaryDirectory()
        self.folder = Path(self.tmp.name)
        self.runs = 0
        tiny = self.tiny_packing()
        common.once(
            ("export", exporter), lambda: regopack.export(tiny, exporter, self.new_folder())
        )

    def teardown(self, cache: dict[str, Any], exporter: str) -> None:
        self.tmp.cleanup()

    def tiny_packing(self) -> Any:
        raise NotImplementedError

    def new_folder(self) -> Path:
        self.runs += 1
        folder = self.folder / f"run{self.runs}"
        folder.mkdir()
        return folder

    def time_export(self, cache: dict[str, Any], exporter: str) -> None:
        regopack.export(self.packing, exporter, self.new_folder())


class Export2D(_Export):
    """2D exporters on ``table1`` (800 µm)."""

    params = ["csv", "json", "svg", "vtk", "lammps", "gsd", "image"]
    param_names = ["exporter"]

    def tiny_packing(self) -> Any:
        return common.tiny_2d("reference")


class Export3D(_Export):
    """3D exporters on the polyhedra of the 60 µm cube."""

    params = ["vtk", "stl", "lammps", "gsd", "slice", "yade"]
    param_names = ["exporter"]
    key = "polyhedra"

    def tiny_packing(self) -> Any:
        return common.tiny_3d("polyhedra")
