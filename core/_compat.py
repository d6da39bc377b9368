"""Old names kept for one release as deprecated aliases of what replaced them.

A module that moved stays importable under its old name: :data:`MOVED_MODULES`
maps the old name to the new one, and the finder that :func:`install` puts at
the front of :data:`sys.meta_path` hands out the new module object itself, so
that an attribute set through the old name (a monkeypatch, say) reaches the
real module. Importing the old name warns once, with a
:class:`DeprecationWarning` naming the new place; a submodule of a moved
package moves with it. :func:`warn_moved` says the same of a single name.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType
from typing import Any

__all__ = ["MOVED_MODULES", "AliasFinder", "install", "warn_moved"]

MOVED_MODULES: dict[str, str] = {
    "regopack.domain3d": "regopack.geometry.domain",
    "regopack._toml": "regopack.base.toml",
    "regopack.errors": "regopack.base.errors",
    "regopack.messages": "regopack.base.messages",
    "regopack.units": "regopack.base.units",
    "regopack.limits": "regopack.base.limits",
    "regopack.colours": "regopack.base.colours",
    "regopack.threads": "regopack.base.threads",
    "regopack.jit": "regopack.base.jit",
    "regopack.outdir": "regopack.base.outdir",
    "regopack.domain": "regopack.geometry.domain",
    "regopack.population": "regopack.geometry.population",
    "regopack.solids": "regopack.geometry.solids",
    "regopack.sphere_volume": "regopack.geometry.sphere_volume",
    "regopack.interfaces": "regopack.registry.interfaces",
    "regopack.plugin_types": "regopack.registry.plugin_types",
    "regopack.hookspecs": "regopack.registry.hookspecs",
    "regopack.manager": "regopack.registry.manager",
    "regopack.analysis_plan": "regopack.scenes.analysis_plan",
    "regopack.scene_model": "regopack.scenes.model",
    "regopack.schema": "regopack.scenes.schema",
    "regopack.packing3d": "regopack.packing.core",
    "regopack.packing.core3d": "regopack.packing.core",
    "regopack.drawing": "regopack.packing.drawing",
    "regopack.drawing3d": "regopack.packing.drawing",
    "regopack.packing.drawing3d": "regopack.packing.drawing",
    "regopack.solid_fraction": "regopack.packing.solid_fraction",
    "regopack.voids": "regopack.packing.voids",
    "regopack.sieve": "regopack.packing.sieve",
    "regopack.verification3d": "regopack.verification.polyhedra",
    "regopack.analysis3d": "regopack.analysis.pipeline",
    "regopack.results": "regopack.analysis.results",
    "regopack.exporting": "regopack.exports.pipeline",
    "regopack.run3d": "regopack.run.pipeline",
    "regopack.compilation": "regopack.run.compilation",
    "regopack.progress": "regopack.run.progress",
    "regopack.warmup": "regopack.api.warmup",
    "regopack.experiment": "regopack.experiments",
    "regopack.experiment_api": "regopack.experiments.api",
    "regopack.experiment_file": "regopack.experiments.file",
    "regopack.experiment_grid": "regopack.experiments.grid",
    "regopack.experiment_plots": "regopack.experiments.plots",
    "regopack.experiment_results": "regopack.experiments.results",
    "regopack.experiment_run": "regopack.experiments.run",
    "regopack.experiment_workers": "regopack.experiments.workers",
    "regopack.cli_args": "regopack.cli.args",
    "regopack.sweep_cli": "regopack.cli.sweep",
    "regopack.plugins.octagon": "regopack.plugins.shapes.octagon",
    "regopack.plugins.disk": "regopack.plugins.shapes.disk",
    "regopack.plugins.sphere": "regopack.plugins.shapes.sphere",
    "regopack.plugins.polyhedra": "regopack.plugins.shapes.polyhedra",
    "regopack.plugins.solid_templates": "regopack.plugins.shapes.solid_templates",
    "regopack.plugins.size_distributions": "regopack.plugins.sizes.distributions",
    "regopack.plugins.change5": "regopack.plugins.sizes.change5",
    "regopack.plugins.available_arc": "regopack.plugins.inserters.available_arc",
    "regopack.plugins.available_surface": "regopack.plugins.inserters.available_surface",
    "regopack.plugins.rsa": "regopack.plugins.inserters.rsa",
    "regopack.plugins.halfplane_clip": "regopack.plugins.common.halfplane_clip",
    "regopack.plugins.walls": "regopack.plugins.common.walls",
    "regopack.plugins.strips": "regopack.plugins.common.strips",
    "regopack.plugins.borrowed": "regopack.plugins.common.borrowed",
    "regopack.plugins.atomics": "regopack.plugins.common.atomics",
    "regopack.plugins.eta": "regopack.plugins.density.eta",
    "regopack.plugins.analysis": "regopack.plugins.analyzers",
    "regopack.plugins.exporters3d": "regopack.plugins.exporters",
    "regopack.plugins.export_common": "regopack.plugins.exporters.export_common",
    "regopack.plugins.solid_export_common": "regopack.plugins.exporters.solid_export_common",
    "regopack.plugins.csv_export": "regopack.plugins.exporters.csv_export",
    "regopack.plugins.json_export": "regopack.plugins.exporters.json_export",
    "regopack.plugins.svg_export": "regopack.plugins.exporters.svg_export",
    "regopack.plugins.image_export": "regopack.plugins.exporters.image_export",
    "regopack.plugins.stl_export": "regopack.plugins.exporters.stl_export",
    "regopack.plugins.slice_export": "regopack.plugins.exporters.slice_export",
    "regopack.plugins.vtk_export": "regopack.plugins.exporters.vtk_export",
    "regopack.plugins.vtk3d_export": "regopack.plugins.exporters.vtk_export",
    "regopack.plugins.gsd_export": "regopack.plugins.exporters.gsd_export",
    "regopack.plugins.gsd3d_export": "regopack.plugins.exporters.gsd_export",
    "regopack.plugins.lammps_export": "regopack.plugins.exporters.lammps_export",
    "regopack.plugins.lammps3d_export": "regopack.plugins.exporters.lammps_export",
    "regopack.plugins.rounded_bodies": "regopack.plugins.exporters.rounded_bodies",
    "regopack.plugins.rounded_bodies_kernel": "regopack.plugins.exporters.rounded_bodies_kernel",
    "regopack.plugins.rounded_polyhedra": "regopack.plugins.exporters.rounded_polyhedra",
}
"""New module of each old module name (kept until the release after the move)."""


def warn_moved(old: str, new: str, stacklevel: int = 2) -> None:
    """Warn that ``old`` is deprecated and that ``new`` replaces it.

    ``stacklevel`` is that of :func:`warnings.warn` counted from the caller:
    the default blames the code that called the caller (the import system's
    own frames are skipped).
    """
    warnings.warn(
        f"{old} is deprecated and will be removed in the next release; use {new}",
        DeprecationWarning,
        stacklevel=stacklevel + 1,
    )


class _AliasLoader(importlib.abc.Loader):
    """Loads an old module name as the module object of the new name."""

    def __init__(self, target: str) -> None:
        self.target = target
        self.spec: ModuleSpec | None = None

    def create_module(self, spec: ModuleSpec) -> ModuleType:
        """Import the new module and return it, warning that the old name is deprecated."""
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        warn_moved(spec.name, self.target)
        return module

    def exec_module(self, module: ModuleType) -> None:
        """Run nothing: give the module back the spec that the import system replaced."""
        module.__spec__ = self.spec


class AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of moved modules (and their submodules).

    Parameters
    ----------
    moved
        New module name by old module name.
    """

    def __init__(self, moved: Mapping[str, str]) -> None:
        self.moved = moved

    def target(self, name: str) -> str | None:
        """Return the new name of the module ``name``, or ``None`` if it did not move."""
        for old, new in self.moved.items():
            if name == old or name.startswith(old + "."):
                return new + name[len(old) :]
        return None

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        """Return a spec that loads the new module for an old name, else ``None``."""
        new = self.target(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


FINDER = AliasFinder(MOVED_MODULES)
"""The finder of regopack's moved modules."""


def install() -> None:
    """Put :data:`FINDER` at the front of :data:`sys.meta_path` (once)."""
    if FINDER not in sys.meta_path:
        sys.meta_path.insert(0, FINDER)


def renamed_names(module: str, names: Mapping[str, str]) -> Callable[[str], Any]:
    """Return a module ``__getattr__`` (PEP 562) that gives ``module``'s renamed objects.

    ``names`` maps each old name to the new name of the same object in
    ``module``, or in another module given as ``"package.module:Name"``; an
    old name warns at every use (:func:`warn_moved`).
    """

    def getattr_(name: str) -> Any:
        if name not in names:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        where, _, new = names[name].rpartition(":")
        warn_moved(f"{module}.{name}", f"{where or module}.{new}")
        return getattr(importlib.import_module(where) if where else sys.modules[module], new)

    return getattr_
