"""Uniform random rotations from random unit quaternions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from regopack.plugins.shapes.polyhedra.rotations import quaternion_matrices, random_rotations

N = 20_000
P_MIN = 0.01


@pytest.fixture(scope="module")
def rotations() -> np.ndarray:
    return random_rotations(np.random.default_rng(20240611), N)


def test_proper_orthonormal(rotations: np.ndarray) -> None:
    assert rotations.shape == (N, 3, 3)
    assert np.allclose(rotations @ rotations.transpose(0, 2, 1), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(rotations), 1.0, atol=1e-12)


def test_known_quaternions() -> None:
    # a turn by 2 pi / 3 about (1, 1, 1) takes x to y and y to z
    axis = np.ones(3) / np.sqrt(3.0)
    q = np.array([[np.cos(np.pi / 3), *(np.sin(np.pi / 3) * axis)]])
    r = quaternion_matrices(q)[0]
    assert np.allclose(r @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    assert np.allclose(r @ [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], atol=1e-15)
    # q and -q are the same rotation; the norm does not matter
    assert np.allclose(quaternion_matrices(-3.0 * q), r, atol=1e-15)
    assert np.allclose(quaternion_matrices(np.array([[2.0, 0, 0, 0]]))[0], np.eye(3))
    # a turn by pi / 3 about z: the quaternion holds half the angle
    half = np.pi / 6
    r_z = quaternion_matrices(np.array([[np.cos(half), 0, 0, np.sin(half)]]))[0]
    assert np.allclose(r_z @ [1.0, 0.0, 0.0], [np.cos(np.pi / 3), np.sin(np.pi / 3), 0.0])


def test_mean_of_rotated_vectors_vanishes(rotations: np.ndarray) -> None:
    for v in (np.array([0.0, 0.0, 1.0]), np.array([1.0, 2.0, -2.0]) / 3.0):
        mean = (rotations @ v).mean(axis=0)
        # each component of a uniform unit vector has variance 1/3
        assert np.all(np.abs(mean) < 5.0 * np.sqrt(1.0 / (3.0 * N)))
    # the mean rotation matrix of the Haar measure is zero
    assert np.abs(rotations.mean(axis=0)).max() < 5.0 * np.sqrt(1.0 / (3.0 * N))


def test_rotated_axis_is_uniform_on_the_sphere(rotations: np.ndarray) -> None:
    z = rotations[:, :, 2]  # the image of the z axis
    # Archimedes: the height of a uniform point on the sphere is uniform on [-1, 1]
    assert stats.kstest(z[:, 2], "uniform", args=(-1.0, 2.0)).pvalue > P_MIN
    azimuth = np.arctan2(z[:, 1], z[:, 0])
    assert stats.kstest(azimuth, "uniform", args=(-np.pi, 2 * np.pi)).pvalue > P_MIN


def test_rotation_angle_has_the_haar_distribution(rotations: np.ndarray) -> None:
    # the angle of a uniform rotation has density (1 - cos t) / pi on [0, pi]
    angle = np.arccos(np.clip((np.trace(rotations, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
    assert stats.kstest(angle, lambda t: (t - np.sin(t)) / np.pi).pvalue > P_MIN


def test_the_tests_reject_naive_rotations() -> None:
    """Uniform Euler angles are not uniform rotations: the same tests must reject them."""
    rng = np.random.default_rng(7)
    beta = rng.uniform(0, np.pi, N)
    height = np.cos(beta)  # the z axis tilted by a uniform polar angle beta
    assert stats.kstest(height, "uniform", args=(-1.0, 2.0)).pvalue < 1e-6
    # uniform axis-angle pairs neither
    axis = rng.standard_normal((N, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    half = rng.uniform(0, np.pi, N) / 2
    q = np.column_stack([np.cos(half), np.sin(half)[:, None] * axis])
    r = quaternion_matrices(q)
    angle = np.arccos(np.clip((np.trace(r, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
    assert stats.kstest(angle, lambda t: (t - np.sin(t)) / np.pi).pvalue < 1e-6


def test_same_seed_same_rotations() -> None:
    a = random_rotations(np.random.default_rng(3), 100)
    b = random_rotations(np.random.default_rng(3), 100)
    c = random_rotations(np.random.default_rng(4), 100)
    assert np.array_equal(a, b) and not np.allclose(a, c)
