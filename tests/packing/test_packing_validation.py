"""A packing file that breaks the format is refused with one line, before any kernel runs.

A crafted file used to reach the compiled g(r) kernel with mineral indices
outside the phases: ``regopack analyze FILE --only rdf`` segfaulted (index
10^6), aborted in glibc (indices 99 and -3) or wrote out of bounds and exited
0 (index 6 of 6 phases). :func:`regopack.load` now checks every array and
``meta`` key of the file, :class:`~regopack.packing.core.Packing` checks itself
when it is built (and :meth:`~regopack.packing.core.Packing.validate` again before
the analyses), and the g(r) wrapper checks the indices it passes to the
compiled code.

Each bad file is a valid one with one entry rewritten by numpy. The command
line runs outside pytest's process (the installed ``regopack`` program, and
forked children of one helper process), so that a crash shows as a negative
exit status instead of killing pytest.
"""

from __future__ import annotations

import io
import json
import os
import re
import subprocess
import sys
import zipfile
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from cli_helpers import one_error_line

from regopack.analysis.pipeline import run_analyses
from regopack.base.errors import ExportError, PackingError, PackingFileError, RegopackError
from regopack.cli import main
from regopack.geometry.domain import Rectangle
from regopack.geometry.population import Population, ShapeBatch
from regopack.packing.core import Packing, load, save
from regopack.plugins.analyzers.common import interior_margin, interior_mask
from regopack.plugins.analyzers.rdf import rdf_histogram
from regopack.plugins.exporters import JsonExporter, read_json
from regopack.registry.interfaces import InsertionResult
from regopack.testing import make_registry, packing_from_polygons
from regopack.verification.polygons import verify

NAMES = ("pyroxene", "glass", "ilmenite")
SIDE = 7


def valid_packing(rounding: bool = False) -> Packing:
    """7 x 7 unit squares of three minerals in a 7 x 7 box; particles 5, 17 and 30 not placed."""
    squares = [
        [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)] for y in range(SIDE) for x in range(SIDE)
    ]
    placed = [j not in (5, 17, 30) for j in range(len(squares))]
    p = packing_from_polygons(squares, domain=(0, SIDE, 0, SIDE), placed=placed)
    p = replace(
        p,
        mineral=np.arange(p.n_particles, dtype=np.int64) % len(NAMES),
        mineral_names=NAMES,
        stats={"interior_margin": 0.5, "tries": 49.0},
    )
    if rounding:  # the radius of the rounded square's area
        rho = 0.01
        radius = np.full(p.n_particles, np.sqrt((1 + 4 * rho + np.pi * rho**2) / np.pi))
        p = replace(p, rounding=np.full(p.n_particles, rho), radius=radius)
    return p


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("good") / "packing.npz"
    save(valid_packing(), path)
    return path


@pytest.fixture(scope="module")
def good_rounded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("good") / "rounded.npz"
    save(valid_packing(rounding=True), path)
    return path


Change = Callable[[dict[str, Any]], None]


def craft(source: Path, target: Path, change: Change) -> Path:
    """Copy ``source`` to ``target`` with ``change`` applied to its entries (``meta`` as a dict)."""
    with np.load(source, allow_pickle=False) as npz:
        contents: dict[str, Any] = {k: npz[k] for k in npz.files}
    contents["meta"] = json.loads(str(contents["meta"]))
    change(contents)
    if isinstance(contents["meta"], dict):
        contents["meta"] = np.array(json.dumps(contents["meta"]))
    np.savez(target, **contents)
    return target


# -- the defects ------------------------------------------------------------------

INTERIOR = 24  # the middle square: placed, inside the g(r) window, so the kernel sees it
NOT_PLACED = 5


def set_value(name: str, j: int, value: Any) -> Change:
    def change(c: dict[str, Any]) -> None:
        arr = c[name].copy()
        arr[j] = value
        c[name] = arr

    return change


def set_array(name: str, value: Callable[[np.ndarray], Any]) -> Change:
    def change(c: dict[str, Any]) -> None:
        c[name] = value(c[name])

    return change


def set_meta(key: str, value: Any) -> Change:
    def change(c: dict[str, Any]) -> None:
        c["meta"][key] = value

    return change


def drop(name: str) -> Change:
    def change(c: dict[str, Any]) -> None:
        del c[name]

    return change


def set_minerals(values: dict[int, int]) -> Change:
    def change(c: dict[str, Any]) -> None:
        m = c["mineral"].copy()
        for j, v in values.items():
            m[j] = v
        c["mineral"] = m

    return change


def swap_offsets(c: dict[str, Any]) -> None:
    o = c["offsets"].copy()
    o[3], o[4] = o[4], o[3]  # offsets decrease from particle 3 to 4
    c["offsets"] = o


