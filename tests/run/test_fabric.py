"""The fabric block of a run summary: lattices, a deposited packing, scale, reuse and the switch."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import regopack
from regopack.geometry.domain import PeriodicRectangle
from regopack.packing.core import Packing
from regopack.registry.manager import default_registry
from regopack.run.fabric import FABRIC_ANALYSES, fabric_rows, fabric_summary
from regopack.run.pipeline import run_scene, summary_rows
from regopack.scenes.analysis_plan import run_analyses
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import make_registry, packing_from_polygons, scaled_packing

sys.path.insert(0, str(Path(__file__).parents[1] / "plugins" / "analyzers"))
from lattices3d import sphere_lattice

KEYS = {
    "tol",
    "n_contacts",
    "n_fabric_contacts",
    "z",
    "z_mechanical",
    "rattlers",
    "rattler_fraction",
    "rattler_min_contacts",
    "anisotropy",
    "anisotropy_error",
    "error_blocks",
    "principal_direction",
}

DEM_SMALL: dict[str, Any] = {"domain__width": 300.0, "domain__height": 300.0}
"""The `dem` scene cut to a 300 µm square (about 2 000 particles, built bottom-up)."""

SCENE3D: dict[str, Any] = {
    "name": "fabric3d",
    "seed": 3,
    "domain": {"kind": "box", "width": 24.0, "height": 24.0, "depth": 24.0},
    "size": {"kind": "uniform", "d_min": 3.0, "d_max": 6.0},
    "phases": [{"name": "glass", "fraction": 1.0, "shape": {"kind": "polyhedron"}}],
    "insertion": {"kind": "available-surface"},
    "density": {"kind": "eta"},
}


@pytest.fixture(scope="module")
def registry():  # type: ignore[no-untyped-def]
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def dem_small(registry) -> tuple[Packing, dict[str, Any]]:  # type: ignore[no-untyped-def]
    scene = regopack.scene("dem", insertion__strip=300.0, **DEM_SMALL)
    outcome = run_scene(scene.with_(registry=registry))
    return outcome.packing, outcome.summary


def hexagons(rows: int, cols: int) -> Packing:
    """A periodic tiling of ``rows`` x ``cols`` regular hexagons of side 1 (rows even)."""
    angle = np.radians(30 + 60 * np.arange(6))
    outlines = []
    for r in range(rows):
        for c in range(cols):
            cx = np.sqrt(3) * (c + 0.5 * (r % 2) + 0.25)
            cy = 1.5 * r + 0.75
            outlines.append(np.c_[cx + np.cos(angle), cy + np.sin(angle)])
    return packing_from_polygons(outlines, PeriodicRectangle(0, cols * np.sqrt(3), 0, 1.5 * rows))


def test_a_tiling_of_hexagons_is_isotropic_with_six_contacts(registry) -> None:  # type: ignore[no-untyped-def]
    block = fabric_summary(hexagons(12, 12), registry)
    assert set(block) == KEYS
    assert block["n_contacts"] == block["n_fabric_contacts"] == 3 * 144
    assert block["z"] == block["z_mechanical"] == 6.0
    assert block["rattlers"] == 0 and block["rattler_fraction"] == 0.0
    assert block["anisotropy"] == pytest.approx(0.0, abs=1e-12)
    assert 0.0 <= block["anisotropy_error"] < 0.02 and block["error_blocks"] == 16


def test_a_cubic_lattice_of_spheres_is_isotropic_without_rattlers(registry) -> None:  # type: ignore[no-untyped-def]
    """Every sphere of a finite piece of the cubic lattice has three contacts or more."""
    block = fabric_summary(sphere_lattice((5, 5, 5), 1.0, 0.0), registry)
    assert set(block) == KEYS
    assert block["n_contacts"] == 3 * 5 * 5 * 4 and block["z"] == pytest.approx(4.8)
    assert block["anisotropy"] == pytest.approx(0.0, abs=1e-12) and block["error_blocks"] == 8
    assert block["rattlers"] == 0 and block["rattler_fraction"] == 0.0
    assert block["z_mechanical"] == pytest.approx(4.8) and block["rattler_min_contacts"] == 2


def test_a_packing_built_bottom_up_has_a_vertical_fabric(dem_small) -> None:  # type: ignore[no-untyped-def]
    packing, summary = dem_small
    block = summary["fabric"]
    assert set(block) == KEYS and summary["fabric_time_s"] > 0
    assert block["anisotropy"] > 0.1 and block["anisotropy_error"] < block["anisotropy"] / 3
    assert abs(block["principal_direction"][1]) > 0.95  # vertical
    # rattlers are removed: the mechanical Z of the rest is higher than the mean
    assert 0.1 < block["rattler_fraction"] < 0.4 and block["rattlers"] > 100
    assert block["z_mechanical"] > block["z"] + 0.2
    assert block["n_contacts"] == pytest.approx(block["z"] * packing.n_placed / 2)
    rows = dict(summary_rows(summary))
    assert rows["fabric anisotropy"].endswith("(vertical)") and " ± " in rows["fabric anisotropy"]
    assert rows["Z / Z_m / rattlers"].endswith(f"{100 * block['rattler_fraction']:.1f} %")


def test_the_block_is_scale_free(dem_small, registry) -> None:  # type: ignore[no-untyped-def]
    packing, summary = dem_small
    block = summary["fabric"]
    for s in (1e-3, 1e3):
        scaled = fabric_summary(scaled_packing(packing, s), registry)
        assert scaled["tol"] == pytest.approx(block["tol"] * s, rel=1e-12)
        for key in KEYS - {"tol"}:
            np.testing.assert_allclose(scaled[key], block[key], rtol=1e-9, err_msg=key)


def test_the_scene_analyses_are_reused(registry, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    packing = hexagons(6, 6)
    done = run_analyses(packing, registry, [("contacts", {"tol": 0.1}), ("network", {})])
    computed: list[str] = []
    for name in FABRIC_ANALYSES:
        cls = type(registry.get("analysis", name).factory(None))
        original = cls.compute

        def spy(self, *args, _original=original, _name=name):  # type: ignore[no-untyped-def]
            computed.append(_name)
            return _original(self, *args)

        monkeypatch.setattr(cls, "compute", spy)
    block = fabric_summary(packing, registry, done)
    assert computed == ["coordination"] and block["tol"] == 0.1


def test_a_registry_without_the_analyzers_skips_the_block(tmp_path) -> None:  # type: ignore[no-untyped-def]
    registry = make_registry(builtins=("regopack.plugins.sizes.change5",))
    block = fabric_summary(hexagons(2, 2), registry)
    assert block == {"skipped": "no analyzer 'contacts' is registered"}
    assert fabric_rows(block) == [("fabric", "skipped: no analyzer 'contacts' is registered")]


def test_rows_show_the_error_to_its_first_digit() -> None:
    block = {
        "anisotropy": 0.18123,
        "anisotropy_error": 0.00043,
        "principal_direction": [0.6, 0.8],
        "z": 3.9,
        "z_mechanical": None,
        "rattler_fraction": None,
    }
    assert fabric_rows(block) == [
        ("fabric anisotropy", "0.1812 ± 0.0004 (37° from vertical)"),
        ("Z / Z_m / rattlers", "3.90 / n/a / n/a"),
    ]
    block["anisotropy_error"] = 0.1  # not twice the error: no direction
    assert fabric_rows(block)[0] == ("fabric anisotropy", "0.181 ± 0.100")


def test_a_2d_run_writes_the_block_and_the_switch_leaves_it_out(tmp_path, registry) -> None:  # type: ignore[no-untyped-def]
    scene = resolve_scene(load_scene("small", ["count=300"]), registry)
    outcome = run_scene(scene, tmp_path / "on")
    written = json.loads((tmp_path / "on" / "summary.json").read_text())
    assert set(written["fabric"]) == KEYS and written["fabric"] == outcome.summary["fabric"]
    assert "fabric" not in outcome.packing.scene["outputs"]
    off = resolve_scene(load_scene("small", ["count=300", "outputs.fabric=false"]), registry)
    summary = run_scene(off, tmp_path / "off").summary
    assert "fabric" not in summary and "fabric_time_s" not in summary
    assert "fabric anisotropy" not in dict(summary_rows(summary))
    assert off.to_dict()["outputs"]["fabric"] is False
    again = json.loads((tmp_path / "off" / "summary.json").read_text())
    assert "fabric" not in again
    assert regopack.scene(off.to_dict()).scene.outputs.fabric is False


def test_a_3d_run_writes_the_block(registry) -> None:  # type: ignore[no-untyped-def]
    summary = regopack.pack_and_summarise(SCENE3D, verify=False, registry=registry).summary
    block = summary["fabric"]
    assert set(block) == KEYS and block["error_blocks"] == 8 and block["rattler_min_contacts"] == 2
    assert block["n_contacts"] > 0 and block["anisotropy"] >= 0 and block["anisotropy_error"] > 0
    assert np.linalg.norm(block["principal_direction"]) == pytest.approx(1.0)
    rows = dict(summary_rows(summary))
    assert "fabric anisotropy" in rows and "Z / Z_m / rattlers" in rows


@pytest.mark.parametrize("dimension", [2, 3])
def test_an_isotropic_fabric_shows_no_direction(dimension: int) -> None:
    """Isotropic normals give an anisotropy of about 2 / sqrt(n) (2D), 7.5 / sqrt(n) (3D).

    That is three times the jackknife error in 3D: twice the error let a
    direction through for three isotropic networks in five.
    """
    from regopack.plugins.analyzers.network import (
        anisotropy_of,
        block_jackknife,
        block_of,
        principal_direction,
    )

    rng = np.random.default_rng(7)
    shown = 0
    for _ in range(100):
        normals = rng.normal(size=(300, dimension))
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        where = rng.uniform(0.0, 1.0, size=(300, dimension))
        error, _ = block_jackknife(normals, block_of(where, np.array([0.0, 1.0] * dimension), 2))
        fabric = normals.T @ normals / 300
        block = {
            "anisotropy": anisotropy_of(fabric),
            "anisotropy_error": error,
            "principal_direction": principal_direction(fabric),
            "n_fabric_contacts": 300,
            "z": 4.0,
            "z_mechanical": 4.0,
            "rattler_fraction": 0.0,
        }
        shown += fabric_rows(block)[0][1].endswith(("vertical)", "horizontal)"))
    assert shown <= 5
    # a fabric of normals mostly along the vertical keeps its direction
    normals = np.zeros((300, dimension))
    normals[:, -1] = 1.0
    normals[::3, 0] = 1.0
    normals[::3, -1] = 0.0
    fabric = normals.T @ normals / 300
    block.update(
        anisotropy=anisotropy_of(fabric),
        anisotropy_error=0.01,
        principal_direction=principal_direction(fabric),
    )
    assert fabric_rows(block)[0][1].endswith("(vertical)")


def test_an_anisotropy_no_larger_than_chance_says_so() -> None:
    one = {"anisotropy": 7.5, "anisotropy_error": None, "n_fabric_contacts": 1,
           "principal_direction": [0.6, -0.2, 0.8], "z": 3.0, "z_mechanical": 3.5,
           "rattler_fraction": 0.3}  # fmt: skip
    assert dict(fabric_rows(one))["fabric anisotropy"] == (
        "7.500 (no more than chance gives 1 contact)"
    )
    many = {**one, "anisotropy": 0.3, "anisotropy_error": 0.01, "n_fabric_contacts": 10_000}
    assert dict(fabric_rows(many))["fabric anisotropy"] == "0.300 ± 0.010 (37° from vertical)"
    low = {**many, "anisotropy": 0.1}  # under twice 7.5 / 100
    assert dict(fabric_rows(low))["fabric anisotropy"] == (
        "0.100 ± 0.010 (no more than chance gives 10000 contacts)"
    )


def test_a_3d_run_lists_the_reference_fractions(registry) -> None:  # type: ignore[no-untyped-def]
    summary = regopack.pack_and_summarise(SCENE3D, verify=False, registry=registry).summary
    labels = [r["label"] for r in summary["phi_references"]]
    assert labels == ["random sequential addition", "Williams–Philipse", "random close packing"]
    row = dict(summary_rows(summary))["φ references"]
    assert "0.36–0.40" in row and "0.61" in row and "0.64" in row
