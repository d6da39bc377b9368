"""Fabric tensor of contact normals: isotropic, aligned, and a lattice of cubes."""

from __future__ import annotations

import numpy as np
import pytest
from lattices3d import cube_lattice

from regopack.plugins.analyzers.contacts import Contacts, ContactsConfig
from regopack.plugins.analyzers.network import Network, fabric_tensor


def test_isotropic_normals_give_a_third_of_the_identity() -> None:
    rng = np.random.default_rng(4)
    n = rng.normal(size=(200_000, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    f, dev, a = fabric_tensor(n)
    np.testing.assert_allclose(f, np.eye(3) / 3, atol=3e-3)
    assert np.trace(f) == pytest.approx(1.0) and a < 0.05
    np.testing.assert_allclose(dev, f - np.eye(3) / 3, atol=1e-15)


def test_aligned_and_axisymmetric_normals_have_the_known_anisotropy() -> None:
    f, dev, a = fabric_tensor(np.array([[0, 0, 1.0], [0, 0, -1.0]]))
    np.testing.assert_allclose(f, np.diag([0, 0, 1.0]), atol=1e-15)
    np.testing.assert_allclose(dev, np.diag([-1.0, -1.0, 2.0]) / 3, atol=1e-15)
    assert a == pytest.approx(7.5)
    # E(n) = (1 + a_ij n_i n_j) / (4 pi), a_ij = 0.6 diag(-1, -1, 2) / 3: sample by rejection
    rng = np.random.default_rng(6)
    n = rng.normal(size=(600_000, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    density = 1 + 0.6 * (3 * n[:, 2] ** 2 - 1) / 3
    keep = rng.uniform(0, 1.4, len(n)) < density
    assert fabric_tensor(n[keep])[2] == pytest.approx(0.6, abs=0.02)


def test_the_fabric_of_a_cube_lattice_follows_its_face_contacts() -> None:
    p = cube_lattice((3, 3, 3), (1 / 64, 2 / 64, 3 / 64))
    contacts = Contacts(ContactsConfig(tol=0.02, margin=0.0)).compute(p, {})
    net = Network().compute(p, {"contacts": contacts}).results()
    np.testing.assert_allclose(net["fabric"], np.diag([1.0, 0, 0]), atol=1e-15)
    assert net["anisotropy"] == pytest.approx(7.5) and net["n_edges"] == 18
    assert net["total_contact_area"] == pytest.approx(18 * 1.02**2)