DEFECTS: dict[str, tuple[Change, str]] = {
    # index ranges: the crashes of the issue
    "mineral 10^6": (
        set_value("mineral", INTERIOR, 10**6),
        "array 'mineral' has the value 1000000",
    ),
    "mineral -3": (set_value("mineral", INTERIOR, -3), "array 'mineral' has the value -3"),
    "mineral 99 and -3": (
        set_minerals({8: 99, 9: -3}),
        "array 'mineral' has the value 99 at particle 8",
    ),
    "mineral n_phases": (
        set_value("mineral", 8, len(NAMES)),
        "array 'mineral' has the value 3 at particle 8",
    ),
    "mineral of unplaced particle": (set_value("mineral", NOT_PLACED, 7), "array 'mineral'"),
    "insertion_index n": (
        set_value("insertion_index", 0, 49),
        "array 'insertion_index' has the value 49",
    ),
    "insertion_index -2": (set_value("insertion_index", NOT_PLACED, -2), "array 'insertion_index'"),
    "insertion_index duplicate": (
        set_value("insertion_index", 1, 0),
        "gives the value 0 to particles 0 and 1",
    ),
    "insertion_index gap": (set_value("insertion_index", 48, 47), "array 'insertion_index' skips"),
    # non-finite and non-positive values
    "vertices NaN": (
        set_value("vertices", 10, np.nan),
        "array 'vertices' has the non-finite value",
    ),
    "vertices inf": (set_value("vertices", 0, np.inf), "array 'vertices' has the non-finite value"),
    "radius NaN": (set_value("radius", 3, np.nan), "array 'radius' has the non-finite value"),
    "radius negative": (
        set_value("radius", 3, -1.0),
        "array 'radius' has the value -1.0 at particle 3",
    ),
    "radius zero": (set_value("radius", 3, 0.0), "array 'radius' has the value 0.0"),
    "orientation inf": (
        set_value("orientation", 2, np.inf),
        "array 'orientation' has the non-finite",
    ),
    "centre NaN placed": (
        set_value("centre", 0, np.nan),
        "array 'centre' is [nan nan] at particle 0, which is placed",
    ),
    "centre inf placed": (set_value("centre", 0, [np.inf, 1.0]), "array 'centre'"),
    "centre of unplaced": (set_value("centre", NOT_PLACED, [1.0, 1.0]), "which is not placed"),
    "centre inf unplaced": (set_value("centre", NOT_PLACED, [np.inf, np.nan]), "array 'centre'"),
    # offsets
    "offsets decreasing": (swap_offsets, "array 'offsets' does not rise strictly"),
    "offsets repeated": (set_value("offsets", 4, 12), "array 'offsets' does not rise strictly"),
    "offsets start": (set_array("offsets", lambda o: o + 1), "array 'offsets' starts at 1, not 0"),
    "offsets end": (set_value("offsets", -1, 10**6), "array 'offsets' ends at 1000000"),
    "offsets wrapping around": (
        set_array(
            "offsets",
            lambda o: np.concatenate([[0, 2**62, -(2**63), -(2**62)], o[4:]]).astype(np.int64),
        ),
        "array 'offsets' has the value 4611686018427387904 at entry 1, outside",
    ),
    "offsets short": (set_array("offsets", lambda o: o[:-1]), "array 'offsets' has 49 entries"),
    # shapes
    "orientation short": (
        set_array("orientation", lambda a: a[:-1]),
        "array 'orientation' has 48 rows",
    ),
    "mineral 2-D": (
        set_array("mineral", lambda a: a.reshape(7, 7)),
        "array 'mineral' has shape (7, 7), expected a 1-D array",
    ),
    "vertices 1-D": (
        set_array("vertices", lambda a: a.ravel()),
        "array 'vertices' has shape (392,), expected a 2-D array",
    ),
    "centre 3 columns": (
        set_array("centre", lambda a: np.c_[a, a[:, :1]]),
        "array 'centre' has shape (49, 3)",
    ),
    "vertices empty": (set_array("vertices", lambda a: a[:0]), "array 'offsets' ends at 196"),
    # dtypes
    "mineral float": (
        set_array("mineral", lambda a: a.astype(np.float64)),
        "array 'mineral' has dtype float64, expected int64",
    ),
    "mineral bool": (set_array("mineral", lambda a: a > 0), "array 'mineral' has dtype bool"),
    "mineral uint64": (
        set_array("mineral", lambda a: a.astype(np.uint64)),
        "array 'mineral' has dtype uint64",
    ),
    "radius complex": (
        set_array("radius", lambda a: a + 0j),
        "array 'radius' has dtype complex128",
    ),
    "radius strings": (set_array("radius", lambda a: a.astype(str)), "array 'radius' has dtype <U"),
    "radius object": (
        set_array("radius", lambda a: a.astype(object)),
        "array 'radius' cannot be read (Object arrays",
    ),
    "mineral object": (
        set_array("mineral", lambda a: a.astype(object)),
        "array 'mineral' cannot be read",
    ),
    # rounding
    "rounding negative": (
        lambda c: c.update(rounding=np.full(49, -0.1)),
        "array 'rounding' has the value -0.1",
    ),
    "rounding NaN": (
        lambda c: c.update(rounding=np.r_[np.zeros(48), np.nan]),
        "array 'rounding' has the value nan at particle 48",
    ),
    "rounding short": (
        lambda c: c.update(rounding=np.zeros(48)),
        "array 'rounding' has shape (48,)",
    ),
    "rounding 2-D": (
        lambda c: c.update(rounding=np.zeros((49, 1))),
        "array 'rounding' has shape (49, 1), expected a 1-D array",
    ),
    # missing arrays
    **{
        f"missing {name}": (drop(name), f"missing array {name!r}")
        for name in (
            "radius",
            "mineral",
            "vertices",
            "offsets",
            "orientation",
            "centre",
            "insertion_index",
        )
    },
    # meta: names, version, types, domain
    "mineral name empty": (
        set_meta("mineral_names", ["pyroxene", "", "ilmenite"]),
        "'mineral_names' has an empty name (phase 1)",
    ),
    "mineral names repeated": (
        set_meta("mineral_names", ["glass", "glass", "ilmenite"]),
        "'mineral_names' repeats 'glass'",
    ),
    "mineral names not strings": (
        set_meta("mineral_names", [1, 2, 3]),
        "meta 'mineral_names' is [1, 2, 3], not a list of strings",
    ),
    "mineral names a string": (set_meta("mineral_names", "abc"), "meta 'mineral_names' is 'abc'"),
    "mineral names missing": (
        lambda c: c["meta"].pop("mineral_names"),
        "meta 'mineral_names' is missing",
    ),
    "mineral names too few": (
        set_meta("mineral_names", ["pyroxene", "glass"]),
        "array 'mineral' has the value 2 at particle 2",
    ),
    "version a string": (
        set_meta("format_version", "1"),
        "meta 'format_version' is '1', a str, not an integer",
    ),
    "version a bool": (set_meta("format_version", True), "meta 'format_version' is True, a bool"),
    "version a float": (set_meta("format_version", 1.0), "meta 'format_version' is 1.0, a float"),
    "version 0": (set_meta("format_version", 0), "meta 'format_version' is 0, not a known version"),
    "version missing": (
        lambda c: c["meta"].pop("format_version"),
        "meta 'format_version' is missing",
    ),
    "scene a list": (set_meta("scene", [1]), "meta 'scene' is [1], not an object"),
    "stats a number": (set_meta("stats", 3), "meta 'stats' is 3, not an object"),
    "stats a string value": (
        set_meta("stats", {"tries": "many"}),
        "meta 'stats' has 'tries' = 'many', not a number",
    ),
    "seed a string": (set_meta("seed", "1"), "meta 'seed' is '1', not an integer"),
    "seed a float": (set_meta("seed", 1.5), "meta 'seed' is 1.5"),
    "version number": (set_meta("version", 1), "meta 'version' is 1, not a string"),
    "domain a list": (
        set_meta("domain", [0, 7, 0, 7]),
        "meta 'domain' is [0, 7, 0, 7], not an object",
    ),
    "domain missing": (lambda c: c["meta"].pop("domain"), "meta 'domain' is missing"),
    "domain reversed": (
        set_meta("domain", {"kind": "rectangle", "bounds": [7, 0, 0, 7]}),
        "meta 'domain' (kind 'rectangle'): bounds [7, 0, 0, 7] must be",
    ),
    "domain flat": (
        set_meta("domain", {"kind": "rectangle", "bounds": [0, 7, 1, 1]}),
        "meta 'domain' (kind 'rectangle')",
    ),
    "domain NaN": (
        set_meta("domain", {"kind": "periodic", "bounds": [0, float("nan"), 0, 7]}),
        "bounds: nan is not finite",
    ),
    "domain string bound": (
        set_meta("domain", {"kind": "rectangle", "bounds": ["0", 7, 0, 7]}),
        "bounds: '0' is not a number",
    ),
    "domain 3 bounds": (
        set_meta("domain", {"kind": "rectangle", "bounds": [0, 7, 0]}),
        "meta 'domain' (kind 'rectangle')",
    ),
    "domain no bounds": (
        set_meta("domain", {"kind": "rectangle"}),
        "meta 'domain' (kind 'rectangle'): no 'bounds'",
    ),
    "domain unknown kind": (set_meta("domain", {"kind": "torus"}), "unknown domain kind 'torus'"),
    "circle radius": (
        set_meta("domain", {"kind": "circle", "center": [3.5, 3.5], "radius": -1}),
        "radius -1 must be > 0",
    ),
    "polygon not convex": (
        set_meta("domain", {"kind": "polygon", "vertices": [[0, 0], [7, 0], [1, 1], [0, 7]]}),
        "meta 'domain' (kind 'polygon'): the corners must form",
    ),
    "meta an array": (lambda c: c.update(meta=np.arange(3)), "'meta' is a int64 array"),
}


