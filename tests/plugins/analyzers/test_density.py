"""Volume fraction of 3D packings over the box and an interior window cutting the solids."""

from __future__ import annotations

import numpy as np
import pytest
from lattices3d import cube_lattice

from regopack.plugins.analyzers.common import solid_volumes
from regopack.plugins.analyzers.density import Density, DensityConfig


def test_a_window_through_a_cube_lattice_has_the_volume_of_its_box_intersections() -> None:
    p = cube_lattice((3, 3, 3), (1 / 64, 2 / 64, 3 / 64))
    r = Density(DensityConfig(margin=1.2)).compute(p, {}).results()
    lo = np.array([p.domain.xmin, p.domain.ymin, p.domain.zmin]) + 1.2
    hi = np.array([p.domain.xmax, p.domain.ymax, p.domain.zmax]) - 1.2
    inside = 0.0
    for c in p.centre:  # each cube clipped to the window: a box
        inside += np.prod(np.clip(np.minimum(c + 0.5, hi) - np.maximum(c - 0.5, lo), 0, None))
    assert r["phi_interior"] == pytest.approx(inside / np.prod(hi - lo), rel=1e-12)
    assert r["phi_domain"] == pytest.approx(27 / p.domain.volume, rel=1e-12)
    assert r["void_ratio_domain"] == pytest.approx((1 - r["phi_domain"]) / r["phi_domain"])
    assert r["window"] == pytest.approx(list(hi - lo))


def test_the_volumes_of_all_solids_at_once_match_their_hulls(packing3d) -> None:
    from scipy.spatial import ConvexHull

    volume = solid_volumes(packing3d)
    np.testing.assert_allclose(volume, packing3d.solids.volume, rtol=1e-12)
    for k in range(0, packing3d.n_particles, 17):
        hull = ConvexHull(packing3d.vertices[packing3d.offsets[k] : packing3d.offsets[k + 1]])
        assert volume[k] == pytest.approx(hull.volume, rel=1e-12)


def test_a_periodic_box_is_interior_throughout() -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    p = cube_lattice((2, 2, 2), (0.0, 0.0, 0.0))
    periodic = dataclasses.replace(p, domain=PeriodicBox(*p.domain.bounds()))
    r = Density().compute(periodic, {}).results()
    assert r["phi_interior"] == r["phi_domain"] == pytest.approx(8 / p.domain.volume)
