"""A tiled packing: the same on any workers, overlap-free across the seams, checked inputs."""

from __future__ import annotations

import copy
import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import regopack
from regopack.base.errors import ConfigError
from regopack.packing.core import Packing
from regopack.verification.polyhedra import verify_polyhedra


def scene(kind: str = "sphere", periodic: bool = False, side: float = 14.0) -> dict[str, Any]:
    """A 28 x 12 x 28 box in tiles of 14: four tiles, four colours."""
    shape: dict[str, Any] = {"kind": kind}
    d_max = 4.0
    if kind == "polyhedron":
        shape["psi"] = 0.6
        d_max = 2.8  # circumradii up to about 2.1: six of them within a tile
    return {
        "name": "tiled",
        "seed": 5,
        "count": "auto",
        "domain": {
            "kind": "periodic-box" if periodic else "box",
            "width": 28.0,
            "height": 12.0,
            "depth": 28.0,
        },
        "size": {"kind": "uniform", "d_min": 1.5, "d_max": d_max},
        "phases": [{"name": "a", "fraction": 1.0, "shape": shape}],
        "insertion": {"kind": "available-surface", "order": "sweep", "closing": "paced"},
        "density": {"kind": "eta"},
        "outputs": {"fabric": False},
        "tiles": {"side": side},
    }


def _arrays(p: Packing) -> dict[str, np.ndarray]:
    s = p.solids
    return {
        "centre": p.centre,
        "index": p.insertion_index,
        "radius": p.radius,
        "vertices": s.vertices,
        "rotation": s.rotation,
    }


def _same(a: Packing, b: Packing) -> None:
    for name, value in _arrays(a).items():
        other = _arrays(b)[name]
        assert value.shape == other.shape, name
        assert np.array_equal(value, other, equal_nan=True), name


def _no_overlap(p: Packing) -> None:
    """The independent oracle: Qhull and HiGHS for polyhedra, distances for spheres."""
    placed = np.flatnonzero(p.placed)
    lo = p.domain.bounds()[0::2]
    hi = p.domain.bounds()[1::2]
    period = (hi - lo) if p.domain.periodic else None
    if p.rounded:
        c = p.centre[placed]
        r = p.rounding_radius[placed]
        d = c[:, None, :] - c[None, :, :]
        if period is not None:
            d -= period * np.round(d / period)
        dist = np.sqrt((d**2).sum(-1))
        np.fill_diagonal(dist, np.inf)
        assert np.all(dist >= (r[:, None] + r[None, :]) * (1 - 1e-9))
        if period is None:
            assert np.all(c - r[:, None] >= lo - 1e-9) and np.all(c + r[:, None] <= hi + 1e-9)
        return
    world = [p.world_vertices(int(j)) for j in placed]
    report = verify_polyhedra(world, None, lo, hi, periodic=period is not None)
    assert report.ok, str(report)


@pytest.fixture(scope="module")
def spheres() -> Packing:
    return regopack.pack(scene(), verify=False)


def test_a_tiled_packing_is_dense_and_touches_across_the_seams(spheres: Packing) -> None:
    s = spheres.stats
    assert s["tiles"] == 4 and s["obstacles"] > 0
    whole = regopack.pack({**scene(), "tiles": None}, verify=False)
    assert spheres.n_placed > 0.95 * whole.n_placed
    assert s["scaffold"] > 0  # dropped from the margins towards later tiles
    _no_overlap(spheres)
    # particles of the later tiles sit against those of the earlier ones: some pairs
    # across the seam x = 0 touch
    c = spheres.centre[spheres.placed]
    r = spheres.rounding_radius[spheres.placed]
    left, right = c[:, 0] < 0, c[:, 0] >= 0
    d = np.linalg.norm(c[left][:, None, :] - c[right][None, :, :], axis=-1)
    gap = d - (r[left][:, None] + r[right][None, :])
    assert np.count_nonzero(gap < 1e-6 * 4.0) > 10


def test_each_tile_keeps_what_lies_in_its_window_or_in_an_earlier_tile() -> None:
    """A tile keeps the particles it placed in its own window or in earlier tiles' windows."""
    from regopack.tiling.executors import InProcess
    from regopack.tiling.run import layout_of, pack_tiled

    resolved = regopack.scene(scene())
    layout = layout_of(resolved)
    tiled = pack_tiled(resolved, resolved.density.build(), InProcess())
    placed = tiled.result.insertion_index >= 0
    owner = layout.owner(tiled.result.centre[placed])
    packer = tiled.tile[placed]
    colour = np.array([t.colour for t in layout.tiles])
    assert np.all((owner == packer) | (colour[owner] < colour[packer]))
    assert np.count_nonzero(owner != packer) > 0  # holes filled across the seams
    assert np.all(np.diff(tiled.tile) >= 0)  # the tiles' particles one tile after another
    # the insertion order runs through the colours
    order = np.argsort(tiled.result.insertion_index[placed])
    assert np.all(np.diff(colour[packer[order]]) >= 0)


def test_the_same_packing_on_two_local_workers(spheres: Packing) -> None:
    two = regopack.pack(scene(), verify=False, workers=2, threads_per_worker=1)
    _same(spheres, two)


def test_polyhedra_tiles_are_the_same_on_two_workers_and_overlap_free() -> None:
    """Polyhedra in a walled box, the tail closing (the paced one's exact refusals are slow)."""
    data = scene("polyhedron")
    data["insertion"]["closing"] = "tail"
    one = regopack.pack(data, verify=False)
    two = regopack.pack(copy.deepcopy(data), verify=False, workers=2)
    _same(one, two)
    _no_overlap(one)
    whole = regopack.pack({**data, "tiles": None}, verify=False)
    assert one.phi > 0.9 * whole.phi