@pytest.mark.parametrize("defect", list(DEFECTS))
def test_load_refuses_the_defect_naming_file_and_array(good, tmp_path, defect):
    change, message = DEFECTS[defect]
    path = craft(good, tmp_path / "bad.npz", change)
    with pytest.raises(PackingFileError) as info:
        load(path)
    text = str(info.value)
    assert text.startswith(f"{path}: ")
    assert message in text
    assert "\n" not in text


def test_the_valid_files_load(good, good_rounded, tmp_path):
    for path in (good, good_rounded):
        p = load(path)
        p.validate()
        assert (p.n_particles, p.n_placed, p.mineral_names) == (49, 46, NAMES)
    assert load(good_rounded).rounded
    # an unchanged rewrite with numpy loads too: the crafting alone is no defect
    assert load(craft(good, tmp_path / "same.npz", lambda c: None)).n_placed == 46
    # narrower dtypes that convert exactly are read as the format's dtypes
    narrow = craft(good, tmp_path / "narrow.npz", set_array("mineral", lambda a: a.astype(np.int8)))
    assert load(narrow).mineral.dtype == np.int64
    # null stats (NaN when written) and a missing scene are fine
    loose = craft(
        good, tmp_path / "loose.npz", lambda c: c["meta"].update(stats={"x": None}, scene=None)
    )
    assert np.isnan(load(loose).stats["x"]) and load(loose).scene == {}


def test_unknown_entries_are_ignored(good, tmp_path):
    path = craft(good, tmp_path / "extra.npz", lambda c: c.update(extra=np.arange(3)))
    assert load(path).n_particles == 49


# -- the command line ---------------------------------------------------------------

CLI_DEFECTS = {
    "index": "mineral 10^6",  # segfaulted
    "index_abort": "mineral 99 and -3",  # glibc abort
    "index_silent": "mineral n_phases",  # exit 0 after an out-of-bounds write
    "insertion": "insertion_index duplicate",
    "finite": "vertices NaN",
    "offsets": "offsets decreasing",
    "shape": "orientation short",
    "dtype": "mineral float",
    "pickle": "mineral object",
    "missing": "missing centre",
    "rounding": "rounding negative",
    "names": "mineral name empty",
    "version": "version a string",
    "meta": "stats a string value",
    "domain": "domain reversed",
}


