"""The asv benchmark suite (benchmarks/benchmarks/) runs: every benchmark, on tiny scenes.

Each benchmark class is loaded as asv loads it, its ``setup_cache`` (if any)
runs once, and every benchmark method runs through its ``setup``, the method
and its ``teardown`` at the first value of each parameter, with the suite's
sizes cut to a few dozen particles (``common``'s module-level sizes, and the
size parameters replaced). So the suite cannot rot unnoticed between two asv
runs: a renamed function of the API, a scene that no longer validates or a
changed exporter fails here. When asv is installed (the ``dev`` extra), the
suite also passes ``asv check``.
"""

from __future__ import annotations

import importlib.util
import inspect
import itertools
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
SUITE = BENCH / "benchmarks"
PACKAGE = "regopack_asv_suite"  # not "benchmarks": no clash with another package of that name

TINY_SIDES = {"side_um": {"2d": 40.0, "3d": 16.0}}
"""Values that replace a size parameter: tiny squares and cubes."""

PREFIXES = ("time_", "peakmem_", "mem_", "track_")


def load_suite() -> dict[str, ModuleType]:
    """Import the suite's package and modules under :data:`PACKAGE`."""
    if PACKAGE not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            PACKAGE, SUITE / "__init__.py", submodule_search_locations=[str(SUITE)]
        )
        assert spec and spec.loader
        package = importlib.util.module_from_spec(spec)
        sys.modules[PACKAGE] = package
        spec.loader.exec_module(package)
    names = sorted(p.stem for p in SUITE.glob("*.py") if p.stem != "__init__")
    return {name: importlib.import_module(f"{PACKAGE}.{name}") for name in names}


def benchmark_classes() -> list[tuple[str, type]]:
    out = []
    for name, module in load_suite().items():
        for cname, cls in vars(module).items():
            if (
                inspect.isclass(cls)
                and not cname.startswith("_")
                and cls.__module__ == module.__name__
            ):
                if any(m.startswith(PREFIXES) for m in dir(cls)):
                    out.append((f"{name}.{cname}", cls))
    return out


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """Cut the suite's sizes to tiny scenes, and the shared packings with them."""
    common = load_suite()["common"]
    patch = pytest.MonkeyPatch()
    patch.setattr(common, "SCENE_SIDE", 50.0)
    patch.setattr(common, "WARM_SIDE_2D", 30.0)
    patch.setattr(common, "WARM_SIDE_3D", 14.0)
    patch.setattr(common, "THREADS_SIDES_3D", {"sweep": 24.0, "paper": 16.0})
    patch.setattr(
        common, "SHARED_SIDES", {"reference": 60.0, "dem": 60.0, "polyhedra": 18.0, "spheres": 18.0}
    )
    caches: dict[Any, Any] = {}
    yield caches, tmp_path_factory.mktemp("asv-cache")
    patch.undo()


def first_params(cls: type, dimension: str) -> tuple[Any, ...]:
    params = getattr(cls, "params", None)
    if params is None:
        return ()
    names = list(getattr(cls, "param_names", []))
    lists = [params] if params and not isinstance(params[0], tuple | list) else params  # as asv
    out = []
    for name, values in itertools.zip_longest(names, lists):
        out.append(TINY_SIDES[name][dimension] if name in TINY_SIDES else values[0])
    return tuple(out)


def test_the_suite_has_every_kind_of_benchmark() -> None:
    names = {n for n, _ in benchmark_classes()}
    for wanted in (
        "packing.Pack2D",
        "packing.Pack3D",
        "packing.Sweep3D",
        "analysis.Analyze2D",
        "analysis.Analyze3D",
        "analysis.AnalyzeAll2D",
        "analysis.AnalyzeAll3D",
        "export.Export2D",
        "export.Export3D",
        "verification.Verify",
    ):
        assert wanted in names
    pack2d = dict(benchmark_classes())["packing.Pack2D"]
    assert hasattr(pack2d, "time_pack") and hasattr(pack2d, "peakmem_pack")


@pytest.mark.parametrize(
    ("name", "cls"), benchmark_classes(), ids=lambda v: v if isinstance(v, str) else ""
)
def test_every_benchmark_runs_on_a_tiny_scene(name: str, cls: type, tiny: Any, monkeypatch) -> None:
    caches, folder = tiny
    dimension = "3d" if "3D" in name else "2d"
    params = first_params(cls, dimension)
    setup_cache = getattr(cls, "setup_cache", None)
    args: tuple[Any, ...] = params
    if setup_cache is not None:
        key = (setup_cache.__module__, setup_cache.__qualname__)
        if key not in caches:
            monkeypatch.chdir(folder)
            caches[key] = setup_cache()
        if caches[key] is not None:  # as asv: a cache of None is not passed
            args = (caches[key], *params)
    for method in sorted(m for m in dir(cls) if m.startswith(PREFIXES)):
        bench = cls()
        if hasattr(bench, "setup"):
            try:
                bench.setup(*args)
            except NotImplementedError as skip:  # asv skips such a benchmark too
                pytest.skip(str(skip))
        try:
            getattr(bench, method)(*args)
        finally:
            if hasattr(bench, "teardown"):
                bench.teardown(*args)


@pytest.mark.skipif(importlib.util.find_spec("asv") is None, reason="asv is in the dev extra")
def test_asv_finds_no_problem_in_the_suite() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "asv", "check", "--python=same"],
        cwd=BENCH,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "No problems found" in done.stdout, done.stdout[-2000:]
