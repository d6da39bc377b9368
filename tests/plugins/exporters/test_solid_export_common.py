"""What the 3D exporters share: fans, exact mass properties, files written whole or not at all."""

from __future__ import annotations

import os

import numpy as np
import pytest
from packings3d import CUBE_LOOPS, cube_and_sphere, packing3d

from regopack.exports.pipeline import export_packing
from regopack.plugins.exporters.solid_export_common import fan_triangles, mass_properties
from regopack.registry.manager import default_registry

EXPORTS = [("vtk", ".vtu"), ("stl", ".stl"), ("gsd", ".gsd"), ("lammps", ".data")]


def test_mass_properties_of_a_shifted_box_match_the_formulas() -> None:
    cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    box = cube * [1.0, 2.0, 3.0] + [0.5, -0.25, 0.125]  # 2 x 4 x 6, off the reference point
    loops = [np.array(loop) for loop in CUBE_LOOPS]
    volume, centroid, moments = mass_properties(box, loops)
    assert volume == pytest.approx(48.0)
    np.testing.assert_allclose(centroid, [0.5, -0.25, 0.125], atol=1e-14)
    np.testing.assert_allclose(moments, np.diag([2.0**2, 4.0**2, 6.0**2]) * 48.0 / 12, atol=1e-12)
    flipped = mass_properties(box, [loop[::-1] for loop in loops])[0]
    assert flipped == pytest.approx(-48.0)  # inward faces give a negative volume


def test_mass_properties_agree_with_the_packing_volumes() -> None:
    packing = packing3d()
    volumes = packing.solids.volume
    for j in np.flatnonzero(packing.placed)[:10].tolist():
        local, loops = packing.solids.solid(j)
        assert mass_properties(local, loops)[0] == pytest.approx(volumes[j], rel=1e-12)
        assert fan_triangles(loops).shape[0] == sum(len(loop) - 2 for loop in loops)


@pytest.mark.parametrize(("kind", "suffix"), [*EXPORTS, ("slice", ".slice.npz")])
def test_an_interrupted_export_leaves_the_previous_file(kind, suffix, tmp_path, monkeypatch):  # type: ignore[no-untyped-def]
    registry = default_registry()
    path = tmp_path / f"p{suffix}"
    export_packing(packing3d(), kind, path, registry=registry)
    before = path.read_bytes()

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        export_packing(cube_and_sphere(rounded=False), kind, path, registry=registry)
    assert path.read_bytes() == before
    assert not [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize(("kind", "suffix"), EXPORTS)
def test_a_packing_with_nothing_placed_gives_an_empty_file(kind, suffix, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    cube = cube_and_sphere(rounded=False)
    empty = dataclasses.replace(cube, centre=np.full((1, 3), np.nan), insertion_index=[-1])
    path = export_packing(empty, kind, tmp_path / f"p{suffix}", registry=default_registry())
    assert path.stat().st_size > 0


@pytest.mark.parametrize("kind", ["vtk", "stl"])
def test_spheres_are_refused_in_one_line_by_the_polyhedron_formats(kind, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from regopack.base.errors import ExportError

    with pytest.raises(
        ExportError, match=rf"^particle 1: a sphere; the {kind} export writes sharp"
    ):
        export_packing(cube_and_sphere(), kind, tmp_path / "p", registry=default_registry())
    assert not list(tmp_path.iterdir())
