"""Homogeneity of 3D packings: a uniform lattice has the same fraction in every region."""

from __future__ import annotations

import numpy as np
import pytest
from lattices3d import cube_lattice

from regopack.plugins.analyzers.homogeneity3d import Homogeneity3D, Homogeneity3DConfig


def test_layers_and_shells_add_up_to_the_window(packing3d) -> None:
    from regopack.packing.solid_fraction import phi_in_box

    h = Homogeneity3D(Homogeneity3DConfig(layers=4, shells=3)).compute(packing3d, {})
    window = packing3d.domain.interior(6.0)  # the scene's d_max
    phi = phi_in_box(packing3d, window)
    # equal layers: the window's fraction is their mean; shells: their volume-weighted mean
    assert np.mean(h.layers["phi"]) == pytest.approx(phi, rel=1e-12)
    steps = np.array([0, 1, 2, 3]) / 3
    weights = np.diff(steps**3)
    assert np.average(h.shells["phi"], weights=weights) == pytest.approx(phi, rel=1e-12)
    inside = window.contains(packing3d.centre)
    assert h.layers["n"].sum() == h.shells["n"].sum() == inside.sum()


def test_a_lattice_of_cubes_is_homogeneous_layer_by_layer() -> None:
    # 4 x 4 x 6 touching unit cubes, the window cutting through none: every layer holds
    # 16 cubes in a 4 x 4 x 1 slab
    p = cube_lattice((4, 4, 6), (0.0, 0.0, 0.0))
    h = Homogeneity3D(Homogeneity3DConfig(layers=6, shells=1, margin=0.5)).compute(p, {})
    np.testing.assert_allclose(h.layers["phi"], 1.0, rtol=1e-12)
    np.testing.assert_array_equal(h.layers["n"], 16)
    r = h.results()
    assert r["phi_layers_cv"] == pytest.approx(0.0, abs=1e-12)
    assert r["mean_diameter_layers"] == pytest.approx([2 * p.radius[0]] * 6)


def test_a_periodic_cell_counts_the_solids_that_cross_its_faces_in_their_images() -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    # 4 x 4 x 4 touching unit cubes in a cell shifted by half a cube: every cube crosses
    # faces of the cell, and its images fill every layer and shell to phi = 1
    p = cube_lattice((4, 4, 4), (0.0, 0.0, 0.0))
    lo = p.centre.min(axis=0)
    cell = dataclasses.replace(p, domain=PeriodicBox(*(v for a in lo for v in (a, a + 4.0))))
    h = Homogeneity3D(Homogeneity3DConfig(layers=4, shells=2)).compute(cell, {})
    np.testing.assert_allclose(h.layers["phi"], 1.0, rtol=1e-12)
    np.testing.assert_allclose(h.shells["phi"], 1.0, rtol=1e-12)
    np.testing.assert_array_equal(h.layers["n"], 16)
