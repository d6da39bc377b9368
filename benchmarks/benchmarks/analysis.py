"""Analyses (``regopack.analyze``) of the packings shared by the suite, 2D and 3D.

Each benchmark analyses a packing file written once per commit by
:func:`common.shared_packings` (``table1`` and ``dem`` at 800 µm; the 3D
cubes of 60 µm). An analyzer runs with those it requires (``coordination``
with ``contacts``), as ``regopack analyze --only`` runs it; the ``All``
benchmarks run the default set of the packing's dimension. The tracked counts say which packing
was measured, so that a change of the packing shows beside a change of time.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import regopack

from . import common


class _Shared:
    setup_cache = staticmethod(common.shared_packings)
    timeout = 600.0
    rounds = common.QUICK["rounds"]
    repeat = common.QUICK["repeat"]
    warmup_time = common.QUICK["warmup_time"]


def _warm(packing: Any, names: Any, **params: Any) -> None:
    """Run the analyzers once per process on a small packing: load their kernels and imports."""
    key = ("analyze", id(packing), repr(names), repr(sorted(params.items())))
    common.once(key, lambda: regopack.analyze(packing, names, **params))


def _load(path: str) -> Any:
    """A shared packing, read once per process."""
    return common.once(("load", path), lambda: regopack.load(path))


class Analyze2D(_Shared):
    """Each 2D analyzer on ``table1`` (the paper's order), 800 µm, 15 261 particles."""

    params = ["density", "contacts", "coordination", "rdf", "homogeneity", "psd"]
    param_names = ["analyzer"]

    def setup(self, cache: dict[str, Any], analyzer: str) -> None:
        self.packing = _load(cache["reference"]["path"])
        _warm(common.tiny_2d("reference"), analyzer)

    def time_analyze(self, cache: dict[str, Any], analyzer: str) -> None:
        regopack.analyze(self.packing, analyzer)


class AnalyzeAll2D(_Shared):
    """The default 2D analyses, as ``regopack analyze`` runs them, on ``table1`` and ``dem``."""

    params = [list(common.MODES_2D)]
    param_names = ["mode"]

    def setup(self, cache: dict[str, Any], mode: str) -> None:
        self.packing = _load(cache[mode]["path"])
        _warm(common.tiny_2d(mode), None)

    def time_analyze(self, cache: dict[str, Any], mode: str) -> None:
        regopack.analyze(self.packing)


class Coordination2D(_Shared):
    """Z(tol): one tolerance against the default sweep of 20 (``table1``, 800 µm).

    Contacts and coordination together, as a user runs them: with one
    tolerance the contacts are sought up to it only.
    """

    params = ["one tolerance", "default sweep"]
    param_names = ["tolerances"]

    def setup(self, cache: dict[str, Any], tolerances: str) -> None:
        self.packing = _load(cache["reference"]["path"])
        one = {"contacts__tol": 0.05, "contacts__tol_max": 0.05, "coordination__tols": [0.05]}
        self.kwargs = one if tolerances == "one tolerance" else {}
        _warm(common.tiny_2d("reference"), "coordination", **self.kwargs)

    def time_coordination(self, cache: dict[str, Any], tolerances: str) -> None:
        regopack.analyze(self.packing, "coordination", **self.kwargs)


class WriteAnalysis2D(_Shared):
    """The files of ``regopack analyze``: tables and report, then with the figures.

    The default analyses of ``table1`` at 800 µm, written into a new folder.
    """

    params = [False, True]
    param_names = ["figures"]

    def setup(self, cache: dict[str, Any], figures: bool) -> None:
        self.packing = _load(cache["reference"]["path"])
        self.tmp = tempfile.TemporaryDirectory()
        self.runs = 0
        tiny = common.tiny_2d("reference")
        common.once(("write", figures), lambda: self.write(tiny, figures))

    def write(self, packing: Any, figures: bool) -> None:
        self.runs += 1
        regopack.analyze(packing, out=Path(self.tmp.name) / f"run{self.runs}", figures=figures)

    def teardown(self, cache: dict[str, Any], figures: bool) -> None:
        self.tmp.cleanup()

    def time_write(self, cache: dict[str, Any], figures: bool) -> None:
        self.write(self.packing, figures)


class Analyze3D(_Shared):
    """Each 3D analyzer on the polyhedra of the 60 µm cube (about 1 700 particles)."""

    params = ["density3d", "contacts3d", "coordination3d", "rdf3d"]
    param_names = ["analyzer"]

    def setup(self, cache: dict[str, Any], analyzer: str) -> None:
        self.packing = _load(cache["polyhedra"]["path"])
        _warm(common.tiny_3d("polyhedra"), analyzer)

    def time_analyze(self, cache: dict[str, Any], analyzer: str) -> None:
        regopack.analyze(self.packing, analyzer)


class AnalyzeAll3D(_Shared):
    """The default 3D analyses on the polyhedra and the spheres of the 60 µm cubes."""

    params = [list(common.SHAPES_3D)]
    param_names = ["shape"]

    def setup(self, cache: dict[str, Any], shape: str) -> None:
        self.packing = _load(cache[shape]["path"])
        _warm(common.tiny_3d(shape), None)

    def time_analyze(self, cache: dict[str, Any], shape: str) -> None:
        regopack.analyze(self.packing)


class FabricBlock(_Shared):
    """The run summary's fabric block (contacts, Z, rattlers, anisotropy and its error).

    On every shared packing: ``table1`` and ``dem`` at 800 µm, the 60 µm cubes.
    """

    params = [list(common.SHARED_SIDES)]
    param_names = ["packing"]

    def setup(self, cache: dict[str, Any], key: str) -> None:
        from regopack.registry.manager import default_registry

        self.packing = _load(cache[key]["path"])
        self.registry = default_registry()
        tiny = common.tiny_2d(key) if key in common.MODES_2D else common.tiny_3d(key)
        _warm(tiny, ["coordination", "network"])

    def time_fabric(self, cache: dict[str, Any], key: str) -> None:
        from regopack.run.fabric import fabric_summary

        fabric_summary(self.packing, self.registry)


class Outcome(_Shared):
    """What the shared packings hold: placed particles and candidate analyses.

    Not timings: a change here means the packing itself changed (the scenes
    and seeds are fixed), which explains a change in the other benchmarks.
    """

    params = [list(common.SHARED_SIDES)]
    param_names = ["packing"]
    unit = "count"

    def track_placed(self, cache: dict[str, Any], key: str) -> int:
        return int(cache[key]["summary"]["placed"])

    def track_candidate_analyses(self, cache: dict[str, Any], key: str) -> int:
        return int(cache[key]["summary"].get("candidate_analyses") or 0)
