"""One packing type for both dimensions: its dimension, the other dimension's arrays, its files.

A 2D packing writes the file the 2D type wrote (format 1 or 2) and a 3D one the
file the 3D type wrote (format 3), byte for byte; the former 3D names are
deprecated aliases.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import sys
import time
import types
import warnings
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from packings3d import cube_and_sphere, cube_packing

import regopack
from regopack.base.errors import PackingError
from regopack.geometry.domain import Box, Circle, PeriodicRectangle, Rectangle
from regopack.packing import core
from regopack.packing.core import Packing, load, save
from regopack.testing import packing_from_polygons

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])

ARRAYS_2D = ("radius", "mineral", "vertices", "offsets", "orientation", "centre", "insertion_index")
ARRAYS_3D = (
    "radius",
    "mineral",
    "vertices",
    "offsets",
    "face_vertices",
    "face_vertex_offsets",
    "face_offsets",
    "normals",
    "support",
    "rotation",
    "centre",
    "insertion_index",
)


def _plain(obj: object) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(type(obj).__name__)


def write_as_before(p: Packing, path: Path) -> None:
    """Write ``p`` as the separate 2D and 3D types' writers did (``save`` and ``save3d``)."""
    d = p.domain
    if isinstance(d, Box):
        arrays = {name: getattr(p, name) for name in ARRAYS_3D}
        if p.rounding is not None:
            arrays["rounding"] = p.rounding
        head = {"format": "regopack-packing", "format_version": 3, "dimension": 3}
    else:
        arrays = {name: getattr(p, name) for name in ARRAYS_2D}
        rounded = p.rounding is not None and bool(np.any(p.rounding > 0))
        if rounded:
            arrays["rounding"] = p.rounding
        version = 1 if type(d) is Rectangle and not rounded else 2
        head = {"format": "regopack-packing", "format_version": version}
    meta = {
        **head,
        "version": p.version,
        "mineral_names": list(p.mineral_names),
        "domain": d.to_dict(),
        "scene": p.scene,
        "seed": p.seed,
        "stats": p.stats,
    }
    np.savez(path, meta=np.array(json.dumps(meta, default=_plain)), **arrays)


@pytest.fixture
def frozen_clock(monkeypatch: pytest.MonkeyPatch) -> None:
    """Give every zip member the same time stamp, so that two writes compare byte for byte."""
    clock = types.SimpleNamespace(time=lambda: 1.0e9, localtime=time.localtime)
    monkeypatch.setattr(zipfile, "time", clock)


def _packings() -> dict[str, Packing]:
    disk = np.zeros((1, 2))
    rounded = packing_from_polygons([SQUARE, SQUARE + 2.0], Rectangle(0, 5, 0, 5))
    rounded = dataclasses.replace(
        rounded,
        vertices=np.vstack([rounded.vertices[:4], disk]),
        offsets=np.array([0, 4, 5]),
        radius=np.array([1.0 / np.sqrt(np.pi), 0.5]),
        rounding=np.array([0.0, 0.5]),
    )
    return {
        "2d version 1": packing_from_polygons([SQUARE, SQUARE + 2.0], Rectangle(0, 5, 0, 5)),
        "2d periodic": packing_from_polygons(
            [SQUARE + 1.0], PeriodicRectangle(0, 5, 0, 5), placed=[True]
        ),
        "2d circle": packing_from_polygons([SQUARE + 2.0], Circle(2.5, 2.5, 2.5)),
        "2d rounded": rounded,
        "3d cubes": cube_packing([[1, 1, 1], [np.nan] * 3]),
        "3d cube and sphere": cube_and_sphere(),
        "3d sharp": cube_and_sphere(rounded=False),
    }


@pytest.mark.parametrize("name", list(_packings()))
def test_each_dimension_writes_the_file_it_wrote_before_byte_for_byte(
    tmp_path: Path, frozen_clock: None, name: str
) -> None:
    p = _packings()[name]
    save(p, tmp_path / "new.npz")
    write_as_before(p, tmp_path / "old.npz")
    assert (tmp_path / "new.npz").read_bytes() == (tmp_path / "old.npz").read_bytes()
    back = load(tmp_path / "old.npz")
    assert type(back) is Packing and back.dimension == p.dimension
    save(back, tmp_path / "again.npz")
    write_as_before(back, tmp_path / "again-old.npz")
    assert (tmp_path / "again.npz").read_bytes() == (tmp_path / "again-old.npz").read_bytes()


