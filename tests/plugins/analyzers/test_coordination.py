"""Coordination numbers of 3D packings: a lattice of cubes with known Z(tol), and rattlers."""

from __future__ import annotations

import numpy as np
import pytest
from lattices3d import cube_lattice

from regopack.plugins.analyzers.contacts import Contacts, ContactsConfig
from regopack.plugins.analyzers.coordination import Coordination, CoordinationConfig

GAPS = (1 / 64, 2 / 64, 3 / 64)


def _coordination(packing, tol: float, tols: list[float], **kw) -> Coordination:
    contacts = Contacts(ContactsConfig(tol=tol, margin=1.5)).compute(packing, {})
    config = CoordinationConfig(tols=tols, **kw)
    return Coordination(config).compute(packing, {"contacts": contacts})


@pytest.fixture(scope="module")
def lattice():
    return cube_lattice((3, 3, 3), GAPS, minerals=2)


def test_the_centre_of_a_cube_lattice_has_the_known_z_at_every_tolerance(lattice) -> None:
    # faces along x, y, z close at the gaps 1/64, 2/64, 3/64; an edge or a corner closes at
    # the largest gap it spans: 2 contacts, then 2 + 2 + 4 (x, y and the xy edges), then 26
    c = _coordination(lattice, 0.0625, [0.02, 0.04, 0.05])
    r = c.results()
    assert r["n_interior"] == 1  # the margin of 1.5 leaves only the centre cube
    assert r["tol_sweep"] == [0.02, 0.04, 0.05, 0.0625]
    assert r["z_interior_sweep"] == [2.0, 8.0, 26.0, 26.0]
    assert r["z_interior"] == 26.0 and r["z_distribution"] == [0] * 26 + [1]
    # 27 cubes: 54 face, 3 x 24 edge and 32 corner pairs at tol
    assert r["z_domain"] == pytest.approx(2 * (54 + 72 + 32) / 27)
    # two minerals alternate; the centre cube (index 13) is of mineral 1
    assert r["z_per_mineral"] == {"pyroxene": None, "glass": 26.0}
    assert r["n_per_mineral"] == {"pyroxene": 0, "glass": 1}


def test_rattlers_need_two_contacts_in_3d_and_four_when_frictionless(lattice) -> None:
    # at tol 0.02 only the x faces touch: chains of three cubes; with 2 (the default,
    # frictional) the chains' ends go first, and then their middles: none is left
    chains = _coordination(lattice, 0.02, [0.02]).results()
    assert chains["rattler_min_contacts"] == 2
    assert chains["rattlers"] == 27 and chains["z_mechanical"] is None
    # at 0.04 the x and y faces and the xy edges touch: each layer is a 3 x 3 king's graph
    # (corners 3 contacts, sides 5, centre 8): two contacts hold every cube
    frictional = _coordination(lattice, 0.04, [0.04]).results()
    assert frictional["rattlers"] == 0 and frictional["z_mechanical"] == pytest.approx(40 / 9)
    # with 4 (d + 1, frictionless) the corners go, and then the rest, round after round
    layers = _coordination(lattice, 0.04, [0.04], rattler_min_contacts=4).results()
    assert layers["rattlers"] == 27 and layers["rattler_rounds"] == 3
    # with 3 every cube stays: 20 contacts in each layer of 9
    held = _coordination(lattice, 0.04, [0.04], rattler_min_contacts=3).results()
    assert held["rattlers"] == 0 and held["z_mechanical"] == pytest.approx(40 / 9)


def test_the_particle_table_has_3d_columns(packing3d, analysed3d) -> None:
    table = analysed3d["coordination3d"].tables["particles"]
    assert list(table.dtype.names) == [
        "particle", "mineral", "x", "y", "z", "radius", "interior", "contacts", "rattler",
        "contacts_mechanical",
    ]  # fmt: skip
    placed = np.flatnonzero(packing3d.placed)
    np.testing.assert_array_equal(table["particle"], placed)
    np.testing.assert_array_equal(table["z"], packing3d.centre[placed, 2])
    r = analysed3d["coordination3d"]
    assert r["z_interior"] == pytest.approx(table["contacts"][table["interior"] == 1].mean())
    assert sum(r["z_distribution"]) == r["n_interior"] > 10
