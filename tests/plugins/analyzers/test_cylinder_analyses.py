"""The 3D analyses of a packing in a walled cylinder: geometry of its windows, scale, figures."""

from __future__ import annotations

import math

import numpy as np
import pytest
from packings3d import cube_packing

import regopack
from regopack.base.errors import PackingError
from regopack.geometry.domain import Cylinder
from regopack.packing.core import Packing, check_solid_values
from regopack.packing.solid_fraction import phi_in_cylinder
from regopack.plugins.analyzers.rdf_histogram import rdf3d_histogram
from regopack.registry.manager import default_registry
from regopack.run.fabric import fabric_summary

ANALYSES = ("density", "contacts", "coordination", "rdf", "network", "psd", "homogeneity")


def _centres() -> np.ndarray:
    """A lattice of step 2 in the cylinder, each point moved at random by up to 0.1."""
    lattice = np.array(
        [
            [x, y, z]
            for x in np.arange(1.0, 10, 2.0)
            for y in np.arange(1.0, 10, 2.0)
            for z in np.arange(1.0, 10, 2.0)
            if math.hypot(x - 5, y - 5) + 1.2 <= 5
        ]
    )
    return lattice + np.random.default_rng(8).uniform(-0.1, 0.1, lattice.shape)


def _spheres(scale: float = 1.0) -> Packing:
    cyl = Cylinder(5 * scale, 5 * scale, 5 * scale, 0.0, 10 * scale)
    c = _centres()
    radii = np.random.default_rng(9).uniform(0.7, 0.8, len(c))
    return Packing.of_spheres(c * scale, radii * scale, cyl)


def _cubes(scale: float = 1.0) -> Packing:
    cyl = Cylinder(5 * scale, 5 * scale, 5 * scale, 0.0, 10 * scale)
    return cube_packing(_centres() * scale, half=0.7 * scale, domain=cyl)


def _scalars(results: dict, prefix: str = "") -> dict[str, float]:
    out = {}
    for key, value in results.items():
        if isinstance(value, bool) or value is None:
            continue
        if isinstance(value, int | float):
            out[prefix + key] = float(value)
        elif isinstance(value, list) and all(isinstance(v, int | float) for v in value):
            out.update({f"{prefix}{key}[{k}]": float(v) for k, v in enumerate(value)})
    return out


LENGTHS = ("margin", "window", "density", "d", "diameter", "half", "r", "length", "width")


@pytest.mark.parametrize("make", [_spheres, _cubes])
def test_the_default_analyses_and_a_scaled_packing_agree(make):
    big = regopack.analyze(make(1.0), list(ANALYSES))
    small = regopack.analyze(make(1e-3), list(ANALYSES))
    for name in ANALYSES:
        a, b = _scalars(big[name].scalars), _scalars(small[name].scalars)
        # equal cubes have no spread of size: its fits see rounding at one scale, none at another
        assert all("mean_d" in k for k in a.keys() ^ b.keys()), (name, a.keys() ^ b.keys())
        a = {k: v for k, v in a.items() if k in b and not (make is _cubes and "mean_d" in k)}
        # the fitted peak of a curve of 27 points moves with the rounding of its bins,
        # in a box as much as here: the curves themselves are compared instead
        a = {k: v for k, v in a.items() if not k.startswith("first_peak")}
        for key, value in a.items():
            # lengths scale by 1e-3, number densities by 1e9; fractions and counts do not
            ratio = b[key] / value if value else 0.0
            expected = [1.0, 1e-3, 1e9, 1e-9, 1e-6, 1e6, 1e3]
            if math.isnan(value):
                assert math.isnan(b[key]), (name, key)
            elif abs(value) < 1e-12 and abs(b[key]) < 1e-12:
                continue  # a deviation of rounding size (equal particles)
            elif value:
                assert min(abs(ratio / e - 1) for e in expected) < 1e-9, (name, key, value, b[key])
            else:
                assert b[key] == 0.0, (name, key)
    near_big, near_small = big["rdf"].analyzer.curves["near"], small["rdf"].analyzer.curves["near"]
    np.testing.assert_allclose(near_small["total"], near_big["total"], rtol=1e-9)


