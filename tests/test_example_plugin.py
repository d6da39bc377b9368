"""The example third-party plugin package in ``docs/examples/regopack-example-plugin``.

Two ways in:

- in-process (fast): the module is imported from the source folder and
  registered with :func:`regopack.testing.make_registry`;
- installed: ``pip install`` puts the package into a fresh virtual environment
  that sees the running interpreter's packages (regopack and its
  dependencies), and ``python -m regopack`` there finds the plugins through
  the ``regopack`` entry-point group. Creating the environment and installing
  take a few seconds.
"""

from __future__ import annotations

import csv
import importlib
import importlib.metadata
import importlib.util
import json
import math
import os
import shutil
import site
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from regopack.packing.core import load
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import (
    assert_valid_packing,
    check_shape_generator,
    make_registry,
    packing_from_polygons,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "docs" / "examples" / "regopack-example-plugin"
MODULE = "regopack_example_plugin"
DIST = "regopack-example-plugin"
TIMEOUT = 600


@pytest.fixture(scope="module")
def plugin() -> Iterator[ModuleType]:
    """The example module, imported from its source folder."""
    sys.path.insert(0, str(EXAMPLE))
    sys.modules.pop(MODULE, None)
    try:
        yield importlib.import_module(MODULE)
    finally:
        sys.modules.pop(MODULE, None)
        sys.path.remove(str(EXAMPLE))


# ---------------------------------------------------------------------------
# the package's files


def test_pyproject_declares_the_entry_point():
    meta = tomllib.loads((EXAMPLE / "pyproject.toml").read_text("utf-8"))
    project = meta["project"]
    assert project["name"] == DIST
    assert project["version"] == "0.1.0"
    assert project["dependencies"] == ["regopack"]
    assert project["entry-points"]["regopack"] == {"example": MODULE}
    assert meta["build-system"]["build-backend"] == "setuptools.build_meta"


def test_every_parameter_is_described_and_in_the_readme(plugin):
    readme = (EXAMPLE / "README.md").read_text("utf-8")
    for model in (plugin.EllipseConfig, plugin.AspectConfig):
        assert model.model_config.get("extra") == "forbid"
        for name, field in model.model_fields.items():
            assert field.description, f"{model.__name__}.{name} has no description"
            assert f"`{name}`" in readme, f"{model.__name__}.{name} is not in the README"


# ---------------------------------------------------------------------------
# in-process: registered with make_registry


def test_in_process_registry_has_both_plugins(plugin):
    registry = make_registry(plugin)
    assert "ellipse-polygon" in registry.names("shape")
    assert "aspect" in registry.names("analysis")
    info = registry.info("shape", "ellipse-polygon")
    assert info.module == MODULE
    assert registry.info("shape", "octagon").distribution == "regopack"


@pytest.mark.parametrize(
    "params", [{}, {"aspect": 1.0}, {"aspect": 1.5, "aspect_max": 4.0}, {"m": 4}, {"m": 101}]
)
def test_ellipse_polygon_keeps_the_shape_contract(plugin, params):
    check_shape_generator(plugin.EllipsePolygon(plugin.EllipseConfig(**params)))


def test_ellipse_polygon_has_the_asked_aspect_ratio(plugin):
    gen = plugin.EllipsePolygon(plugin.EllipseConfig(aspect=2.5, m=24))
    batch = gen.generate(np.array([1.0, 3.0, 7.0]), np.random.default_rng(5))
    area, aspect, angle = plugin.second_moment_aspect(batch.vertices, batch.offsets)
    np.testing.assert_allclose(area, math.pi * np.array([1.0, 9.0, 49.0]))
    np.testing.assert_allclose(aspect, 2.5)
    # the major axis is the orientation drawn, modulo pi
    turn = np.mod(angle - batch.orientation, np.pi)
    np.testing.assert_allclose(np.minimum(turn, np.pi - turn), 0.0, atol=1e-9)


def test_ellipse_config_rejects_a_reversed_range(plugin):
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match="aspect_max"):
        plugin.EllipseConfig(aspect=3.0, aspect_max=2.0)


