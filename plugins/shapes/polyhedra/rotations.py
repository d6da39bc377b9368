"""Uniformly random rotations of space, from random unit quaternions.

Four independent standard normal numbers, divided by their norm, give a point
uniformly distributed on the unit sphere S³ in R⁴ (the normal distribution is
isotropic). Unit quaternions cover the rotation group SO(3) twice (``q`` and
``-q`` give the same rotation), and the uniform measure on S³ maps to the
uniform (Haar) measure on SO(3), so the rotation matrix of such a quaternion
is a uniformly random rotation.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = ["quaternion_matrices", "random_rotations"]


def quaternion_matrices(q: FloatArray) -> FloatArray:
    """Rotation matrices of quaternions ``(w, x, y, z)``, normalised first.

    Parameters
    ----------
    q
        ``(n, 4)`` quaternions with non-zero norm; ``w`` is the scalar part.

    Returns
    -------
    ndarray
        ``(n, 3, 3)`` proper rotation matrices ``R``; a vector ``v`` turns
        into ``R @ v``.

    Examples
    --------
    >>> r = quaternion_matrices(np.array([[np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]]))
    >>> np.round(r[0] @ [1.0, 0.0, 0.0], 12) + 0.0  # a quarter turn about z
    array([0., 1., 0.])
    """
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=1)[:, None]
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.empty((q.shape[0], 3, 3))
    r[:, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    r[:, 0, 1] = 2.0 * (x * y - w * z)
    r[:, 0, 2] = 2.0 * (x * z + w * y)
    r[:, 1, 0] = 2.0 * (x * y + w * z)
    r[:, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    r[:, 1, 2] = 2.0 * (y * z - w * x)
    r[:, 2, 0] = 2.0 * (x * z - w * y)
    r[:, 2, 1] = 2.0 * (y * z + w * x)
    r[:, 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return r


def random_rotations(rng: np.random.Generator, n: int) -> FloatArray:
    """Draw ``n`` rotations uniformly distributed on SO(3).

    Draws one ``(n, 4)`` array of standard normal numbers from ``rng`` (in one
    call, so the stream used does not depend on how it is consumed) and turns
    each row into the rotation of the unit quaternion along it.

    Parameters
    ----------
    rng
        The random generator.
    n
        Number of rotations.

    Returns
    -------
    ndarray
        ``(n, 3, 3)`` rotation matrices.

    Examples
    --------
    >>> r = random_rotations(np.random.default_rng(0), 2)
    >>> r.shape, bool(np.allclose(r @ r.transpose(0, 2, 1), np.eye(3)))
    ((2, 3, 3), True)
    """
    q = rng.standard_normal((n, 4))
    # a zero row has probability zero; map it to the identity rather than divide by zero
    q[np.all(q == 0.0, axis=1), 0] = 1.0
    return quaternion_matrices(q)
