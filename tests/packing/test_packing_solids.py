"""3D packings: validation, the version-3 file, and reading 2D or 3D files with one call."""

from __future__ import annotations

import dataclasses
import json
import zipfile

import numpy as np
import pytest
from packings3d import _cube_arrays, cube_and_sphere, cube_packing

import regopack
from regopack.base.errors import PackingError, PackingFileError
from regopack.geometry.domain import Box, PeriodicBox, Rectangle
from regopack.packing.core import Packing, load, save
from regopack.testing import packing_from_polygons


def test_a_solid_without_faces_must_be_a_sphere() -> None:
    with pytest.raises(PackingError, match="no faces but is not a sphere"):
        cube_packing(
            [[1, 1, 1]],
            vertices=np.zeros((1, 3)),
            offsets=np.array([0, 1]),
            face_vertices=np.zeros(0, dtype=np.int64),
            face_vertex_offsets=np.zeros(1, dtype=np.int64),
            face_offsets=np.array([0, 0]),
            normals=np.zeros((0, 3)),
            support=np.zeros(0),
        )


def test_cubes_have_their_volume_fraction() -> None:
    p = cube_packing([[1, 1, 1], [3, 1, 1], [np.nan] * 3])
    assert p.n_placed == 2 and p.placed_in_order().tolist() == [0, 1]
    assert p.solids.volume.tolist() == pytest.approx([1.0, 1.0, 1.0])
    assert p.phi == pytest.approx(2.0 / 1000.0)
    assert p.world_vertices(1).min(axis=0).tolist() == [2.5, 0.5, 0.5]
    assert "2 of 3 placed" in repr(p)


def test_file_round_trip_and_one_reader_for_both_dimensions(tmp_path) -> None:
    p3 = cube_packing([[1, 1, 1], [np.nan] * 3], domain=PeriodicBox(0, 4, 0, 5, 0, 6))
    save(p3, tmp_path / "p3.npz")
    back = load(tmp_path / "p3.npz")
    assert isinstance(back, Packing) and back.dimension == 3
    assert type(back.domain) is PeriodicBox
    for name in ("vertices", "face_vertices", "normals", "centre", "rotation", "insertion_index"):
        assert np.array_equal(getattr(back, name), getattr(p3, name), equal_nan=name == "centre")
    regopack.save(p3, tmp_path / "again.npz")
    assert regopack.load(tmp_path / "again.npz").dimension == 3
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    p2 = packing_from_polygons([square, square + 2.0], Rectangle(0, 5, 0, 5))
    regopack.save(p2, tmp_path / "p2.npz")
    back2 = regopack.load(tmp_path / "p2.npz")
    assert isinstance(back2, regopack.Packing) and back2.dimension == 2


def test_a_version_3_file_of_another_dimension_is_refused_in_one_line(tmp_path) -> None:
    path = tmp_path / "p3.npz"
    save(cube_packing([[1, 1, 1]]), path)

    def flat(contents: dict[str, np.ndarray]) -> None:
        meta = json.loads(str(contents["meta"]))
        meta["dimension"] = 2
        contents["meta"] = np.array(json.dumps(meta))

    _rewrite(path, flat)
    with pytest.raises(PackingFileError) as err:
        load(path)
    assert str(err.value) == f"{path}: invalid packing file: meta 'dimension' is 2, not 3"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"normals": np.tile([[2.0, 0, 0]], (6, 1))}, "non-unit row"),
        ({"rotation": np.array([[0.5, 0, 0, 0]])}, "'rotation' has the non-unit"),
        ({"face_vertices": np.full(24, 8)}, "'face_vertices' has the value 8"),
        ({"face_vertex_offsets": np.array([0, 2, 6, 10, 14, 18, 24])}, "at least 3"),
        ({"face_offsets": np.array([0, 5])}, "'face_offsets' ends at 5"),
        ({"centre": np.array([[1.0, 1.0]])}, r"'centre' has shape \(1, 2\)"),
        ({"support": np.full(5, 0.5)}, "'support' has 5 entries"),
        ({"vertices": np.full((8, 3), np.inf)}, "non-finite"),
        ({"mineral": np.array([3])}, "'mineral' has the value 3"),
        ({"domain": "box"}, "not a 3D box"),
        ({"support": np.full(6, 5.0)}, "off its plane"),
        ({"support": np.full(6, -0.5), "normals": -_cube_arrays(0.5)["normals"]}, "support > 0"),
        (
            {"face_vertices": _cube_arrays(0.5)["face_vertices"].reshape(6, 4)[:, ::-1].ravel()},
            "not counter-clockwise",
        ),
        ({"rounding": np.array([0.1])}, "rounded"),
    ],
)
def test_broken_packings_are_refused_naming_the_array(
    change: dict[str, object], message: str
) -> None:
    with pytest.raises(PackingError, match=message):
        cube_packing([[1, 1, 1]], **change)


def _rewrite(path, edit) -> None:  # type: ignore[no-untyped-def]
    with np.load(path, allow_pickle=False) as npz:
        contents = {k: npz[k] for k in npz.files}
    edit(contents)
    np.savez(path, **contents)


