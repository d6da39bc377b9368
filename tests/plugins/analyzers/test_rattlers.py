"""Rattlers (iterative removal), the mechanical coordination number, Z counts, void ratio."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

from regopack.analysis.pipeline import run_analyses
from regopack.plugins.analyzers import coordination as coordination_module
from regopack.plugins.analyzers import density as density_module
from regopack.plugins.analyzers.coordination import remove_rattlers
from regopack.plugins.analyzers.density import void_ratio
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

pytest.importorskip("regopack.plugins.inserters.available_arc")


def graph(edges, n):
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    return e[:, 0], e[:, 1], np.ones(n, dtype=bool)


def test_a_chain_is_removed_entirely_and_only_iteratively():
    # 0 - 1 - 2 - 3 - 4: only the ends have one contact, then the next ones ...
    i, j, members = graph([(0, 1), (1, 2), (2, 3), (3, 4)], 5)
    rattler, z, rounds = remove_rattlers(i, j, members, 2)
    assert rattler.all()
    assert z.tolist() == [0] * 5
    assert rounds == 3


def test_a_triangle_keeps_its_corners_and_drops_its_tail():
    # triangle 0-1-2, a chain 2-3-4 hanging from corner 2, and an isolated 5
    i, j, members = graph([(0, 1), (1, 2), (2, 0), (2, 3), (3, 4)], 6)
    rattler, z, rounds = remove_rattlers(i, j, members, 2)
    assert np.flatnonzero(rattler).tolist() == [3, 4, 5]
    assert z.tolist() == [2, 2, 2, 0, 0, 0]
    assert rounds == 2  # 4 and 5 first, then 3
    # Z_m: 3 contacts among 3 particles
    assert z[~rattler].mean() == pytest.approx(2.0)


def test_frictionless_threshold_and_the_z0_definition():
    # a square with one diagonal: corners 0, 2 have 3 contacts, 1, 3 have 2
    i, j, members = graph([(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)], 4)
    rattler, _, _ = remove_rattlers(i, j, members, 3)
    assert rattler.all()  # 1 and 3 go, then 0 and 2 have one contact each
    rattler, _, rounds = remove_rattlers(i, j, members, 1)
    assert not rattler.any() and rounds == 0


def test_non_members_take_no_part():
    i, j, members = graph([(0, 1), (1, 2), (2, 0), (2, 3)], 4)
    members[1] = False
    rattler, z, _ = remove_rattlers(i, j, members, 2)
    assert not rattler[1] and z[1] == 0
    assert rattler[[0, 2, 3]].all()


def test_void_ratio():
    assert void_ratio(0.8) == pytest.approx(0.25)
    assert void_ratio(1.0) == 0.0
    assert void_ratio(0.0) is None
    assert void_ratio(float("nan")) is None
    assert void_ratio(None) is None


def test_doctests():
    for module in (coordination_module, density_module):
        assert doctest.testmod(module).failed == 0


@pytest.fixture(scope="module")
def done():
    registry = default_registry(autoload=False)
    packing = run_scene(resolve_scene(load_scene("small", ["count=300"]), registry)).packing
    return packing, run_analyses(packing, registry, [("coordination", {}), ("density", {})])


def test_coordination_reports_rattlers_and_z_mechanical(done):
    packing, analyzers = done
    coord = analyzers["coordination"]
    res = coord.results()
    contacts = analyzers["contacts"]
    placed = packing.placed
    interior = contacts.interior
    z = coord.per_particle
    rattler = coord.rattler
    assert res["rattlers"] == int(rattler.sum()) > 0
    # interior rattlers by the DEM definition: fewer than 2 contacts, removed iteratively
    assert res["rattlers_interior"] == int(rattler[interior].sum())
    assert res["rattlers_interior"] > int(np.sum(interior & (z < 2)))
    assert "rattlers_interior_dem" not in res
    # interior particles without any contact, under their own name
    assert res["isolated_interior"] == int(np.sum(z[interior] == 0))
    assert res["rattlers_interior"] > res["isolated_interior"]
    assert res["rattler_fraction"] == pytest.approx(rattler.sum() / placed.sum())
    # every particle left has at least two contacts with particles left
    zm = coord.z_mechanical
    assert zm[placed & ~rattler].min() >= 2
    again = np.bincount(contacts.i, weights=~rattler[contacts.j], minlength=len(z))
    again += np.bincount(contacts.j, weights=~rattler[contacts.i], minlength=len(z))
    assert np.array_equal(zm[~rattler], again[~rattler])
    assert res["z_mechanical"] == pytest.approx(zm[placed & ~rattler].mean())
    assert res["z_mechanical_interior"] == pytest.approx(zm[interior & ~rattler].mean())
    assert res["z_mechanical_interior"] > res["z_interior"]
    tables = coord.tables()
    counts = tables["z_counts"]
    assert counts["n_interior"].tolist()[: len(res["z_distribution"])] == res["z_distribution"]
    assert counts["n_domain"].sum() == placed.sum()
    assert counts["n_interior_mechanical"].sum() == res["n_mechanical_interior"]
    assert sum(counts[f"n_interior_{m}"].sum() for m in packing.mineral_names) == res["n_interior"]
    assert len(tables["particles"]["rattler"]) == placed.sum()


def test_single_pass_removal_would_miss_rattlers(done):
    """Removing the particles below the threshold once finds fewer rattlers here."""
    packing, analyzers = done
    once = packing.placed & (analyzers["coordination"].per_particle < 2)
    assert analyzers["coordination"].rattler.sum() > once.sum()


def test_density_reports_the_void_ratio(done):
    _, analyzers = done
    res = analyzers["density"].results()
    phi = res["phi_domain"]
    assert res["void_ratio_domain"] == pytest.approx((1 - phi) / phi)
    phi = res["phi_interior"]
    assert res["void_ratio_interior"] == pytest.approx((1 - phi) / phi)