def test_a_packed_2d_run_writes_the_file_it_wrote_before(
    tmp_path: Path, frozen_clock: None
) -> None:
    p = regopack.pack("small", domain__width=60, domain__height=60, count=20)
    regopack.save(p, tmp_path / "new.npz")
    write_as_before(p, tmp_path / "old.npz")
    assert (tmp_path / "new.npz").read_bytes() == (tmp_path / "old.npz").read_bytes()


def test_one_type_for_both_dimensions() -> None:
    p2 = packing_from_polygons([SQUARE])
    p3 = cube_packing([[1, 1, 1]])
    assert type(p2) is type(p3) is Packing
    assert (p2.dimension, p3.dimension) == (2, 3)
    # the other dimension's arrays are empty
    assert p2.face_vertices.shape == (0,) and p2.normals.shape == (0, 3)
    assert p2.rotation.shape == (0, 4) and p3.orientation.shape == (0,)
    assert p3.face_offsets.tolist() == [0, 6]


def test_generic_measures_work_in_both_dimensions() -> None:
    p2 = packing_from_polygons([SQUARE, SQUARE + 2.0], Rectangle(0, 5, 0, 5))
    p3 = cube_packing([[1, 1, 1], [3, 1, 1]])
    assert p2.measure().tolist() == pytest.approx([1.0, 1.0])
    assert p3.measure().tolist() == pytest.approx([1.0, 1.0])
    assert p2.phi == pytest.approx(2 / 25) and p3.phi == pytest.approx(2 / 1000)
    assert p2.circumradius == pytest.approx([np.sqrt(0.5)] * 2)
    assert p3.circumradius == pytest.approx([np.sqrt(0.75)] * 2)
    assert np.array_equal(p2.world_vertices(1), p2.polygon(1))
    assert p3.world_vertices(1).min(axis=0).tolist() == [2.5, 0.5, 0.5]
    spheres = cube_and_sphere()
    assert spheres.circumradius == pytest.approx([np.sqrt(3), 1.0])


def test_the_reprs_of_both_dimensions() -> None:
    p2 = packing_from_polygons([SQUARE])
    assert repr(p2) == "Packing(1/1 placed, scene='test', seed=0)"
    p3 = cube_packing([[1, 1, 1], [np.nan] * 3])
    assert repr(p3) == "<Packing: 1 of 2 placed in a 10 × 10 × 10 box, phi 0.0010>"


@pytest.mark.parametrize(
    ("call", "instead"),
    [
        (lambda p: p.polygon(0), "world_vertices"),
        (lambda p: p.polygons(), "world_vertices"),
        (lambda p: p.to_shapely(), "solids"),
        (lambda p: p.area(), "measure"),
    ],
    ids=["polygon", "polygons", "to_shapely", "area"],
)
def test_a_2d_only_method_refuses_a_3d_packing_in_one_line(call: Any, instead: str) -> None:
    with pytest.raises(PackingError, match=f"works on 2D packings.*use .*{instead}") as err:
        call(cube_packing([[1, 1, 1]]))
    assert "\n" not in str(err.value)


def test_the_solids_of_a_2d_packing_are_refused_in_one_line() -> None:
    with pytest.raises(PackingError, match=r"works on 3D packings.*polygons\(\)") as err:
        _ = packing_from_polygons([SQUARE]).solids
    assert "\n" not in str(err.value)


def test_a_3d_packing_has_a_notebook_picture_of_its_section() -> None:
    p3 = cube_packing([[1, 1, 1]])
    assert p3._repr_png_()[:4] == b"\x89PNG"
    html = p3._repr_html_()
    assert "1 of 1 particles placed" in html and "box" in html
    assert packing_from_polygons([SQUARE])._repr_png_()[:4] == b"\x89PNG"


