from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
import shapely

import regopack
from regopack.base.errors import PackingFileError
from regopack.geometry.domain import Rectangle
from regopack.geometry.population import Population, ShapeBatch
from regopack.packing.core import (
    FORMAT_VERSION_3D,
    Packing,
    load,
    save,
    write_json_atomic,
)
from regopack.registry.interfaces import InsertionResult
from regopack.testing import packing_from_polygons


def random_packing(n: int = 50, seed: int = 0) -> Packing:
    """Random (overlapping, it does not matter here) particles with 3 to 8 vertices.

    Each is a convex polygon inscribed in a circle around its centre (the
    gaps between its corners' angles below pi), its radius the equivalent
    radius of its area, as a file requires.
    """
    rng = np.random.default_rng(seed)
    counts = rng.integers(3, 9, size=n)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    verts = []
    radius = np.empty(n)
    for j, k in enumerate(counts):
        ang = (np.arange(k) + rng.uniform(0, 0.4, size=k)) * (2 * np.pi / k)
        r = rng.uniform(0.5, 1.5)
        v = np.c_[r * np.cos(ang), r * np.sin(ang)]
        verts.append(v)
        area = 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
        radius[j] = np.sqrt(area / np.pi)
    placed = rng.random(n) < 0.8
    centre = np.where(placed[:, None], rng.uniform(-10, 10, size=(n, 2)), np.nan)
    order = np.full(n, -1, dtype=np.int64)
    order[placed] = rng.permutation(int(placed.sum()))
    return Packing(
        radius=radius,
        mineral=rng.integers(0, 3, size=n).astype(np.int64),
        mineral_names=("a", "b", "c"),
        vertices=np.concatenate(verts),
        offsets=offsets,
        orientation=rng.uniform(0, np.pi, size=n),
        centre=centre,
        insertion_index=order,
        domain=Rectangle(-12.0, 12.0, -11.0, 11.0),
        scene={"name": "random", "notes": [{"name": "a", "shape": {"kind": "x"}}], "x": 0.1},
        seed=seed,
        version="9.9.9",
        stats={"tries": 12.0, "nan": float("nan")},
    )


ARRAYS = ("radius", "mineral", "vertices", "offsets", "orientation", "centre", "insertion_index")


def assert_identical(a: Packing, b: Packing) -> None:
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype, name
        assert x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name
    assert a.mineral_names == b.mineral_names
    assert a.domain == b.domain
    assert a.scene == b.scene
    assert a.seed == b.seed
    assert a.version == b.version
    assert a.stats.keys() == b.stats.keys()
    for k in a.stats:
        assert a.stats[k] == b.stats[k] or (np.isnan(a.stats[k]) and np.isnan(b.stats[k]))


# -- the object ------------------------------------------------------------------


def test_counts_and_order():
    p = random_packing()
    assert p.n_particles == 50
    assert p.n_placed == int(p.placed.sum())
    assert len(p.not_placed) == p.n_particles - p.n_placed
    assert np.all(np.isnan(p.centre[p.not_placed]))
    order = p.placed_in_order()
    assert p.insertion_index[order].tolist() == list(range(p.n_placed))


def test_area_matches_shapely_and_is_positive():
    p = random_packing()
    idx = np.flatnonzero(p.placed)
    np.testing.assert_allclose(p.area()[idx], shapely.area(p.to_shapely()), rtol=1e-12)
    assert np.all(p.area() > 0)


def test_circumradius():
    p = random_packing()
    for j in range(p.n_particles):
        v = p.vertices[p.offsets[j] : p.offsets[j + 1]]
        assert p.circumradius[j] == np.max(np.hypot(v[:, 0], v[:, 1]))


def test_polygons_and_polygon_agree():
    p = random_packing()
    polys = p.polygons()
    idx = np.flatnonzero(p.placed)
    assert len(polys) == len(idx)
    for j, poly in zip(idx, polys, strict=True):
        np.testing.assert_array_equal(poly, p.polygon(j))
    sel = p.polygons([idx[3], idx[0]])
    np.testing.assert_array_equal(sel[0], p.polygon(idx[3]))
    assert p.polygons([]) == []
    assert len(p.to_shapely([])) == 0