FORKING_DRIVER = """
import json, os, sys
# what 'analyze' imports, once for all children
import regopack.analysis.pipeline, regopack.registry.manager
from regopack.cli import main

results = {}
for label, argv, out, err in json.loads(sys.argv[1]):
    pid = os.fork()
    if pid == 0:  # the child runs the command once, as the regopack program would
        os.dup2(os.open(out, os.O_WRONLY | os.O_CREAT), 1)
        os.dup2(os.open(err, os.O_WRONLY | os.O_CREAT), 2)
        code = main(argv)
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    results[label] = pid
for label, pid in results.items():
    results[label] = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
print(json.dumps(results))
"""
"""Import regopack once, then run each command in a child of its own (a crash kills only it)."""


def analyze_argv(path: Path, out_dir: Path) -> list[str]:
    return ["analyze", str(path), "--only", "rdf", "--no-figures", "--out", str(out_dir)]


@pytest.fixture(scope="module", autouse=True)
def cli_started(good, tmp_path_factory):
    """Start ``regopack analyze FILE --only rdf`` on every bad file; the other tests run meanwhile.

    The issue's crash (mineral index 10^6) runs through the installed
    ``regopack`` program; the rest run in forked children of one process that
    imported regopack once, so the whole set takes about as long as one run.
    """
    root = tmp_path_factory.mktemp("cli")
    files = {
        label: craft(good, root / f"{label}.npz", DEFECTS[defect][0])
        for label, defect in CLI_DEFECTS.items()
    }
    program = Path(sys.executable).with_name("regopack")
    real = subprocess.Popen(
        [str(program), *analyze_argv(files["index"], root / "out-index")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    jobs = [
        (
            label,
            analyze_argv(path, root / f"out-{label}"),
            f"{root}/{label}.out",
            f"{root}/{label}.err",
        )
        for label, path in files.items()
        if label != "index"
    ]
    driver = subprocess.Popen(
        [sys.executable, "-c", FORKING_DRIVER, json.dumps(jobs)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    yield files, root, real, driver
    for proc in (real, driver):
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@pytest.fixture(scope="module")
def cli_runs(cli_started):
    """Exit status, stdout, stderr and output directory of every command started."""
    files, root, real, driver = cli_started
    driver_out, driver_err = driver.communicate(timeout=120)
    assert driver.returncode == 0, driver_err
    runs = {}
    for label, status in json.loads(driver_out).items():
        out = (root / f"{label}.out").read_text()
        err = (root / f"{label}.err").read_text()
        runs[label] = (files[label], status, out, err, root / f"out-{label}")
    out, err = real.communicate(timeout=120)
    runs["index"] = (files["index"], real.returncode, out, err, root / "out-index")
    return runs


def test_the_kernel_would_see_the_crafted_particles(good):
    """The particles given bad minerals lie in the g(r) window: without the checks, the
    compiled kernel indexes its histogram with their minerals (the crash of the issue)."""
    p = load(good)
    inside = interior_mask(p, interior_margin(p))
    assert inside[[INTERIOR, 8, 9]].all()
    assert inside.sum() == 23  # 25 squares inside the window, 2 of them not placed


@pytest.mark.parametrize("label", list(CLI_DEFECTS))
def test_cli_refuses_a_bad_file_in_one_line(cli_runs, label):
    path, status, out, err, out_dir = cli_runs[label]
    assert status == 2, f"exit status {status} (a crash is negative or > 128): {err[-2000:]}"
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"regopack: error: {path}: invalid packing file: ")
    assert DEFECTS[CLI_DEFECTS[label]][1] in lines[0]
    assert "Traceback" not in err
    assert out == ""
    assert not out_dir.exists()


# -- packings built in Python ---------------------------------------------------------


def test_packing_error_is_a_one_line_user_error():
    assert issubclass(PackingError, RegopackError)
    assert issubclass(PackingError, ValueError)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"mineral": np.full(49, 3)}, "array 'mineral' has the value 3 at particle 0"),
        ({"mineral": np.full(49, -1)}, "array 'mineral' has the value -1"),
        ({"mineral": np.zeros(49)}, "array 'mineral' has dtype float64, expected int64"),
        ({"mineral_names": ()}, "not a phase index in [0, 0)"),
        ({"mineral_names": "abc"}, "'mineral_names' must be a list of strings"),
        ({"insertion_index": np.arange(49)}, "array 'centre' is [nan nan] at particle 5"),
        ({"offsets": np.zeros(50, dtype=np.int64)}, "array 'offsets' does not rise strictly"),
        ({"radius": np.ones((49, 1))}, "array 'radius' has shape (49, 1), expected a 1-D array"),
        ({"vertices": [[0.0, 0.0]] * 3}, "array 'offsets' ends at 196, but 'vertices' has 3 rows"),
        ({"radius": [object()] * 49}, "array 'radius' has dtype object"),
        ({"rounding": np.zeros(3)}, "array 'rounding' has shape (3,)"),
        ({"stats": {"tries": "many"}}, "'stats' has 'tries' = 'many', not a number"),
        ({"domain": (0, 7, 0, 7)}, "'domain' is a tuple, not a PlaneDomain"),
    ],
    ids=lambda v: next(iter(v)) if isinstance(v, dict) else None,
)
def test_constructor_refuses_a_broken_packing(changes, message):
    with pytest.raises(PackingError) as info:
        replace(valid_packing(), **changes)
    assert message in str(info.value)


def test_constructor_converts_exact_dtypes():
    p = valid_packing()
    q = replace(p, mineral=p.mineral.astype(np.int32).tolist(), radius=p.radius.astype(np.float32))
    assert q.mineral.dtype == np.int64 and q.radius.dtype == np.float64
    assert replace(p, mineral_names=list(NAMES)).mineral_names == NAMES