def test_density_and_homogeneity_use_the_coaxial_window():
    p = _spheres()
    res = regopack.analyze(
        p, ["density", "homogeneity"], density__margin=1.0, homogeneity__margin=1.0
    )
    window = p.domain.interior(1.0)
    assert isinstance(window, Cylinder) and window.radius == 4.0
    phi = phi_in_cylinder(p, window)
    assert res["density"].scalars["phi_interior"] == pytest.approx(phi, rel=1e-12)
    assert res["density"].scalars["phi_domain"] == pytest.approx(p.phi, rel=1e-14)
    h = res["homogeneity"].analyzer
    layers = h.layers
    dz = layers["z_hi"] - layers["z_lo"]
    # a layer is a disc of the window's cross-section: volume pi R^2 dz
    np.testing.assert_allclose(layers["number_density"] * math.pi * 16.0 * dz, layers["n"])
    solid = float(np.sum(layers["phi"] * math.pi * 16.0 * dz))
    assert solid == pytest.approx(phi * window.volume, rel=1e-10)
    assert res["homogeneity"].scalars["phi"] == pytest.approx(phi, rel=1e-12)
    # the shells fill the window: their solid adds up to the window's
    shells = h.shells
    outer = shells["half_hi"] / shells["half_hi"][-1]
    volumes = np.diff(np.concatenate([[0.0], math.pi * 16.0 * outer**2 * 8.0 * outer]))
    assert float(np.sum(shells["phi"] * volumes)) == pytest.approx(phi * window.volume, rel=1e-10)


def test_the_rdf_of_uniform_points_in_a_cylinder_is_one():
    rng = np.random.default_rng(4)
    cyl = Cylinder(0.0, 0.0, 5.0, 0.0, 10.0)
    n = 6000
    r = 5.0 * np.sqrt(rng.uniform(size=n))
    t = rng.uniform(0, 2 * np.pi, n)
    pts = np.column_stack([r * np.cos(t), r * np.sin(t), rng.uniform(0, 10, n)])
    total, _ = rdf3d_histogram(pts, np.zeros(n, dtype=np.int64), 1, 1.0, 0.5, 14, cyl)
    # without the edge correction g would fall to about 0.5 at r = 7
    assert np.all(np.abs(total - 1.0) < 0.06)
    assert abs(float(total.mean()) - 1.0) < 0.02


def test_the_fabric_block_of_a_cylinder_packing():
    block = fabric_summary(_cubes(), default_registry(autoload=False))
    assert block and "skipped" not in block


def test_file_checks_accept_a_cylinder_and_refuse_a_particle_far_beyond_its_wall():
    check_solid_values(_spheres())
    p = _spheres()
    centre = p.centre.copy()
    centre[0] = [5 + 7.5 * math.cos(0.8), 5 + 7.5 * math.sin(0.8), 5.0]  # in the bounding box's
    far = Packing.of_spheres(centre, np.ones(len(centre)), p.domain)
    check_solid_values(far)  # within a size of the wall
    centre[0] = [5 + 17 * math.cos(0.8), 5 + 17 * math.sin(0.8), 5.0]
    with pytest.raises(PackingError, match="beyond its side wall"):
        check_solid_values(Packing.of_spheres(centre, np.ones(len(centre)), p.domain))


def test_sections_and_views_of_a_cylinder_draw():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from regopack.packing.drawing import draw_section, draw_view

    p = _cubes()
    fig = plt.figure()
    for axis in range(3):
        draw_section(p, fig.add_subplot(2, 2, axis + 1), axis=axis)
    shown = draw_view(p, fig.add_subplot(2, 2, 4, projection="3d"))
    assert 0 < shown < p.n_placed
    plt.close(fig)


def test_a_settled_state_stays_in_its_cylinder():
    from regopack.packing.motion import moved

    p = _spheres()
    q = moved(p, np.array([0]), np.array([[0.0, 0.0, -0.5]]))
    assert q.domain == p.domain and q.centre[0, 2] == p.centre[0, 2] - 0.5