def test_to_shapely_vertices():
    sq = [(0, 0), (2, 0), (2, 2), (0, 2)]
    p = packing_from_polygons([sq])
    g = p.to_shapely()[0]
    assert g.area == 4.0
    assert shapely.get_num_coordinates(g) == 5


def test_from_parts():
    n = 3
    verts = np.tile([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]], (n, 1))
    shapes = ShapeBatch(verts, np.arange(0, 3 * n + 1, 3, dtype=np.int64), np.zeros(n))
    pop = Population(np.ones(n), np.array([0, 1, 0], dtype=np.int64), ("x", "y"), shapes)
    result = InsertionResult(
        np.array([[0.0, 0.0], [np.nan, np.nan], [5.0, 5.0]]),
        np.array([0, -1, 1], dtype=np.int64),
        {"tries": 4.0},
    )
    dom = Rectangle(-10, 10, -10, 10)
    p = Packing.from_parts(pop, result, dom, {"name": "s"}, 7, {"extra": 1.0})
    assert p.n_placed == 2
    assert p.mineral_names == ("x", "y")
    assert p.seed == 7
    assert p.version == regopack.__version__
    assert p.stats == {"extra": 1.0}
    assert Packing.from_parts(pop, result, dom, {}, 7).stats == {"tries": 4.0}


def test_empty_packing(tmp_path):
    p = packing_from_polygons([], domain=(0, 1, 0, 1))
    assert p.n_particles == 0
    assert p.area().shape == (0,)
    save(p, tmp_path / "e.npz")
    assert_identical(p, load(tmp_path / "e.npz"))


# -- files --------------------------------------------------------------------------


def test_save_load_round_trip_is_bit_identical(tmp_path):
    p = random_packing()
    path = tmp_path / "p.npz"
    save(p, path)
    q = load(path)
    assert_identical(p, q)
    save(q, tmp_path / "q.npz")
    assert_identical(p, load(tmp_path / "q.npz"))
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".")] == []


def test_load_accepts_str_and_is_exported(tmp_path):
    p = random_packing(5)
    save(p, str(tmp_path / "p.npz"))
    assert_identical(p, regopack.load(str(tmp_path / "p.npz")))
    regopack.save(p, tmp_path / "q.npz")
    assert_identical(p, load(tmp_path / "q.npz"))


def test_save_keeps_the_name(tmp_path):
    save(random_packing(3), tmp_path / "packing.data")
    assert (tmp_path / "packing.data").exists()
    assert not (tmp_path / "packing.data.npz").exists()


def test_meta_entry(tmp_path):
    p = random_packing(4)
    save(p, tmp_path / "p.npz")
    with np.load(tmp_path / "p.npz", allow_pickle=False) as npz:
        meta = json.loads(str(npz["meta"]))
        assert sorted(npz.files) == sorted([*ARRAYS, "meta"])
    assert meta["format"] == "regopack-packing"
    assert meta["format_version"] == 1  # a walled rectangle fits the first version
    assert meta["domain"] == {"kind": "rectangle", "bounds": [-12.0, 12.0, -11.0, 11.0]}
    assert meta["mineral_names"] == ["a", "b", "c"]


def test_temporaries_of_a_killed_save_are_removed_by_the_next(tmp_path):
    stale = [".p.npz.abcd_123.tmp", ".p.npz.0a1b2c3d.tmp"]
    others = [".q.npz.abcd1234.tmp", ".p.npz.short.tmp", "p.npz.abcd1234.tmp"]
    for name in stale + others:
        (tmp_path / name).write_bytes(b"what a SIGKILL left")
    save(random_packing(3), tmp_path / "p.npz")
    assert sorted(f.name for f in tmp_path.iterdir()) == sorted(["p.npz", *others])


def test_interrupted_save_keeps_previous_file(tmp_path, monkeypatch):
    path = tmp_path / "p.npz"
    save(random_packing(seed=1), path)
    before = path.read_bytes()

    def boom(*args, **kwargs):
        args[0].write(b"partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", boom)
    with pytest.raises(KeyboardInterrupt):
        save(random_packing(seed=2), path)
    assert path.read_bytes() == before
    assert sorted(f.name for f in tmp_path.iterdir()) == ["p.npz"]


