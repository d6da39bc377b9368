"""Analyses are scale-invariant: a packing scaled by s analyses alike, lengths times s."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import regopack
from regopack.analysis.pipeline import analysis_summary, main_numbers, run_analyses
from regopack.packing.core import Packing
from regopack.registry.manager import default_registry
from regopack.testing import scaled_packing

SCENE2D: dict[str, Any] = {
    "name": "scale",
    "seed": 2,
    "domain": {"kind": "rectangle", "width": 60.0, "height": 60.0},
    "size": {"kind": "change5", "d_min": 2.0, "d_max": 10.0, "d0": 16.0, "alpha": 6.9},
    "phases": [
        {"name": "pyroxene", "fraction": 0.6, "shape": {"kind": "octagon", "psi": 0.5}},
        {"name": "glass", "fraction": 0.4, "shape": {"kind": "octagon", "psi": 2.0}},
    ],
    "insertion": {"kind": "available-arc"},
    "density": {"kind": "eta"},
}
"""A 60 × 60 µm packing of about 150 octagons of 2 to 10 µm (a 40 µm interior window)."""

ANALYSES = ("density", "contacts", "coordination", "rdf", "homogeneity")
ANALYSES_3D = ("density", "contacts", "coordination", "rdf")

SCALES = st.sampled_from([1e-6, 1e-3, 1e3, 1e6]) | st.floats(-6.0, 6.0).map(lambda e: 10.0**e)
"""Scale factors from 10⁻⁶ to 10⁶: the decades of the issue, and any factor between."""


def _analyse(packing: Any, names: tuple[str, ...]) -> dict[str, Any]:
    return dict(run_analyses(packing, default_registry(), [(n, {}) for n in names]))


@pytest.fixture(scope="module")
def base2d() -> tuple[Packing, dict[str, Any]]:
    packing = regopack.pack(SCENE2D, verify=False)
    assert packing.dimension == 2
    return packing, _analyse(packing, ANALYSES)


def _close(a: Any, b: Any, s: float = 1.0, atol: float = 0.0) -> None:
    """``b == a s``, to 1e-9 relative, or ``atol s`` for values that are rounding noise."""
    want = np.asarray(a, dtype=float) * s
    np.testing.assert_allclose(np.asarray(b, dtype=float), want, rtol=1e-9, atol=atol * s)


def _same_analyses(done: dict[str, Any], scaled: dict[str, Any], s: float) -> None:
    """``scaled`` is ``done`` with every length times ``s``."""
    base, other = done["contacts"], scaled["contacts"]
    assert other.tol == pytest.approx(base.tol * s, rel=1e-12)
    assert other.tol_max == pytest.approx(base.tol_max * s, rel=1e-12)
    assert other.results()["n_contacts"] == base.results()["n_contacts"]
    np.testing.assert_array_equal(other.pairs, base.pairs)
    _close(base.threshold, other.threshold, s, atol=1e-12)  # touching pairs: 0 up to rounding
    _close(base.area, other.area, s * s, atol=1e-12)
    zb, zs = done["coordination"].results(), scaled["coordination"].results()
    for key in ("z_domain", "z_interior", "n_interior"):
        assert zs[key] == pytest.approx(zb[key], rel=1e-12), key
    _close(done["coordination"].tols, scaled["coordination"].tols, s)  # Z(tol s) = Z(tol)
    np.testing.assert_array_equal(
        scaled["coordination"].z_tol_interior, done["coordination"].z_tol_interior
    )
    for key, value in done["density"].results().items():
        if isinstance(value, float) and key.startswith("phi"):
            assert scaled["density"].results()[key] == pytest.approx(value, rel=1e-9), key
    for field in ("near", "far"):
        if field not in done["rdf"].curves:
            continue
        a, b = done["rdf"].curves[field], scaled["rdf"].curves[field]
        _close(a["r"], b["r"], s)  # g(r / s) = g(r)
        np.testing.assert_allclose(b["total"], a["total"], rtol=1e-9, equal_nan=True)
    rb, rs = done["rdf"].results(), scaled["rdf"].results()
    assert rs["first_peak_distinct"] == rb["first_peak_distinct"]
    lo, hi = rb["first_peak_fit_range"]
    assert rs["first_peak_fit_range"] == pytest.approx([lo * s, hi * s], rel=1e-9)
    if rb["first_peak_r"] is not None:
        assert rs["first_peak_r"] == pytest.approx(rb["first_peak_r"] * s, rel=1e-9)


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(s=SCALES)
def test_a_scaled_packing_analyses_alike(base2d, s):
    packing, done = base2d
    scaled = _analyse(scaled_packing(packing, s), ANALYSES)
    _same_analyses(done, scaled, s)
    hb, hs = done["homogeneity"].results(), scaled["homogeneity"].results()
    assert hs["ring_width"] == pytest.approx(hb["ring_width"] * s, rel=1e-12)
    assert hs["slope_length"] == pytest.approx(hb["slope_length"] * s, rel=1e-12)
    assert hs["phi_slope_per_100"] == pytest.approx(hb["phi_slope_per_100"], rel=1e-6, abs=1e-12)


def test_the_defaults_are_the_former_numbers_at_the_builtin_scale(base2d):
    _, done = base2d
    assert (done["contacts"].tol, done["contacts"].tol_max) == (0.05, 0.5)
    cfg = done["rdf"].config
    assert (cfg.near, cfg.near_bin, cfg.far, cfg.far_bin) == ((0.0, 10.0), 0.1, (100.0, 340.0), 2.0)
    former = [round(float(v), 6) for v in np.linspace(0.02, 0.5, 20)]
    assert done["coordination"].tols.tolist() == sorted({*former, 0.05})
    assert done["homogeneity"].results()["slope_length"] == 100.0


def test_a_length_the_user_sets_is_used_as_given(base2d):
    packing, _ = base2d
    tiny = scaled_packing(packing, 1e-3)
    done = run_analyses(tiny, default_registry(), [("contacts", {"tol": 0.05})])
    assert done["contacts"].results()["tol"] == 0.05  # every pair of a 2 nm particle packing
    assert done["contacts"].results()["tol_max"] == 0.05


@pytest.fixture(scope="module")
def base3d(packing3d: Any) -> tuple[Any, dict[str, Any]]:
    return packing3d, _analyse(packing3d, ANALYSES_3D)


@pytest.mark.parametrize("s", [1e-6, 1e3])
def test_a_scaled_3d_packing_analyses_alike(base3d, s):
    packing, done = base3d
    assert packing.scene["size"]["d_min"] == 3.0  # defaults at 1.5 times the built-in scale
    _same_analyses(done, _analyse(scaled_packing(packing, s), ANALYSES_3D), s)


def test_the_small_scene_in_millimetres_analyses_as_in_micrometres():
    scene = regopack.scene(
        "small",
        length_unit="mm",
        size__d_min=0.002,
        size__d_max=0.04,
        size__d0=0.016,
        domain__width=0.2,
        domain__height=0.2,
    )
    packing = regopack.pack(scene, verify=False)
    res = regopack.analyze(packing)
    z = res["coordination"]["z_interior"]
    assert 2.5 < z < 3.5  # 2.98 in micrometres; every pair a contact gave 298
    lo, hi = res["rdf"]["first_peak_fit_range"]
    assert 0.002 < lo < hi < 0.006  # 3.05 to 3.75 µm: a plateau, no distinct peak
    assert res["contacts"]["tol"] == pytest.approx(5e-5, rel=1e-12)
    summary = analysis_summary(packing, res.analyzers)
    assert summary["length_unit"] == "mm"
    rows = dict(main_numbers(summary))
    assert rows["contact tolerance tol"] == "5e-05 mm"
    assert rows["first g(r) peak"].endswith(" mm)")  # "no distinct peak (plateau ... mm)"
    assert "µm" not in " ".join([*rows, *rows.values()])