def test_from_parts_refuses_an_inserter_result_out_of_range():
    shapes = ShapeBatch(
        np.tile([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]], (2, 1)), np.array([0, 3, 6]), np.zeros(2)
    )
    pop = Population(np.ones(2), np.array([0, 1], dtype=np.int64), ("x", "y"), shapes)
    result = InsertionResult(np.array([[0.0, 0.0], [5.0, 5.0]]), np.array([0, 0], dtype=np.int64))
    with pytest.raises(PackingError, match="gives the value 0 to particles 0 and 1"):
        Packing.from_parts(pop, result, valid_packing().domain, {}, 1)


def test_analyses_refuse_arrays_changed_in_place():
    p = valid_packing()
    p.mineral[INTERIOR] = 10**6  # the arrays are not read-only: the analyses check again
    with pytest.raises(PackingError, match="array 'mineral' has the value 1000000"):
        p.validate()
    with pytest.raises(PackingError, match="array 'mineral'"):
        run_analyses(p, make_registry(builtins=()), [("rdf", {})])


def test_json_import_refuses_a_broken_packing(tmp_path):
    path = JsonExporter().export(valid_packing(), tmp_path / "p.json")
    doc = json.loads(path.read_text())
    doc["particles"][4]["mineral"] = 99
    path.write_text(json.dumps(doc))
    with pytest.raises(ExportError, match=rf"^{path}: array 'mineral' has the value 99"):
        read_json(path)


# -- the g(r) wrapper -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "n_kinds", "x", "bins", "message"),
    [
        ([0, 1, 3], 3, [0.0, 1.0, 2.0], 4, r"every kind must lie in \[0, 3\)"),
        ([0, -1, 2], 3, [0.0, 1.0, 2.0], 4, r"every kind must lie in \[0, 3\)"),
        ([0, 0, 0], 0, [0.0, 1.0, 2.0], 4, "n_kinds must be >= 1"),
        ([0, 0], 1, [0.0, 1.0, 2.0], 4, "one length"),
        ([0.0, 0.0, 0.0], 1, [0.0, 1.0, 2.0], 4, "integer array"),
        ([0, 0, 0], 1, [0.0, np.nan, 2.0], 4, "finite"),
        ([0, 0, 0], 1, [0.0, 1.0, 2.0], 0, "bins"),
    ],
)
def test_rdf_wrapper_checks_what_the_kernel_indexes(kind, n_kinds, x, bins, message):
    x = np.asarray(x)
    y = np.zeros(3)
    with pytest.raises(ValueError, match=message):
        rdf_histogram(x, y, np.asarray(kind), n_kinds, 0.0, 0.5, bins, 10.0, 10.0)


# -- special and hostile files: refused before anything is read --------------------------


def write_members(
    target: Path, members: dict[str, bytes | np.ndarray], deflate: bool = False
) -> Path:
    """A zip of ``name.npy`` members: arrays written as NPY, bytes as they are."""
    method = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
    with zipfile.ZipFile(target, "w", method) as zf:
        for name, value in members.items():
            if isinstance(value, np.ndarray):
                buf = io.BytesIO()
                np.lib.format.write_array(buf, value, allow_pickle=False)
                value = buf.getvalue()
            zf.writestr(f"{name}.npy", value)
    return target


def members_of(path: Path) -> dict[str, bytes | np.ndarray]:
    with np.load(path, allow_pickle=False) as npz:
        return {k: npz[k] for k in npz.files}


def refuse_data_reads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if the data of a member other than ``meta`` is read from now on."""
    read_array = np.lib.format.read_array

    def refuse(fh, *args, **kwargs):
        assert fh.name == "meta.npy", f"the data of {fh.name} was read"
        return read_array(fh, *args, **kwargs)

    monkeypatch.setattr(np.lib.format, "read_array", refuse)


@pytest.mark.parametrize("kind", ["fifo", "device", "directory"])
def test_only_regular_files_are_opened(tmp_path, kind, capsys):
    """A FIFO used to block in open(), /dev/zero to read without end."""
    if kind == "fifo":
        path = tmp_path / "pipe.npz"
        os.mkfifo(path)
        what = "is a FIFO (named pipe)"
    elif kind == "device":
        path = Path("/dev/zero")
        what = "is a character device"
    else:
        path = tmp_path
        what = "is a directory"
    with pytest.raises(PackingFileError, match=rf"^{re.escape(str(path))}: {re.escape(what)}, "):
        load(path)
    assert main(["verify", str(path)]) == 2
    assert what in one_error_line(capsys)


def test_a_zip_bomb_is_refused_before_it_is_decompressed(good, tmp_path, monkeypatch):
    members = members_of(good)
    members["radius"] = np.zeros(2**19)  # 4 MiB that deflate to 4 KiB
    path = write_members(tmp_path / "bomb.npz", members, deflate=True)
    refuse_data_reads(monkeypatch)
    with pytest.raises(PackingFileError, match="member 'radius' declares 4194432 bytes compressed"):
        load(path)


def test_a_recompressed_one_phase_packing_loads(tmp_path):
    """A one-phase packing's 'mineral' (all zeros) deflates far more than 100 times."""
    n = 2**17 + 1000  # 'mineral' above 1 MiB
    side = 1e-3 * (1 + 1e-6 * np.arange(n))  # every square a little larger: no repeats
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    p = Packing(
        radius=side / np.sqrt(np.pi),
        mineral=np.zeros(n, np.int64),
        mineral_names=("a",),
        vertices=(side[:, None, None] * unit).reshape(-1, 2),
        offsets=np.arange(0, 4 * n + 1, 4),
        orientation=np.zeros(n),
        centre=np.full((n, 2), np.nan),
        insertion_index=np.full(n, -1),
        domain=Rectangle(0, 7, 0, 7),
    )
    plain = tmp_path / "plain.npz"
    save(p, plain)
    packed = tmp_path / "compressed.npz"
    np.savez_compressed(packed, **members_of(plain))
    with zipfile.ZipFile(packed) as zf:
        info = zf.getinfo("mineral.npy")
        assert info.file_size > 100 * info.compress_size
    q = load(packed)
    assert q.n_particles == n and not q.mineral.any()


