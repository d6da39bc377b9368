"""Read the final dump of LAMMPS bodies back into a packing.

The ``lammps`` script of a packing of bodies (2D or 3D) stores each body's first
orientation (``fix store/state 0`` of its quaternion) and, after its run,
writes ``<stem>.final.dump``: ``id type x y z``, the displacement of the centre
of mass (``compute displace/atom``, unwrapped in a periodic box) and the
quaternions now and at the start. :func:`read_body_dump` turns every body by
the rotation from the one to the other about its centre of mass and moves it
by its displacement.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import PackingError, PackingFileError
from regopack.packing.core import Packing
from regopack.packing.motion import moved
from regopack.plugins.exporters.granular_common import check_atoms, read_dump

__all__ = ["BODY_DUMP_COLUMNS", "read_body_dump", "rotation_matrices"]

FloatArray = NDArray[np.float64]

BODY_DUMP_COLUMNS = (
    "id type x y z c_disp[1] c_disp[2] c_disp[3] c_q[1] c_q[2] c_q[3] c_q[4] "
    "f_q0[1] f_q0[2] f_q0[3] f_q0[4]"
).split()
"""The columns of the final dump of bodies, as the ``lammps`` script writes them."""


def rotation_matrices(q: FloatArray) -> FloatArray:
    """Rotation matrices ``(k, 3, 3)`` of quaternions ``(w, x, y, z)`` (normalised first).

    Examples
    --------
    >>> rotation_matrices(np.array([[np.cos(0.5), 0, 0, np.sin(0.5)]])).round(6)[0, 0].tolist()
    [0.540302, -0.841471, 0.0]
    """
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    out: FloatArray = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )
    return out


def read_body_dump(
    packing: Packing[Any],
    path: Path,
    index: NDArray[np.int64],
    pivot: FloatArray,
    scale: float,
    start: FloatArray | None = None,
) -> Packing[Any]:
    """Return ``packing`` as the LAMMPS run whose final dump of bodies is ``path`` left it.

    Parameters
    ----------
    packing
        The exported 3D packing.
    path
        The dump (:data:`BODY_DUMP_COLUMNS`, sorted by id): body ``k`` is
        particle ``index[k - 1]``.
    index, pivot
        Draw index of each body and its centre of mass relative to the
        particle's reference point, in the packing's lengths.
    scale
        The export's length scale: the dump's lengths are divided by it.
    start
        Where the export put each body's centre of mass, in the packing's
        lengths: each body's position less its displacement must be there
        (modulo a periodic box), else the dump was read with another scale.

    Raises
    ------
    PackingFileError
        One line naming ``path``, when it is no final dump of these bodies.
    """
    step, columns, table = read_dump(path, "LAMMPS")
    if columns != BODY_DUMP_COLUMNS:
        raise PackingFileError(
            f"{path}: its columns are not those of the lammps script's final dump of bodies "
            f"({' '.join(BODY_DUMP_COLUMNS)})"
        )
    check_atoms(path, table, index.size, "bodies", table)
    dim = packing.dimension
    if start is not None:
        _check_start(path, packing, table[:, 2 : 2 + dim] - table[:, 5 : 5 + dim], start, scale)
    now, first = table[:, 8:12], table[:, 12:16]
    if (np.linalg.norm(now, axis=1) < 0.5).any() or (np.linalg.norm(first, axis=1) < 0.5).any():
        raise PackingFileError(f"{path}: a body's quaternion is not a unit quaternion")
    turn = rotation_matrices(now) @ rotation_matrices(first).transpose(0, 2, 1)
    # in 2D the bodies turn about z and move in the plane
    try:
        return moved(
            packing,
            index,
            table[:, 5 : 5 + dim] / scale,
            turn[:, :dim, :dim],
            pivot,
            stats={"settled_steps": step},
        )
    except PackingError as err:
        raise PackingFileError(f"{path}: {str(err).removeprefix('moved: ')}") from err


def _check_start(
    path: Path, packing: Packing[Any], origin: FloatArray, start: FloatArray, scale: float
) -> None:
    """Refuse a dump whose bodies did not start where the export put them (another scale)."""
    dim = packing.dimension
    bounds = packing.domain.bounds().reshape(dim, 2) * scale
    side = bounds[:, 1] - bounds[:, 0]
    gap = origin - start * scale
    if packing.domain.periodic:
        gap -= side * np.round(gap / side)
    if np.abs(gap).max(initial=0.0) > 1e-9 * float(side.max()):
        raise PackingFileError(
            f"{path}: its bodies did not start where the export with length scale {scale!r} "
            "put them; give the export's units and length_scale"
        )