def test_aspect_analyzer_on_known_particles(plugin):
    rect = [(0, 0), (3, 0), (3, 1), (0, 1)]  # second moments 9/12 and 1/12: aspect 3
    square = [(5, 0), (7, 0), (7, 2), (5, 2)]
    packing = packing_from_polygons([rect, square], placed=[True, True])
    analyzer = plugin.AspectRatio(plugin.AspectConfig(bins=4, upper=5.0))
    with pytest.raises(RuntimeError, match="compute"):
        analyzer.results()
    assert analyzer.compute(packing, {}) is analyzer
    np.testing.assert_allclose(analyzer.aspect, [3.0, 1.0])
    results = analyzer.results()
    assert results["n"] == 2
    assert results["mean"] == pytest.approx(2.0)
    assert results["mean_test"] == pytest.approx(2.0)
    tables = analyzer.tables()
    assert tables["aspect"]["particle"].tolist() == [0, 1]
    assert tables["aspect_histogram"]["count"].tolist() == [1, 0, 1, 0]
    assert tables["aspect_histogram"]["lower"][0] == 1.0
    json.dumps(results)


def check_outcome(summary: dict[str, Any], packing: Any, out_dir: Path | None) -> None:
    """What a run of example.toml must give, in or out of process."""
    assert summary["placed"] > 100
    assert_valid_packing(packing)
    aspect = summary["analyses"]["aspect"]
    assert set(summary["analyses"]) == {"aspect", "density"}
    assert aspect["n"] == summary["placed"]
    assert 1.0 <= aspect["min"] <= aspect["mean"] <= aspect["max"]
    # elongated grains (aspect 1.5 to 3) against round-ish octagons
    assert 1.5 - 1e-9 <= aspect["mean_plagioclase"] <= 3.0 + 1e-9
    assert aspect["mean_glass"] < aspect["mean_plagioclase"]
    counts = np.diff(packing.offsets)
    assert np.all(counts[packing.mineral == 0] == 16)
    if out_dir is not None:
        with (out_dir / "analysis" / "aspect.csv").open() as fh:
            rows = list(csv.DictReader(fh))
        assert len(rows) == summary["placed"]
        with (out_dir / "analysis" / "aspect_histogram.csv").open() as fh:
            assert len(list(csv.DictReader(fh))) == 10


def test_in_process_run_of_the_example_scene(plugin, tmp_path):
    registry = make_registry(plugin)
    scene = resolve_scene(load_scene(EXAMPLE / "example.toml"), registry)
    outcome = run_scene(scene, tmp_path / "out", figures=False)
    check_outcome(outcome.summary, outcome.packing, tmp_path / "out")


# ---------------------------------------------------------------------------
# installed with pip into a virtual environment


def _parent_site_dirs() -> list[str]:
    dirs = list(site.getsitepackages())
    if site.ENABLE_USER_SITE:
        dirs.append(site.getusersitepackages())
    return [d for d in dirs if Path(d).is_dir()]


def _builds_without_isolation() -> bool:
    """Whether setuptools can build a wheel with what is installed (no download)."""
    try:
        version = importlib.metadata.version("setuptools")
    except importlib.metadata.PackageNotFoundError:
        return False
    major, minor = (int(p) for p in (version.split(".") + ["0"])[:2])
    return (major, minor) >= (70, 1) or importlib.util.find_spec("wheel") is not None


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "REGOPACK_DISABLE_PLUGIN_AUTOLOAD"}
    env["COLUMNS"] = "200"
    env.update(extra)
    return env