def _patch_member_field(path: Path, member: str, field: str, value: int) -> None:
    """Set a field of ``member``'s local and central headers: ``method``, or or-ed ``flags``."""
    data = bytearray(path.read_bytes())
    name = member.encode()
    for sig, method, flags, nlen_at, hdr in (
        (b"PK\x01\x02", 10, 8, 28, 46),
        (b"PK\x03\x04", 8, 6, 26, 30),
    ):
        i = data.find(sig)
        while i >= 0:
            nlen = int.from_bytes(data[i + nlen_at : i + nlen_at + 2], "little")
            if data[i + hdr : i + hdr + nlen] == name:
                at = i + (method if field == "method" else flags)
                old = int.from_bytes(data[at : at + 2], "little")
                new = value if field == "method" else old | value
                data[at : at + 2] = new.to_bytes(2, "little")
            i = data.find(sig, i + 4)
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    ("field", "value", "why"),
    [
        ("method", 99, "That compression method is not supported"),
        ("flags", 1, "it is encrypted"),
    ],
)
def test_a_member_zipfile_cannot_open_is_one_line(good, tmp_path, capsys, field, value, why):
    path = write_members(tmp_path / "odd.npz", members_of(good))
    _patch_member_field(path, "radius.npy", field, value)
    with pytest.raises(PackingFileError, match=f"member 'radius' cannot be read \\({why}"):
        load(path)
    assert main(["verify", str(path)]) == 2
    assert why in one_error_line(capsys)


def test_a_member_given_twice_is_refused(good, tmp_path):
    """zipfile would read one copy and numpy.load the other."""
    path = write_members(tmp_path / "twice.npz", members_of(good))
    with pytest.warns(UserWarning, match="Duplicate name"), zipfile.ZipFile(path, "a") as zf:
        zf.writestr("radius.npy", b"\x93NUMPY garbage")
    with pytest.raises(PackingFileError, match=r"member 'radius\.npy' appears more than once"):
        load(path)


def test_a_header_of_a_trillion_entries_is_refused_before_allocation(good, tmp_path, monkeypatch):
    members = members_of(good)
    buf = io.BytesIO()
    header = {"descr": "<f8", "fortran_order": False, "shape": (10**12,)}
    np.lib.format.write_array_header_1_0(buf, header)
    members["radius"] = buf.getvalue() + bytes(8 * 49)
    path = write_members(tmp_path / "huge.npz", members)
    refuse_data_reads(monkeypatch)
    with pytest.raises(PackingFileError, match=r"array 'radius' declares shape \(1000000000000,\)"):
        load(path)


def test_rows_beyond_the_particle_count_are_refused_before_reading(good, tmp_path):
    members = members_of(good)
    members["mineral"] = np.zeros(10**4, dtype=np.int64)
    path = write_members(tmp_path / "rows.npz", members)
    with pytest.raises(PackingFileError, match="array 'mineral' declares 10000 rows; at most 49"):
        load(path)


def test_a_member_without_an_npy_header_is_one_line(good, tmp_path):
    members = members_of(good)
    members["mineral"] = b"not an array at all"
    path = write_members(tmp_path / "junk.npz", members)
    with pytest.raises(PackingFileError, match="member 'mineral' has no valid NPY header"):
        load(path)


@pytest.mark.parametrize(
    ("meta", "message"),
    [
        ("[" * 100_000 + "]" * 100_000, "meta nests objects and lists 100000 deep; at most 32"),
        (json.dumps({"format": "x", "pad": "[" * 10**5}), "not a regopack packing file"),
        ("x" * (2**22 + 1), "meta is 4194305 characters long; at most 4194304"),
    ],
    ids=["deep", "brackets in a string", "long"],
)
def test_meta_is_bounded_in_depth_and_size(good, tmp_path, meta, message):
    members = members_of(good)
    members["meta"] = np.array(meta)
    path = write_members(tmp_path / "meta.npz", members)
    with pytest.raises(PackingFileError, match=message):
        load(path)


# -- what the numbers mean: outlines, radii, positions ------------------------------------


def set_outline(j: int, outline: list[tuple[float, float]]) -> Change:
    """Give particle ``j`` the outline ``outline`` (relative to its centre)."""

    def change(c: dict[str, Any]) -> None:
        o = c["offsets"]
        v = c["vertices"]
        new = np.asarray(outline, dtype=np.float64)
        c["vertices"] = np.concatenate([v[: o[j]], new, v[o[j + 1] :]])
        c["offsets"] = np.concatenate([o[: j + 1], o[j + 1 :] + len(new) - (o[j + 1] - o[j])])

    return change


def scale_file(factor: float) -> Change:
    def change(c: dict[str, Any]) -> None:
        for name in ("vertices", "centre", "radius"):
            c[name] = c[name] * factor
        c["meta"]["domain"]["bounds"] = [b * factor for b in c["meta"]["domain"]["bounds"]]

    return change


def periodic(c: dict[str, Any]) -> None:
    c["meta"].update(format_version=2, domain={"kind": "periodic", "bounds": [0, 7, 0, 7]})


PENTAGRAM = [(np.cos(a), np.sin(a)) for a in np.radians([0, 144, 288, 72, 216])]
DENTED = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (0.0, 0.2), (-0.5, 0.5)]