@pytest.mark.parametrize(
    "name",
    ["face_vertices", "face_vertex_offsets", "face_offsets", "normals", "support", "rotation"],
)
def test_a_2d_packing_with_an_array_of_3d_is_refused_in_one_line(name: str) -> None:
    p3 = cube_packing([[1, 1, 1]])
    p2 = packing_from_polygons([SQUARE])
    with pytest.raises(PackingError) as err:
        dataclasses.replace(p2, **{name: getattr(p3, name)})
    text = str(err.value)
    assert text.startswith(f"array {name!r} is set (shape ")
    assert text.endswith(
        "but a 2D packing (domain 'rectangle') has none: it belongs to 3D packings"
    )


def test_a_3d_packing_with_orientations_is_refused_in_one_line() -> None:
    with pytest.raises(PackingError) as err:
        cube_packing([[1, 1, 1]], orientation=np.zeros(1))
    assert str(err.value) == (
        "array 'orientation' is set (shape (1,)), but a 3D packing (domain 'box') has none: "
        "it belongs to 2D packings"
    )


def test_2d_arrays_in_a_box_name_the_orientation() -> None:
    p2 = packing_from_polygons([SQUARE])
    with pytest.raises(PackingError, match=r"'orientation' is set .* 3D packing .*'box'"):
        dataclasses.replace(p2, domain=Box(0, 5, 0, 5, 0, 5))


def test_a_domain_that_is_none_is_named_for_the_dimension_of_the_vertices() -> None:
    with pytest.raises(PackingError, match="'domain' is a str, not a PlaneDomain"):
        dataclasses.replace(packing_from_polygons([SQUARE]), domain="rectangle")
    with pytest.raises(PackingError, match="'domain' is a str, not a 3D box"):
        cube_packing([[1, 1, 1]], domain="box")


def test_save_refuses_what_is_no_packing(tmp_path: Path) -> None:
    with pytest.raises(PackingError, match="dict is not a packing"):
        save({}, tmp_path / "p.npz")  # type: ignore[arg-type]
    assert not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("Packing3D", "Packing"),
        ("save3d", "save"),
        ("save_packing", "save"),
        ("load_packing", "load"),
        ("check_file_values3d", "check_file_values"),
    ],
)
def test_the_former_3d_names_are_deprecated_aliases(old: str, new: str) -> None:
    with pytest.warns(DeprecationWarning, match=rf"core\.{old} is deprecated.*core\.{new}$"):
        value = getattr(core, old)
    assert value is getattr(core, new)


def test_packing3d_is_packing_and_isinstance_holds_for_both_dimensions() -> None:
    with pytest.warns(DeprecationWarning, match=r"regopack\.Packing3D is deprecated.*Packing$"):
        alias = regopack.Packing3D
    assert alias is Packing
    assert isinstance(cube_packing([[1, 1, 1]]), alias)
    assert isinstance(packing_from_polygons([SQUARE]), alias)  # test .dimension instead
    assert "Packing3D" not in regopack.__all__
    with pytest.raises(AttributeError):
        _ = core.Packing4D


def test_the_former_module_is_the_packing_module(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delitem(sys.modules, "regopack.packing.core3d", raising=False)
    with pytest.warns(DeprecationWarning, match=r"regopack\.packing\.core3d is deprecated"):
        old = importlib.import_module("regopack.packing.core3d")
    assert old is core
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert regopack.load is load and regopack.save is save


def test_a_packing_pickled_before_the_fields_of_both_dimensions_unpickles_whole() -> None:
    import pickle

    for p in (packing_from_polygons([SQUARE]), cube_packing([[1, 1, 1]])):
        state = dict(p.__dict__)
        other = ("face_vertices", "normals", "rotation") if p.dimension == 2 else ("orientation",)
        for name in other:  # as a packing of the build before held them
            del state[name]
        old = object.__new__(type(p))
        old.__dict__.update(state)
        back = pickle.loads(pickle.dumps(old))
        back.validate()
        assert back.dimension == p.dimension and back.phi == p.phi