@pytest.fixture(scope="module")
def venv_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Python of a virtual environment with the example package installed by pip.

    The environment is made with ``--system-site-packages`` and a ``.pth`` file
    that adds the running interpreter's site directories, so regopack and its
    dependencies (and pip and setuptools) are visible without installing them
    again; the example package is installed into the environment itself, where
    only its python sees its entry point.
    """
    if importlib.util.find_spec("pip") is None:
        pytest.skip("pip is not installed")
    root = tmp_path_factory.mktemp("example-plugin")
    src = root / "src"
    shutil.copytree(
        EXAMPLE, src, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__")
    )
    venv = root / "venv"
    subprocess.run(
        [sys.executable, "-m", "venv", "--without-pip", "--system-site-packages", str(venv)],
        check=True,
        timeout=TIMEOUT,
    )
    python = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
        timeout=TIMEOUT,
    ).stdout.strip()
    lines = [f"import site; site.addsitedir({d!r})" for d in _parent_site_dirs()]
    (Path(purelib) / "_regopack_parent_env.pth").write_text("\n".join(lines) + "\n")
    # build with the setuptools at hand when it can make wheels by itself; older ones
    # need the wheel package, and pip then fetches a build environment from the index
    isolation = ["--no-build-isolation"] if _builds_without_isolation() else []
    result = subprocess.run(
        [
            str(python),
            "-m",
            "pip",
            "install",
            "--no-deps",
            "--disable-pip-version-check",
            "--quiet",
            *isolation,
            str(src),
        ],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        check=False,
        env=_env(),
    )
    assert result.returncode == 0, f"pip install failed:\n{result.stdout}\n{result.stderr}"
    return python


def regopack(
    python: Path, *args: str, cwd: Path | None = None, **env: str
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(python), "-m", "regopack", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=TIMEOUT,
        check=False,
        env=_env(**env),
    )


def test_plugins_lists_the_example_with_its_origin(venv_python):
    result = regopack(venv_python, "plugins")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "ellipse-polygon" in out and "aspect" in out
    assert f"{MODULE}" in out
    assert f"{DIST} 0.1.0" in out
    assert "aspect_max" in out and "Number of bins of the aspect-ratio histogram." in out

    result = regopack(venv_python, "plugins", "--json")
    assert result.returncode == 0, result.stderr
    entries = {(e["kind"], e["name"]): e for e in json.loads(result.stdout)["plugins"]}
    for key in (("shape", "ellipse-polygon"), ("analysis", "aspect")):
        entry = entries[key]
        assert (entry["module"], entry["distribution"], entry["version"]) == (
            MODULE,
            DIST,
            "0.1.0",
        )
        assert entry["plugin"] == "example"  # the entry point's name
        assert all(f["description"] for f in entry["fields"])
    assert entries["shape", "octagon"]["distribution"] == "regopack"


def test_run_uses_both_plugins(venv_python, tmp_path):
    shutil.copy(EXAMPLE / "example.toml", tmp_path / "example.toml")
    result = regopack(venv_python, "run", "example.toml", "--out", "out", "--quiet", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out"
    summary = json.loads((out / "summary.json").read_text())
    check_outcome(summary, load(out / "packing.npz"), out)
    assert (out / "analysis" / "report.md").is_file()


def test_schema_includes_the_example(venv_python):
    result = regopack(venv_python, "schema")
    assert result.returncode == 0, result.stderr
    schema = json.loads(result.stdout)
    branch = schema["$defs"]["shape.ellipse-polygon"]
    assert set(branch["properties"]) == {"kind", "aspect", "aspect_max", "m"}
    assert f"{DIST} 0.1.0" in branch["description"]
    assert "analysis.aspect" in schema["$defs"]


def test_disabling_autoload_makes_the_example_kind_unknown(venv_python, tmp_path):
    shutil.copy(EXAMPLE / "example.toml", tmp_path / "example.toml")
    result = regopack(
        venv_python,
        "run",
        "example.toml",
        "--out",
        "out",
        cwd=tmp_path,
        REGOPACK_DISABLE_PLUGIN_AUTOLOAD="1",
    )
    assert result.returncode == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(
        "regopack: error: example.toml: phases.0.shape.kind: "
        "unknown shape kind 'ellipse-polygon'; known kinds: "
    )
    assert not (tmp_path / "out").exists()

    result = regopack(venv_python, "plugins", "--json", REGOPACK_DISABLE_PLUGIN_AUTOLOAD="1")
    names = {e["name"] for e in json.loads(result.stdout)["plugins"]}
    assert "ellipse-polygon" not in names and "aspect" not in names


def test_docstring_examples(plugin):
    import doctest

    result = doctest.testmod(plugin, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