MEANING: dict[str, tuple[Change, str]] = {
    "zero area": (
        set_outline(INTERIOR, [(-0.5, 0.0), (0.5, 0.0), (0.5, 0.0), (-0.5, 0.0)]),
        "gives particle 24 2 distinct vertices and no rounding: its outline has no area",
    ),
    "collinear": (
        set_outline(INTERIOR, [(-0.5, -0.5), (0.0, 0.0), (0.5, 0.5), (0.25, 0.25)]),
        "gives particle 24 an outline whose edge (-0.5, -0.5) -> (0, 0) does not pass "
        "counter-clockwise around its centre",
    ),
    "bow tie": (
        set_outline(INTERIOR, [(-0.5, -0.5), (0.5, 0.5), (0.5, -0.5), (-0.5, 0.5)]),
        "particle 24 an outline whose edge",
    ),
    "clockwise": (
        set_outline(INTERIOR, [(-0.5, -0.5), (-0.5, 0.5), (0.5, 0.5), (0.5, -0.5)]),
        "particle 24 an outline whose edge",
    ),
    "pentagram": (
        set_outline(INTERIOR, PENTAGRAM),
        "gives particle 24 an outline that winds 2 times around its centre (it crosses itself)",
    ),
    "not convex": (
        set_outline(INTERIOR, DENTED),
        "gives particle 24 an outline that turns clockwise at its vertex (0, 0.20000000000000001)",
    ),
    "radius off": (
        set_value("radius", INTERIOR, 0.57),
        "array 'radius' has the value 0.57 at particle 24, but its outline's area 1 has "
        "the equivalent radius 0.56418958354775628",
    ),
    "radius 1e-320": (set_value("radius", INTERIOR, 1e-320), "array 'radius' has the value"),
    "rounding 1e300": (
        lambda c: (
            c.update(rounding=np.r_[np.zeros(24), 1e300, np.zeros(24)])
            or c["meta"].update(format_version=2)
        ),
        "array 'radius' has the value 0.5641895835477563 at particle 24, but its outline's "
        "area inf",
    ),
    "tiny particle": (
        lambda c: scale_file(1e-13)(c) or c["meta"].update(domain=DOMAIN_7),
        "array 'radius' has the value 5.641895835477563e-14 at placed particle 0, less than "
        "1e-12 of the domain's larger side 7",
    ),
    "particle at 1e17": (
        set_value("centre", INTERIOR, [1e17, 3.5]),
        "array 'centre' places particle 24 at [1.0e+17 3.5e+00] (reaching 0.5 from it), "
        "more than the domain's larger side (7) beyond the domain's bounds [0.0, 7.0, 0.0, 7.0]",
    ),
    "periodic centre outside": (
        lambda c: periodic(c) or set_value("centre", INTERIOR, [10.5, 3.5])(c),
        "array 'centre' places particle 24 at [10.5 3.5], outside the periodic cell [0, 7) x "
        "[0, 7)",
    ),
    "periodic in version 1": (
        set_meta("domain", {"kind": "periodic", "bounds": [0, 7, 0, 7]}),
        "meta 'format_version' is 1 with a periodic domain; version 1 holds sharp polygons in a "
        "walled rectangle only",
    ),
    "rounded in version 1": (
        lambda c: c.update(rounding=np.zeros(49)) or set_value("rounding", 0, 0.1)(c),
        "meta 'format_version' is 1 with rounded particles",
    ),
}
DOMAIN_7 = {"kind": "rectangle", "bounds": [0, 7, 0, 7]}


@pytest.mark.parametrize("defect", list(MEANING))
def test_load_refuses_what_the_numbers_cannot_mean(good, tmp_path, defect):
    change, message = MEANING[defect]
    path = craft(good, tmp_path / "bad.npz", change)
    with pytest.raises(PackingFileError) as info:
        load(path)
    text = str(info.value)
    assert text.startswith(f"{path}: invalid packing file: ")
    assert message in text
    assert "\n" not in text


@pytest.mark.parametrize("factor", [1e-6, 1e6])
def test_a_scaled_file_loads_and_verifies_the_same(good, tmp_path, factor):
    path = craft(good, tmp_path / "scaled.npz", scale_file(factor))
    p = load(path)
    assert p.n_placed == 46 and verify(p).ok
    np.testing.assert_allclose(p.area(), factor**2)


def test_octagons_of_many_vertices_load_at_any_scale(tmp_path):
    # a = 1, psi = 0.01, m = 256: pairs of vertices about 1e-10 of the outline
    # apart whose edge runs slightly backwards, merged on loading
    import regopack

    shape = {"kind": "octagon", "psi": 0.01, "a": 1.0, "m": 256}
    p = regopack.pack(
        "small",
        domain__width=100,
        domain__height=100,
        phases=[{"name": "a", "fraction": 1.0, "shape": shape}],
    )
    path = tmp_path / "octagons.npz"
    save(p, path)
    assert load(path).n_placed == p.n_placed

    def unscened(c: dict[str, Any]) -> None:
        c["meta"]["scene"] = {"name": "octagons"}

    for factor in (1e-6, 1e6):
        scaled = tmp_path / f"octagons-{factor:g}.npz"
        craft(path, scaled, lambda c, f=factor: (unscened(c), scale_file(f)(c)))
        q = load(scaled)
        np.testing.assert_allclose(q.radius, p.radius * factor)


def test_outlines_that_overflow_are_refused_without_warnings(good, tmp_path, recwarn):
    path = craft(good, tmp_path / "huge.npz", set_array("vertices", lambda v: v * 1e200))
    with pytest.raises(PackingFileError, match="array 'radius' has the value"):
        load(path)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_a_periodic_file_with_centres_in_the_cell_loads(good, tmp_path):
    assert load(craft(good, tmp_path / "periodic.npz", periodic)).domain.periodic


