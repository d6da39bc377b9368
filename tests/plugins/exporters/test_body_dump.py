"""Reading the final dump of LAMMPS bodies back (:mod:`regopack.plugins.exporters.body_dump`)."""

from __future__ import annotations

import numpy as np
import pytest
from packings3d import cube_packing
from scipy.spatial.transform import Rotation

from regopack.base.errors import PackingFileError
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.body_dump import (
    BODY_DUMP_COLUMNS,
    read_body_dump,
    rotation_matrices,
)
from regopack.testing import packing_from_polygons


def test_rotation_matrices_of_quaternions() -> None:
    r = Rotation.random(20, random_state=3)
    wxyz = r.as_quat()[:, [3, 0, 1, 2]] * 2.5  # any length: normalised first
    np.testing.assert_allclose(rotation_matrices(wxyz), r.as_matrix(), atol=1e-14)


def dump(path, rows: np.ndarray, columns: list[str] = BODY_DUMP_COLUMNS, step: object = 7):
    lines = ["ITEM: TIMESTEP", str(step), "ITEM: NUMBER OF ATOMS", str(len(rows))]
    lines += ["ITEM: BOX BOUNDS ff ff ff", "0 10", "0 10", "0 10"]
    lines += ["ITEM: ATOMS " + " ".join(columns)]
    lines += [" ".join(repr(float(x)) for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def rows_of(start: np.ndarray, now: np.ndarray, moved: np.ndarray) -> np.ndarray:
    n = len(start)
    ids = np.arange(1, n + 1)[:, None]
    return np.hstack([ids, np.ones((n, 1)), np.zeros((n, 3)), moved, now, start])


def test_bodies_turn_by_the_turn_from_their_first_orientation(tmp_path) -> None:
    packing = cube_packing([[3.0, 3, 3], [6, 6, 6]], half=0.5)
    first = Rotation.random(2, random_state=1)
    turn = Rotation.random(2, random_state=2)
    start = first.as_quat()[:, [3, 0, 1, 2]]
    now = (turn * first).as_quat()[:, [3, 0, 1, 2]]
    shift = np.array([[0.5, 0, 0], [0, 0, -1.0]]) * 1e-6
    pivot = np.array([[0.1, 0, 0], [0, 0, 0]])
    path = dump(tmp_path / "d.dump", rows_of(start, now, shift))
    settled = read_body_dump(packing, path, np.array([0, 1]), pivot, 1e-6)
    for k in range(2):
        before = packing.world_vertices(k) - packing.centre[k] - pivot[k]
        want = before @ turn[k].as_matrix().T + packing.centre[k] + pivot[k] + shift[k] / 1e-6
        np.testing.assert_allclose(settled.world_vertices(k), want, atol=1e-12)
    assert settled.stats["settled_steps"] == 7


def test_wrong_dumps_are_refused_in_one_line(tmp_path) -> None:
    packing = cube_packing([[3.0, 3, 3], [6, 6, 6]], half=0.5)
    q = np.tile([1.0, 0, 0, 0], (2, 1))
    good = rows_of(q, q, np.zeros((2, 3)))
    index, pivot = np.array([0, 1]), np.zeros((2, 3))
    cases = [
        (dump(tmp_path / "a", good, BODY_DUMP_COLUMNS[:-1] + ["x"]), "its columns are not"),
        (dump(tmp_path / "b", good[:1]), "1 atoms, but the packing has 2 bodies"),
        (dump(tmp_path / "c", rows_of(q * 0, q, np.zeros((2, 3)))), "not a unit quaternion"),
        (dump(tmp_path / "d", good[::-1]), "ids are not 1 to 2"),
    ]
    bad = good.copy()
    bad[0, 6] = np.nan
    cases.append((dump(tmp_path / "e", bad), "not finite"))
    for path, message in cases:
        with pytest.raises(PackingFileError, match=message) as err:
            read_body_dump(packing, path, index, pivot, 1.0)
        assert str(err.value).startswith(str(path))


def test_2d_bodies_turn_about_z_and_scale_back(tmp_path) -> None:
    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    packing = packing_from_polygons([square, square + 3.0])
    q0 = np.tile([1.0, 0, 0, 0], (2, 1))
    turn = np.array([[np.cos(0.2), 0, 0, np.sin(0.2)], [1.0, 0, 0, 0]])  # 0.4 rad about z
    moved_by = np.array([[2.0, -4.0, 0.0], [0.0, 0.0, 0.0]])  # in lengths x 2
    start = packing.centre.copy()
    rows = rows_of(q0, turn, moved_by)
    rows[:, 2:4] = start * 2.0 + moved_by[:, :2]  # x = start + displacement
    path = dump(tmp_path / "d.dump", rows)
    settled = read_body_dump(packing, path, np.array([0, 1]), np.zeros((2, 2)), 2.0, start)
    c, s = np.cos(0.4), np.sin(0.4)
    want = (packing.polygon(0) - packing.centre[0]) @ np.array([[c, -s], [s, c]]).T
    np.testing.assert_allclose(settled.polygon(0), want + packing.centre[0] + [1.0, -2.0])
    assert settled.orientation[0] == pytest.approx(packing.orientation[0] + 0.4)
    with pytest.raises(PackingFileError, match="did not start where the export"):
        read_body_dump(packing, path, np.array([0, 1]), np.zeros((2, 2)), 3.0, start)


def test_a_step_that_is_no_count_is_refused(tmp_path) -> None:
    packing = cube_packing([[3.0, 3, 3], [6, 6, 6]], half=0.5)
    q = np.tile([1.0, 0, 0, 0], (2, 1))
    for step in ("nan", "1e400", "-3", "2.5"):
        path = dump(tmp_path / f"s{step}", rows_of(q, q, np.zeros((2, 3))), step=step)
        with pytest.raises(PackingFileError, match="is no step count"):
            read_body_dump(packing, path, np.array([0, 1]), np.zeros((2, 3)), 1.0)


def test_sphere_dumps_scale_back(tmp_path) -> None:
    from regopack.plugins.exporters.granular_common import read_sphere_dump
    from regopack.plugins.exporters.liggghts_export import LiggghtsConfig

    centres = np.array([[2.0, 2, 2], [5, 5, 5]])
    packing = Packing.of_spheres(centres, [1.0, 0.5], Box(0, 10, 0, 10, 0, 10))
    columns = "id type x y z radius mass".split()
    rows = np.array([[1, 1, 4.0, 4, 3, 2.0, 1], [2, 1, 10, 10, 10, 1.0, 1]])
    path = dump(tmp_path / "s.dump", rows, columns)
    settled = read_sphere_dump(packing, path, LiggghtsConfig(), 2.0, "LIGGGHTS")
    np.testing.assert_array_equal(settled.centre, [[2.0, 2, 1.5], [5, 5, 5]])
