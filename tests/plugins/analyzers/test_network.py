"""Fabric tensor of contact normals: isotropic, aligned, and a lattice of cubes."""

from __future__ import annotations

import numpy as np
import pytest
from lattices3d import cube_lattice

from regopack.plugins.analyzers.contacts import Contacts, ContactsConfig
from regopack.plugins.analyzers.network import (
    Network,
    NetworkConfig,
    anisotropy_of,
    block_jackknife,
    block_of,
    fabric_tensor,
    principal_direction,
)


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


def _normals_2d(rng: np.random.Generator, n: int, b: float) -> np.ndarray:
    """``n`` 2D unit normals with the density ``1 + b cos 2(θ - 90°)``: anisotropy ``b``."""
    out: list[np.ndarray] = []
    while sum(len(o) for o in out) < n:
        t = rng.uniform(0, np.pi, 4 * n)
        out.append(t[rng.uniform(0, 1 + b, t.size) < 1 + b * np.cos(2 * (t - np.pi / 2))])
    t = np.concatenate(out)[:n]
    return np.c_[np.cos(t), np.sin(t)]


def test_anisotropy_and_direction_of_known_fabrics() -> None:
    assert anisotropy_of(np.diag([0.6, 0.4])) == pytest.approx(0.4)
    assert anisotropy_of(np.diag([0.0, 1.0])) == pytest.approx(2.0)
    assert anisotropy_of(np.diag([0.0, 0.0, 1.0])) == pytest.approx(7.5)
    assert principal_direction(np.diag([0.3, 0.7])) == [0.0, 1.0]
    assert principal_direction(np.diag([0.2, 0.2, 0.6])) == [0.0, 0.0, 1.0]
    d = principal_direction(np.array([[0.5, -0.4], [-0.4, 0.5]]))
    np.testing.assert_allclose(d, [np.sqrt(0.5), -np.sqrt(0.5)])


def test_blocks_are_an_equal_grid_over_the_bounds() -> None:
    bounds = np.array([0.0, 4.0, 10.0, 12.0])
    pts = np.array([[0.5, 10.1], [3.9, 10.1], [0.5, 11.9], [3.9, 11.9], [-5.0, 99.0]])
    assert block_of(pts, bounds, 2).tolist() == [0, 2, 1, 3, 1]
    cube = np.array([0.0, 1.0] * 3)
    assert block_of(np.array([[0.9, 0.1, 0.9]]), cube, 2).tolist() == [5]


def test_the_jackknife_treats_contacts_of_one_block_as_one_sample() -> None:
    """Copies of contacts in their own block (correlated contacts) do not shrink the error."""
    rng = np.random.default_rng(8)
    n = _normals_2d(rng, 3000, 0.2)
    block = block_of(rng.uniform(0, 1, (3000, 2)), np.array([0, 1, 0, 1.0]), 4)
    error, used = block_jackknife(n, block)
    assert used == 16 and error is not None and 0.01 < error < 0.05
    copied, _ = block_jackknife(np.repeat(n, 5, axis=0), np.repeat(block, 5))
    assert copied == pytest.approx(error, rel=1e-9)
    assert block_jackknife(n, np.zeros(3000, dtype=np.int64)) == (None, 1)
    assert block_jackknife(np.zeros((0, 2)), np.zeros(0, dtype=np.int64)) == (None, 0)


def test_the_jackknife_error_is_the_spread_of_independent_samples() -> None:
    rng = np.random.default_rng(3)
    found, errors = [], []
    for _ in range(200):
        n = _normals_2d(rng, 2000, 0.2)
        found.append(anisotropy_of(n.T @ n / len(n)))
        block = block_of(rng.uniform(0, 1, (2000, 2)), np.array([0, 1, 0, 1.0]), 4)
        errors.append(block_jackknife(n, block)[0])
    assert np.mean(found) == pytest.approx(0.2, abs=0.01)
    assert np.mean(errors) == pytest.approx(np.std(found), rel=0.2)


def test_the_network_reports_the_error_and_direction(packing3d) -> None:  # type: ignore[no-untyped-def]
    contacts = Contacts().compute(packing3d, {})
    net = Network().compute(packing3d, {"contacts": contacts}).results()
    assert net["error_blocks"] == 8 and net["n_fabric_contacts"] > 0
    assert 0 < net["anisotropy_error"] < net["anisotropy"] + 1.0
    assert np.linalg.norm(net["principal_direction"]) == pytest.approx(1.0)
    finer = Network(NetworkConfig(blocks=3)).compute(packing3d, {"contacts": contacts}).results()
    assert finer["anisotropy"] == net["anisotropy"]
    assert finer["error_blocks"] > 8 and finer["anisotropy_error"] != net["anisotropy_error"]