def test_verify_refuses_a_self_intersecting_outline_in_one_line(good, tmp_path, capsys):
    """The bow tie reached GEOS (an error with a traceback) in 'regopack verify'."""
    path = craft(good, tmp_path / "bowtie.npz", MEANING["bow tie"][0])
    assert main(["verify", str(path)]) == 2
    assert "particle 24 an outline whose edge" in one_error_line(capsys)


# -- the scene a file holds ------------------------------------------------------------

SCENE_7 = {
    "name": "squares",
    "seed": 1,
    "count": "auto",
    "domain": {"kind": "rectangle", "width": 7.0, "height": 7.0, "center": [3.5, 3.5]},
    "size": {"kind": "change5", "d_min": 1.0, "d_max": 2.0, "d0": 1.5, "alpha": 6.9},
    "phases": [
        {"name": name, "fraction": 1 / 3, "shape": {"kind": "regular", "m": 4}} for name in NAMES
    ],
    "insertion": {"kind": "available-arc"},
    "density": {"kind": "eta", "eta": 0.0},
}


def with_scene(**changes: Any) -> Change:
    """The good file with :data:`SCENE_7`, its ``size`` (or another section) changed."""

    def change(c: dict[str, Any]) -> None:
        scene = json.loads(json.dumps(SCENE_7))
        for key, value in changes.items():
            section, _, field = key.partition("__")
            if field:
                scene[section][field] = value
            else:
                scene[section] = value
        c["meta"]["scene"] = scene

    return change


SCENE_DEFECTS: dict[str, tuple[Change, str]] = {
    "d_max negative": (
        with_scene(size__d_max=-40),
        "meta 'scene': size.d_max = -40: Input should be greater than 0",
    ),
    "d_max a string": (
        with_scene(size__d_max="x"),
        "meta 'scene': size.d_max = \"x\": Input should be a valid number",
    ),
    "d_max below the radii": (
        with_scene(size__d_max=1.1),
        "array 'radius' has the value 0.5641895835477563 at particle 0, outside the range "
        "[0.5, 0.55000000000000004] of meta 'scene' size",
    ),
    "domain kind": (
        with_scene(domain={"kind": "circle", "radius": 3.5, "center": [3.5, 3.5]}),
        "meta 'scene' has domain.kind = 'circle', but meta 'domain' is a 'rectangle'",
    ),
    "phase names": (
        lambda c: with_scene()(c) or c["meta"]["scene"]["phases"].reverse(),
        "meta 'scene' names the phases ['ilmenite', 'glass', 'pyroxene'], but meta "
        "'mineral_names' is ['pyroxene', 'glass', 'ilmenite']",
    ),
    "interior margin": (
        set_meta("stats", {"interior_margin": -40.0}),
        "meta 'stats' has 'interior_margin' = -40.0; it is finite and >= 0",
    ),
}


@pytest.mark.parametrize("defect", list(SCENE_DEFECTS))
def test_the_scene_a_file_holds_is_checked_as_a_scene_file(good, tmp_path, defect):
    """A tampered d_max = -40 changed phi_interior from 0.85 to 0.42 without a word."""
    change, message = SCENE_DEFECTS[defect]
    path = craft(good, tmp_path / "bad.npz", change)
    with pytest.raises(PackingFileError) as info:
        load(path)
    text = str(info.value)
    assert text.startswith(f"{path}: invalid packing file: ")
    assert message in text
    assert "\n" not in text


def test_a_file_with_a_valid_scene_loads(good, tmp_path):
    p = load(craft(good, tmp_path / "scene.npz", with_scene()))
    assert p.scene["size"]["d_max"] == 2.0


def test_a_scene_naming_a_missing_sieve_table_loads(good, tmp_path):
    """The scene's plugins are not resolved: a sieve table moved away does not matter."""
    size = {"kind": "tabulated", "path": str(tmp_path / "gone.csv"), "basis": "number"}
    p = load(craft(good, tmp_path / "moved.npz", with_scene(size=size)))
    assert p.scene["size"]["path"] == size["path"]


def test_a_scene_naming_a_fifo_loads_without_opening_it(good, tmp_path):
    import threading

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    size = {"kind": "tabulated", "path": str(fifo), "basis": "number"}
    path = craft(good, tmp_path / "fifo.npz", with_scene(size=size))
    done: list[Any] = []
    thread = threading.Thread(target=lambda: done.append(load(path)), daemon=True)
    thread.start()
    thread.join(timeout=10)
    if not done:  # unblock the reader, so that the thread ends
        fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        os.close(fd)
    assert done and done[0].n_particles == 49


def test_a_scene_of_an_unknown_size_kind_loads(good, tmp_path):
    size = {"kind": "no-such-plugin", "spread": "wide"}
    assert load(craft(good, tmp_path / "unknown.npz", with_scene(size=size))).n_particles == 49


@pytest.mark.parametrize(
    "scene",
    [
        {"name": "mine"},
        {"name": "mine", "count": 4},
        {"name": "mine", "domain": SCENE_7["domain"]},
        {"name": "mine", "size": {"kind": "change5", "d_min": 9.0, "d_max": 10.0}},
    ],
)
def test_a_partial_scene_is_not_checked_as_a_run_s(good, tmp_path, scene):
    """Packings built in Python carry what scene they like; save writes them, load reads them."""
    p = load(craft(good, tmp_path / "partial.npz", set_meta("scene", scene)))
    q = tmp_path / "resaved.npz"
    save(p, q)
    assert load(q).scene == scene


def test_analyze_refuses_a_tampered_scene_in_one_line(good, tmp_path, capsys):
    path = craft(good, tmp_path / "tampered.npz", SCENE_DEFECTS["d_max negative"][0])
    assert main(["analyze", str(path), "--no-figures", "--out", str(tmp_path / "out")]) == 2
    assert "size.d_max = -40" in one_error_line(capsys)
    assert not (tmp_path / "out").exists()
