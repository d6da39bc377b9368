"""Size distribution of a 3D packing: masses are volumes, against the closed form."""

from __future__ import annotations

import numpy as np

from regopack.plugins.analyzers.psd3d import Psd3D


def test_mass_shares_weight_the_cube_of_the_diameter(packing3d) -> None:
    psd = Psd3D().compute(packing3d, {})
    c = psd.classes
    d = 2.0 * packing3d.radius
    placed = packing3d.placed
    k = np.searchsorted(c["d_hi"], d, side="right").clip(0, len(c["d_hi"]) - 1)
    mass = np.bincount(k[placed], weights=d[placed] ** 3, minlength=len(c["d_lo"]))
    np.testing.assert_allclose(c["mass_share_placed"], mass / mass.sum(), rtol=1e-12)
    np.testing.assert_allclose(psd.mass, np.pi / 6 * d**3, rtol=1e-15)
    # the scene's uniform 3-6 µm diameters: class shares of d³ in closed form
    lo, hi = np.clip(c["d_lo"], 3.0, 6.0), np.clip(c["d_hi"], 3.0, 6.0)
    expected = (hi**4 - lo**4) / (6.0**4 - 3.0**4)
    np.testing.assert_allclose(c["mass_share_analytic"], expected, atol=2e-4)
    assert psd.results()["analytic"] == "uniform"
