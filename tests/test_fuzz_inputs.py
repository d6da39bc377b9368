"""Fuzzing: mutated packing files and scene files never crash a command.

Every command given a mutated input either succeeds or ends with one
``regopack: error:`` line and exit status 1 or 2 (1: a violated packing in
``verify``), and writes nothing outside its output folder.
"""

from __future__ import annotations

import contextlib
import importlib.resources
import io
import json
import math
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.base import toml as _toml
from regopack.cli import main
from regopack.packing.core import save
from regopack.testing import packing_from_polygons

SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
ARRAYS = ("radius", "mineral", "vertices", "offsets", "orientation", "centre", "insertion_index")
FUZZ = settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)


def run_cli(argv: list[str]) -> tuple[int, list[str]]:
    """Exit status and standard-error lines of ``regopack ARGV``, run in this process."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        status = main(argv)
    return status, err.getvalue().splitlines()


def assert_clean_outcome(status: int, lines: list[str], allowed: tuple[int, ...]) -> None:
    assert status in allowed, (status, lines)
    if status == 2:
        errors = [line for line in lines if line.startswith("regopack: error: ")]
        assert len(errors) == 1 and len(lines) == 1, lines
    assert not any("Traceback" in line for line in lines), lines


def files_in(folder: Path) -> set[Path]:
    return {p for p in folder.rglob("*")}


# ---------------------------------------------------------------------------
# packing files

BAD_VALUES = st.sampled_from(
    [math.nan, math.inf, -math.inf, -1.0, 0.0, 1e308, -(2**62), 2**62, 10**6, 7]
)


@st.composite
def mutated_arrays(draw: Any) -> tuple[dict[str, np.ndarray], str]:
    arrays, meta = valid_file()
    key = draw(st.sampled_from([*ARRAYS, "meta"]))
    kind = draw(st.sampled_from(["value", "dtype", "shape", "drop", "meta"]))
    if key == "meta" or kind == "meta":
        doc = json.loads(meta)
        field = draw(st.sampled_from(sorted(doc)))
        doc[field] = draw(st.sampled_from([None, -1, "x", [], {}, 1e308, True, {"kind": "circle"}]))
        meta = json.dumps(doc) if draw(st.booleans()) else meta[: draw(st.integers(0, 40))]
    elif kind == "drop":
        del arrays[key]
    elif kind == "dtype":
        arrays[key] = arrays[key].astype(draw(st.sampled_from(["float32", "int32", "U4", "bool"])))
    elif kind == "shape":
        arrays[key] = arrays[key].reshape(-1)[: draw(st.integers(0, 3))]
    else:
        a = arrays[key].copy()
        flat = a.reshape(-1)
        if flat.size:
            value = draw(BAD_VALUES)
            if a.dtype.kind == "i":
                value = int(value) if math.isfinite(value) else -1
            flat[draw(st.integers(0, flat.size - 1))] = value
        arrays[key] = a
    return arrays, meta


def valid_file() -> tuple[dict[str, np.ndarray], str]:
    p = packing_from_polygons([SQUARE, [(x + 2, y) for x, y in SQUARE]], domain=(-1, 4, -1, 2))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.npz"
        save(p, path)
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    meta = str(arrays.pop("meta"))
    return arrays, meta


@FUZZ
@given(mutated_arrays())
def test_mutated_packing_files_are_one_error_or_fine(mutation):
    arrays, meta = mutation
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        path = root / "p.npz"
        np.savez(path, meta=np.array(meta), **arrays)
        before = files_in(root)
        assert_clean_outcome(*run_cli(["verify", str(path)]), allowed=(0, 1, 2))
        out = root / "analysis"
        status, lines = run_cli(["analyze", str(path), "--only", "density", "--out", str(out)])
        assert_clean_outcome(status, lines, allowed=(0, 2))
        export = root / "export.csv"
        status, lines = run_cli(["export", str(path), "--to", "csv", "--out", str(export)])
        assert_clean_outcome(status, lines, allowed=(0, 2))
        allowed = {out, export, *export.parent.glob("export_*")}
        new = {p for p in files_in(root) - before if not any(p.is_relative_to(a) for a in allowed)}
        assert not new, new


# ---------------------------------------------------------------------------
# scene files

SCENE_BAD_VALUES = st.sampled_from(
    ["200", "yes", "", -1, 0, -1e308, 1e308, math.nan, math.inf, True, [], [1, 2], {"x": 1}]
)


def scene_paths(doc: dict[str, Any], prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = []
    for key, value in doc.items() if isinstance(doc, dict) else enumerate(doc):
        here = (*prefix, key)
        numbers = isinstance(value, list) and value and isinstance(value[0], int | float)
        if isinstance(value, dict | list) and value and not numbers:
            out += scene_paths(value, here)
        else:
            out.append(here)
    return out


@FUZZ
@given(data=st.data())
def test_mutated_scene_files_are_one_error_or_fine(data):
    text = importlib.resources.files("regopack.scenes").joinpath("small.toml").read_text("utf-8")
    doc = tomllib.loads(text)
    doc["count"] = 30
    doc["domain"]["width"] = doc["domain"]["height"] = 60.0
    paths = scene_paths(doc)
    where = data.draw(st.sampled_from(paths))
    target = doc
    for key in where[:-1]:
        target = target[key]
    value = data.draw(SCENE_BAD_VALUES)
    if data.draw(st.booleans()) and isinstance(target, dict):
        del target[where[-1]]
    else:
        target[where[-1]] = value
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        scene = root / "scene.toml"
        try:
            scene.write_text(_toml.dumps(doc), encoding="utf-8")
        except (TypeError, ValueError):  # TOML cannot say it (NaN in some writers, None)
            return
        before = files_in(root)
        status, lines = run_cli(["run", str(scene), "--out", str(root / "out"), "--quiet"])
        assert_clean_outcome(status, lines, allowed=(0, 2))
        new = {p for p in files_in(root) - before if not p.is_relative_to(root / "out")}
        assert not new, new


# ---------------------------------------------------------------------------
# experiment files

EXPERIMENT = {
    "name": "fuzz",
    "base": "small",
    "set": {"count": 10, "domain.width": 50.0, "domain.height": 50.0},
    "sweep": {"seed": "1..2"},
    "metrics": ["placed", "phi_domain"],
    "verify": False,
    "max_runs": 4,
}
EXPERIMENT_BAD_VALUES = st.sampled_from(
    ["", "yes", "1..", "3..1", "1..10**9", -1, 0, 1e308, math.inf, True, [], {"x": 1}, [None]]
)


@settings(max_examples=15, deadline=None, derandomize=True)
@given(
    key=st.sampled_from(["name", "base", "set", "sweep", "metrics", "verify", "max_runs", "seed"]),
    value=EXPERIMENT_BAD_VALUES,
)
def test_mutated_experiment_files_are_one_error_or_fine(key, value):
    doc = json.loads(json.dumps(EXPERIMENT))
    if key == "seed":
        doc["sweep"]["seed"] = value
    else:
        doc[key] = value
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        path = root / "fuzz.toml"
        try:
            path.write_text(_toml.dumps(doc), encoding="utf-8")
        except (TypeError, ValueError):
            return
        before = files_in(root)
        argv = ["sweep", str(path), "--out", str(root / "out"), "--workers", "1"]
        status, lines = run_cli([*argv, "--quiet", "--no-plots"])
        assert_clean_outcome(status, lines, allowed=(0, 1, 2))
        new = {p for p in files_in(root) - before if not p.is_relative_to(root / "out")}
        assert not new, new
