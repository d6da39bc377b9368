"""The available-surface inserter: touching, overlap-free, contained, reproducible packings."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import regopack
from regopack.errors import ConfigError
from regopack.packing3d import Packing3D
from regopack.verification3d import separating_gap, verify_polyhedra


def scene(**changes: Any) -> dict[str, Any]:
    base: dict[str, Any] = {
        "name": "surface",
        "seed": 3,
        "count": 60,
        "domain": {"kind": "box", "width": 30.0, "height": 30.0, "depth": 30.0},
        "size": {"kind": "uniform", "d_min": 3.0, "d_max": 8.0},
        "phases": [
            {"name": "pyroxene", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 0.25}},
            {"name": "ilmenite", "fraction": 0.5, "shape": {"kind": "polyhedron", "psi": 15.0}},
        ],
        "insertion": {"kind": "available-surface"},
        "density": {"kind": "eta"},
    }
    base.update(changes)
    return base


def _pack(data: dict[str, Any]) -> Packing3D:
    packing = regopack.pack(data, verify=False)
    assert isinstance(packing, Packing3D)
    return packing


def _check(packing: Packing3D) -> None:
    """Overlap-free and inside the box (the oracle), and each particle touches an earlier one."""
    order = packing.placed_in_order()
    solids = [packing.world_vertices(int(j)) for j in order]
    box = packing.domain
    report = verify_polyhedra(
        solids, None, [box.xmin, box.ymin, box.zmin], [box.xmax, box.ymax, box.zmax]
    )
    assert report.ok, str(report)
    size = float(np.cbrt(packing.solids.volume.min()))
    centre = packing.centre[order]
    radius = packing.solids.circumradius[order]
    for a in range(1, len(order)):
        # only particles whose circumspheres meet can touch
        reach = (
            np.linalg.norm(centre[:a] - centre[a], axis=1) <= (radius[:a] + radius[a]) * 1.000001
        )
        gaps = [separating_gap(solids[a], solids[b]) for b in np.flatnonzero(reach)]
        assert min(gaps) == pytest.approx(0.0, abs=1e-8 * size)  # touches its candidate


def test_a_box_of_polyhedra_is_touching_and_overlap_free() -> None:
    packing = _pack(scene())
    assert packing.n_placed >= 50
    _check(packing)
    assert packing.stats["candidate_analyses"] >= packing.n_placed - 1


def test_same_scene_and_seed_give_the_same_packing() -> None:
    a, b = _pack(scene(count=30)), _pack(scene(count=30))
    assert np.array_equal(a.centre, b.centre, equal_nan=True)
    assert np.array_equal(a.insertion_index, b.insertion_index)
    c = _pack(scene(count=30, seed=4))
    assert not np.array_equal(a.centre, c.centre, equal_nan=True)


def test_the_first_particle_sits_at_the_centre_and_too_large_ones_are_refused() -> None:
    packing = _pack(
        scene(
            count=8,
            size={"kind": "uniform", "d_min": 3.0, "d_max": 60.0},
            domain={"kind": "box", "width": 40.0, "height": 40.0, "depth": 40.0},
        )
    )
    first = packing.placed_in_order()[0]
    assert packing.centre[first].tolist() == [0.0, 0.0, 0.0]
    too_big = packing.solids.circumradius > 40.0
    assert not packing.placed[too_big].any()


@settings(max_examples=6, deadline=None)
@given(
    psi=st.sampled_from([0.01, 1.0, 1000.0]),
    a=st.sampled_from([0.05, 1.0]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    ratio=st.sampled_from([1.5, 30.0]),
)
def test_extremes_stay_overlap_free(psi: float, a: float, scale: float, ratio: float) -> None:
    d_max = 4.0 * scale
    data = scene(
        count=14,
        domain={"kind": "box", "width": 12 * d_max, "height": 12 * d_max, "depth": 12 * d_max},
        size={"kind": "uniform", "d_min": d_max / ratio, "d_max": d_max},
        phases=[
            {"name": "a", "fraction": 1.0, "shape": {"kind": "polyhedron", "psi": psi, "a": a}}
        ],
    )
    _check(_pack(data))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (
            {"domain": {"kind": "periodic-box", "width": 30.0, "height": 30.0, "depth": 30.0}},
            "walled boxes only",
        ),
        (
            {"phases": [{"name": "g", "fraction": 1.0, "shape": {"kind": "sphere"}}]},
            "sharp polyhedra only",
        ),
        ({"density": {"kind": "eta", "eta": 5.0}}, "eta = 0 only"),
    ],
)
def test_what_it_does_not_pack_yet_is_refused_in_one_line(
    changes: dict[str, Any], message: str
) -> None:
    with pytest.raises(ConfigError, match=message) as err:
        regopack.pack(scene(count=5, **changes))
    assert "\n" not in str(err.value)