def test_load_missing_file(tmp_path):
    with pytest.raises(PackingFileError, match="no such file"):
        load(tmp_path / "missing.npz")


def test_load_directory(tmp_path):
    with pytest.raises(PackingFileError, match="is a directory"):
        load(tmp_path)


@pytest.mark.parametrize(
    "content",
    [b"", b"not a zip file at all", b"PK\x03\x04garbage" * 10],
)
def test_load_corrupt_file(tmp_path, content):
    path = tmp_path / "bad.npz"
    path.write_bytes(content)
    with pytest.raises(PackingFileError) as info:
        load(path)
    assert "not a regopack packing file" in str(info.value)
    assert "\n" not in str(info.value)


def test_load_truncated_file(tmp_path):
    path = tmp_path / "p.npz"
    save(random_packing(), path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(PackingFileError, match="not a regopack packing file"):
        load(path)


def test_load_foreign_npz(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.arange(3))
    with pytest.raises(PackingFileError, match="no 'meta' entry"):
        load(tmp_path / "x.npz")
    np.savez(tmp_path / "y.npz", meta=np.array(json.dumps({"format": "other"})))
    with pytest.raises(PackingFileError, match="does not identify"):
        load(tmp_path / "y.npz")
    np.savez(tmp_path / "z.npz", meta=np.array("{"))
    with pytest.raises(PackingFileError, match="unreadable"):
        load(tmp_path / "z.npz")


def rewrite(path: Path, change) -> None:
    with np.load(path, allow_pickle=False) as npz:
        contents = {k: npz[k] for k in npz.files}
    change(contents)
    np.savez(path, **contents)


def test_load_newer_format_version(tmp_path):
    path = tmp_path / "p.npz"
    save(random_packing(), path)

    def bump(contents):
        meta = json.loads(str(contents["meta"]))
        meta["format_version"] = FORMAT_VERSION_3D + 1
        contents["meta"] = np.array(json.dumps(meta))

    rewrite(path, bump)
    newer = FORMAT_VERSION_3D + 1
    with pytest.raises(PackingFileError, match=rf"format version {newer}.*upgrade"):
        load(path)


def test_load_inconsistent_arrays(tmp_path):
    path = tmp_path / "p.npz"
    save(random_packing(), path)
    rewrite(path, lambda c: c.update(offsets=c["offsets"][:-1]))
    with pytest.raises(PackingFileError, match=r"array 'offsets' has 50 entries, expected n \+ 1"):
        load(path)
    save(random_packing(), path)
    rewrite(path, lambda c: c.pop("centre"))
    with pytest.raises(PackingFileError, match="missing array 'centre'"):
        load(path)


def test_load_refuses_pickles(tmp_path):
    path = tmp_path / "p.npz"
    save(random_packing(), path)
    rewrite(path, lambda c: c.update(radius=np.array([object()], dtype=object)))
    with pytest.raises(PackingFileError):
        load(path)


def test_npz_is_a_zip(tmp_path):
    save(random_packing(3), tmp_path / "p.npz")
    assert zipfile.is_zipfile(tmp_path / "p.npz")


def test_write_json_atomic(tmp_path):
    path = tmp_path / "s.json"
    write_json_atomic(path, {"a": np.float64(1.5), "b": float("nan"), "c": [np.int64(2)]})
    assert json.loads(path.read_text()) == {"a": 1.5, "b": None, "c": [2]}
    write_json_atomic(path, {"a": 2})
    assert json.loads(path.read_text()) == {"a": 2}
    assert sorted(f.name for f in tmp_path.iterdir()) == ["s.json"]


def test_saved_files_get_the_usual_permissions(tmp_path):
    import os
    import stat

    path = tmp_path / "p.npz"
    save(random_packing(), path)
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
    write_json_atomic(tmp_path / "s.json", {"a": 1})
    assert stat.S_IMODE((tmp_path / "s.json").stat().st_mode) == 0o666 & ~umask


def test_load_a_plain_npy_file_says_what_it_is(tmp_path):
    path = tmp_path / "x.npy"
    np.save(path, np.arange(3))
    with pytest.raises(PackingFileError, match="not an NPZ archive"):
        load(path)
