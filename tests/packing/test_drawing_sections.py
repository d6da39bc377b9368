"""Figures of 3D packings: exact sections and a rendered view."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from packings3d import cube_packing

from regopack.packing.drawing import draw_section, draw_view, section_polygons


def _area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_sections_of_cubes_are_their_squares() -> None:
    p = cube_packing([[5.0, 5.0, 5.0], [7.0, 5.0, 5.3], [2.0, 2.0, 2.0]], 0.5)
    polys, owners = section_polygons(p, axis=2, at=5.2)
    assert owners.tolist() == [0, 1]
    assert [_area(q) for q in polys] == pytest.approx([1.0, 1.0])
    assert polys[1].min(axis=0).tolist() == pytest.approx([6.5, 4.5])
    polys, owners = section_polygons(p, axis=0, at=2.25)
    assert owners.tolist() == [2] and _area(polys[0]) == pytest.approx(1.0)
    assert section_polygons(p, axis=1, at=9.0)[0] == []


def test_a_rotated_cube_cut_through_its_centre_has_the_right_area() -> None:
    # a cube turned by 45 degrees about z, cut by a plane x = const through its centre
    c, s = np.cos(np.pi / 8), np.sin(np.pi / 8)
    base = cube_packing([[5.0, 5.0, 5.0]], 0.5)
    rot = np.array(
        [
            [np.cos(np.pi / 4), -np.sin(np.pi / 4), 0],
            [np.sin(np.pi / 4), np.cos(np.pi / 4), 0],
            [0, 0, 1],
        ]
    )
    from dataclasses import replace

    turned = replace(
        base,
        vertices=base.vertices @ rot.T,
        normals=base.normals @ rot.T,
        rotation=np.array([[c, 0, 0, s]]),
    )
    polys, _ = section_polygons(turned, axis=0, at=5.0)
    assert _area(polys[0]) == pytest.approx(np.sqrt(2.0))  # the diagonal, times the height


def test_figures_draw(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = cube_packing([[5.0, 5.0, 5.0], [9.4, 0.6, 9.4]], 0.5)
    fig = plt.figure(figsize=(7, 3))
    draw_section(p, fig.add_subplot(1, 2, 1), axis=1, at=5.0)
    shown = draw_view(p, fig.add_subplot(1, 2, 2, projection="3d"))
    assert shown == 1  # only the cube by the visible faces
    fig.savefig(tmp_path / "f.png", dpi=60)
    plt.close(fig)
    assert (tmp_path / "f.png").stat().st_size > 1000


def test_plot_draws_a_3d_packing_by_its_section() -> None:
    # three cubes; the plane z = 5.2 cuts the first two, whose squares are drawn
    p = cube_packing([[5.0, 5.0, 5.0], [7.0, 5.0, 5.3], [2.0, 2.0, 2.0]], 0.5)
    _, ax = plt.subplots()
    art = p.plot(ax, axis=2, at=5.2)
    paths = art.particles.get_paths()
    assert len(paths) == 2
    assert ax.get_xlabel().startswith("x (") and ax.get_ylabel().startswith("y (")
    art = p.plot(color_by="diameter", axis=0, at=2.25)
    assert len(art.particles.get_paths()) == 1 and art.colorbar is not None
    assert art.ax.get_xlabel().startswith("y (") and art.ax.get_ylabel().startswith("z (")
    plt.close("all")


def test_a_bad_section_axis_is_one_line() -> None:
    from regopack.base.errors import ConfigError

    p = cube_packing([[5.0, 5.0, 5.0]], 0.5)
    with pytest.raises(ConfigError, match=r"^axis = 3: expected 0, 1 or 2"):
        p.plot(axis=3)
    plt.close("all")