def test_a_damaged_3d_file_is_refused_naming_the_file(tmp_path) -> None:
    path = tmp_path / "p.npz"
    save(cube_packing([[1, 1, 1]]), path)

    def bad_domain(contents: dict[str, np.ndarray]) -> None:
        meta = json.loads(str(contents["meta"]))
        meta["domain"] = {"kind": "box", "bounds": [0, 1, 0, 1, 1, 0]}
        contents["meta"] = np.array(json.dumps(meta))

    _rewrite(path, bad_domain)
    with pytest.raises(PackingFileError, match=r"p\.npz: invalid packing file: meta 'domain'"):
        load(path)

    save(cube_packing([[1, 1, 1]]), path)
    _rewrite(path, lambda c: c.pop("normals"))
    with pytest.raises(PackingFileError, match="missing array 'normals'"):
        load(path)
    path.write_bytes(b"not a zip")
    assert not zipfile.is_zipfile(path)
    with pytest.raises(PackingFileError, match="not an NPZ archive"):
        load(path)


def _set(name: str, value: object):  # type: ignore[no-untyped-def]
    def edit(contents: dict[str, np.ndarray]) -> None:
        contents[name] = np.asarray(value)

    return edit


def _periodic_box(contents: dict[str, np.ndarray]) -> None:
    meta = json.loads(str(contents["meta"]))
    meta["domain"] = {"kind": "periodic-box", "bounds": [0, 10, 0, 10, 0, 10]}
    contents["meta"] = np.array(json.dumps(meta))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            _set("radius", [1.3, 1.0]),
            r"array 'radius' has the value 1\.3 at particle 0, but its solid's volume "
            r"(8|7\.9999\d*) has "
            r"the equivalent radius 1\.2407009817988\d*",
        ),
        (
            _set("rounding", [0.0, 1e300]),
            r"array 'radius' has the value 1\.0 at particle 1, but its solid's volume inf",
        ),
        (
            _set("centre", [[1e17, 3, 3], [7, 3, 3]]),
            r"array 'centre' places particle 0 at \[1\.e\+17 3\.e\+00 3\.e\+00\] .* more "
            r"than the box's largest side \(10\) beyond",
        ),
        (
            lambda c: _periodic_box(c) or _set("centre", [[11, 3, 3], [7, 3, 3]])(c),
            r"array 'centre' places particle 0 at \[11\. 3\. 3\.\], outside the periodic cell",
        ),
    ],
    ids=["radius", "rounding 1e300", "at 1e17", "periodic centre outside"],
)
def test_a_3d_file_whose_numbers_cannot_mean_a_packing_is_refused(tmp_path, edit, message) -> None:
    path = tmp_path / "p.npz"
    save(cube_and_sphere(), path)
    assert load(path).n_placed == 2
    _rewrite(path, edit)
    with pytest.raises(PackingFileError, match=rf"p\.npz: invalid packing file: {message}"):
        load(path)


@pytest.mark.parametrize("factor", [1e-6, 1e6])
def test_a_scaled_3d_file_loads(tmp_path, factor) -> None:
    path = tmp_path / "p.npz"
    p = cube_and_sphere()
    side = 10 * factor
    scaled = {
        "radius": p.radius * factor,
        "vertices": p.vertices * factor,
        "support": p.support * factor,
        "centre": p.centre * factor,
        "rounding": p.rounding * factor,
        "domain": Box(0, side, 0, side, 0, side),
    }
    save(dataclasses.replace(p, **scaled), path)
    assert load(path).n_placed == 2


@pytest.mark.parametrize("bounds", [5, None, 1.5])
def test_a_3d_file_whose_domain_bounds_are_no_list_names_the_field(tmp_path, bounds) -> None:
    path = tmp_path / "p.npz"
    save(cube_packing([[1, 1, 1]]), path)

    def edit(contents: dict[str, np.ndarray]) -> None:
        meta = json.loads(str(contents["meta"]))
        meta["domain"] = {"kind": "box", "bounds": bounds}
        contents["meta"] = np.array(json.dumps(meta))

    _rewrite(path, edit)
    with pytest.raises(PackingFileError) as caught:
        load(path)
    assert str(caught.value) == (
        f"{path}: invalid packing file: meta 'domain' (kind 'box'): "
        f"bounds: {bounds!r} is not a list of numbers"
    )


def test_a_3d_file_whose_domain_names_no_kind_says_so(tmp_path) -> None:
    path = tmp_path / "p.npz"
    save(cube_packing([[1, 1, 1]]), path)

    def edit(contents: dict[str, np.ndarray]) -> None:
        meta = json.loads(str(contents["meta"]))
        meta["domain"].pop("kind")
        contents["meta"] = np.array(json.dumps(meta))

    _rewrite(path, edit)
    with pytest.raises(PackingFileError) as caught:
        load(path)
    assert str(caught.value) == (
        f"{path}: invalid packing file: meta 'domain' (kind None): 'rectangle' is a 2D "
        "domain kind, not 3D; 3D kinds: box, periodic-box, cylinder"
    )