def test_periodic_spheres_meet_their_images_across_the_box_seam() -> None:
    p = regopack.pack(scene(periodic=True), verify=False)
    _no_overlap(p)
    whole = regopack.pack({**scene(periodic=True), "tiles": None}, verify=False)
    assert p.phi > 0.9 * whole.phi


def test_the_same_packing_on_a_dask_cluster(spheres: Packing) -> None:
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        on_dask = regopack.pack(scene(), verify=False, client=client)
    _same(spheres, on_dask)


def test_tiles_narrower_than_two_particles_are_refused() -> None:
    with pytest.raises(ConfigError, match=r"tiles\.side = 3: .* narrower than two margins"):
        regopack.pack(scene(side=3.0), verify=False)


def test_workers_without_tiles_are_refused_in_one_line() -> None:
    with pytest.raises(ConfigError, match="give it tiles") as err:
        regopack.pack({**scene(), "tiles": None}, verify=False, workers=2)
    assert "\n" not in str(err.value)


def test_a_domain_without_tiles_is_refused() -> None:
    data = scene()
    data["domain"] = {"kind": "cylinder", "radius": 14.0, "height": 12.0}
    with pytest.raises(ConfigError, match="domain kind 'cylinder' is not tiled"):
        regopack.pack(data, verify=False)


def test_progress_is_reported_tile_by_tile() -> None:
    calls: list[tuple[int, int, int]] = []
    p = regopack.pack(scene(), verify=False, progress=lambda *a: calls.append(a))
    tiles = [c for c in calls if c[0] > 0]
    assert len(tiles) >= 4  # one report per tile at least
    done, placed, total = tiles[-1]
    assert done == total and placed == p.n_placed
    assert all(a[0] <= b[0] for a, b in itertools.pairwise(tiles))


@pytest.mark.parametrize(
    ("insertion", "says"),
    [
        ({"order": "paper"}, "insertion.order = 'paper': a tiled scene is packed in the sweep"),
        ({"lag": "pilot"}, "insertion.lag = 'pilot' is not available in tiles"),
    ],
)
def test_settings_a_tile_cannot_pack_are_refused_before_drawing(
    insertion: dict[str, str], says: str
) -> None:
    data = scene()
    data["insertion"] = {**data["insertion"], **insertion}
    with pytest.raises(ConfigError, match=says) as err:
        regopack.pack(data, verify=False, workers=2)
    assert "\n" not in str(err.value) and str(err.value).startswith("tiles.side = 14: ")


@pytest.mark.parametrize("seed", [4, 10, 51])
def test_rare_giants_are_within_the_reach_that_chose_the_obstacles(
    tmp_path: Path, seed: int
) -> None:
    """The reach is measured on every particle the tiles pack, their margins' share too."""
    sizes = tmp_path / "bimodal.csv"
    # 99.86 % of diameters 1.0-1.2, 0.14 % giants of 5.0-5.5 (by number)
    sizes.write_text("1.0, 0\n1.2, 99.86\n5.0, 99.86\n5.5, 100\n", encoding="utf-8")
    data = scene()
    data["size"] = {"kind": "tabulated", "path": str(sizes), "basis": "number"}
    data["domain"] = {"kind": "box", "width": 68.0, "height": 8.0, "depth": 68.0}
    data["count"] = 500
    data["seed"] = seed
    data["tiles"] = {"side": 17.0}
    p = regopack.pack(data, verify=False)
    assert p.stats["tiles"] == 16
    assert p.stats["tile_reach"] >= float(np.max(p.rounding_radius))
    _no_overlap(p)


@pytest.mark.parametrize("count", [1, 4, 20, 100])
def test_a_sparse_tiled_scene_keeps_what_it_draws(count: int) -> None:
    """Each tile starts below the middle of its own window, not in a neighbour's."""
    data = {**scene(), "count": count}
    p = regopack.pack(data, verify=False)
    whole = regopack.pack({**data, "tiles": None}, verify=False)
    assert p.n_placed >= 0.9 * min(count, whole.n_placed)


def _kernel_threads(_: int) -> int:
    import numba

    return int(numba.get_num_threads())


def test_local_workers_run_the_threads_asked_for() -> None:
    from regopack.tiling.executors import LocalProcesses

    with LocalProcesses(2, threads=1) as local:
        assert local.map(_kernel_threads, [0, 1]) == [1, 1]


def test_strips_need_their_width_along_the_cut_axis_only() -> None:
    """Strips 14 wide across a depth of 10: the uncut depth is no tile's width."""
    data = scene()
    data["domain"] = {"kind": "box", "width": 28.0, "height": 12.0, "depth": 10.0}
    data["tiles"] = {"side": [14.0, 10.0]}
    p = regopack.pack(data, verify=False)
    assert p.stats["tiles"] == 2
    _no_overlap(p)


@pytest.mark.parametrize(
    ("options", "says"),
    [
        ({"workers": 1.5}, "workers 1.5: give a whole number of workers"),
        ({"workers": "2"}, "workers '2': give a whole number of workers"),
        ({"threads_per_worker": 0}, "threads_per_worker 0: give a whole number of threads"),
    ],
)
def test_bad_worker_options_are_refused_in_one_line(options: dict[str, Any], says: str) -> None:
    with pytest.raises(ConfigError, match=says) as err:
        regopack.pack(scene(), verify=False, **options)
    assert "\n" not in str(err.value)


def test_threads_per_worker_without_tiles_is_refused() -> None:
    with pytest.raises(ConfigError, match="threads_per_worker 2: the scene is packed as one task"):
        regopack.pack({**scene(), "tiles": None}, verify=False, threads_per_worker=2)
