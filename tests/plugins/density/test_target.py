"""A target packing fraction, porosity or void ratio, met by choosing eta."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from regopack.api.functions import pack_and_summarise
from regopack.base.errors import DensityTargetWarning
from regopack.base.field_error import FieldValueError
from regopack.cli import main
from regopack.plugins.density.eta import EtaController
from regopack.plugins.density.target import TargetConfig, TargetController
from regopack.registry.interfaces import DensityController
from regopack.registry.manager import default_registry
from regopack.scenes.model import load_scene, resolve_scene


def _eta(ctl: DensityController) -> float:
    assert isinstance(ctl, EtaController)
    return ctl.eta


# ---------------------------------------------------------------------------
# the configuration


@pytest.mark.parametrize(
    ("given", "phi"),
    [({"phi": 0.8}, 0.8), ({"porosity": 0.3}, 0.7), ({"void_ratio": 0.25}, 0.8)],
)
def test_each_form_of_the_target_is_a_packing_fraction(given: dict[str, float], phi: float) -> None:
    assert TargetController(TargetConfig(**given)).phi == pytest.approx(phi, abs=1e-15)


@pytest.mark.parametrize(
    "given",
    [{}, {"phi": 0.8, "porosity": 0.2}, {"porosity": 0.2, "void_ratio": 0.25}],
)
def test_exactly_one_target_is_given(given: dict[str, float]) -> None:
    with pytest.raises(ValidationError, match="exactly one of phi, porosity and void_ratio"):
        TargetConfig(**given)


@pytest.mark.parametrize(
    "given",
    [
        {"phi": 0.0},
        {"phi": 1.0},
        {"phi": math.nan},
        {"porosity": 1.0},
        {"void_ratio": 0.0},
        {"phi": 0.5, "tolerance": 0.0},
        {"phi": 0.5, "eta_max": 0.0},
        {"phi": 0.5, "packings": 1},
        {"phi": 0.5, "of": "window"},
    ],
)
def test_values_out_of_range_are_refused(given: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        TargetConfig(**given)


# ---------------------------------------------------------------------------
# the search, on made-up fractions of eta


def test_a_linear_fraction_is_met_by_the_secant_at_once() -> None:
    made: list[float] = []

    def probe(ctl: DensityController) -> float:
        made.append(_eta(ctl))
        return 0.85 - 0.003 * _eta(ctl)

    found = TargetController(TargetConfig(phi=0.70)).search(probe)
    assert made[:2] == [0.0, 100.0] and len(made) == 3
    assert found.met and found.chosen == 2 and found.tries[2]["eta"] == pytest.approx(50.0)


@given(
    target=st.floats(0.45, 0.84),
    noise=st.floats(0.0, 0.004),
    seed=st.integers(0, 2**31),
    tolerance=st.floats(0.001, 0.02),
)
@settings(max_examples=150, deadline=None)
def test_search_keeps_the_first_hit_or_the_closest(
    target: float, noise: float, seed: int, tolerance: float
) -> None:
    # a concave fall with noise of its own at every eta: the bracket holds by the values
    rng = np.random.default_rng(seed)

    def probe(ctl: DensityController) -> float:
        x = _eta(ctl) / 100.0
        return 0.85 - 0.4 * x * x + float(rng.uniform(-noise, noise)) * (0.0 < x < 1.0)

    cfg = TargetConfig(phi=target, tolerance=tolerance, packings=12)
    found = TargetController(cfg).search(probe)
    phis = [t["phi"] for t in found.tries]
    off = [abs(p - target) for p in phis]
    assert 1 <= len(phis) <= 12
    hits = [k for k, d in enumerate(off) if d <= tolerance]
    if found.met:
        assert hits == [len(phis) - 1] == [found.chosen]  # the search stops at its first hit
    else:
        assert not hits and len(phis) == 12
        assert found.chosen == off.index(min(off))
    assert all(0.0 <= t["eta"] <= 100.0 for t in found.tries)
    if noise <= tolerance / 4:  # a fall the noise hardly blurs is met within twelve
        assert found.met


def test_a_target_above_the_densest_is_refused_after_one_packing() -> None:
    made: list[float] = []

    def probe(ctl: DensityController) -> float:
        made.append(_eta(ctl))
        return 0.85 - 0.003 * _eta(ctl)

    with pytest.raises(FieldValueError) as err:
        TargetController(TargetConfig(porosity=0.10)).search(probe)
    assert made == [0.0]
    assert err.value.field == "density.porosity" and err.value.value == 0.10
    assert "above the densest this scene packs, 0.8500 at eta = 0" in str(err.value)


def test_a_target_below_the_loosest_is_refused_with_the_reachable_range() -> None:
    with pytest.raises(FieldValueError, match=r"the reachable range is 0\.5500 to 0\.8500"):
        TargetController(TargetConfig(void_ratio=2.0)).search(lambda c: 0.85 - 0.003 * _eta(c))


def test_within_the_tolerance_of_an_end_is_met_there() -> None:
    lo = TargetController(TargetConfig(phi=0.5515, tolerance=0.002))
    found = lo.search(lambda c: 0.85 - 0.003 * _eta(c))
    assert found.met and found.chosen == 1 and len(found.tries) == 2
    hi = TargetController(TargetConfig(phi=0.8515, tolerance=0.002))
    found = hi.search(lambda c: 0.85 - 0.003 * _eta(c))
    assert found.met and found.chosen == 0 and len(found.tries) == 1


def test_a_fraction_that_cannot_be_measured_is_refused() -> None:
    with pytest.raises(FieldValueError, match=r'set density\.of = "domain"'):
        TargetController(TargetConfig(phi=0.6)).search(lambda c: math.nan)


# ---------------------------------------------------------------------------
# whole runs


def _run(scene: str, overrides: list[str]) -> dict[str, Any]:
    loaded = load_scene(scene, [*overrides, "outputs.fabric=false"])
    resolved = resolve_scene(loaded, default_registry())
    return pack_and_summarise(resolved, verify=False).summary


@pytest.mark.parametrize("target", ["phi = 0.80", "porosity = 0.25", "void_ratio = 0.35"])
def test_three_targets_are_met_in_2d(target: str) -> None:
    summary = _run("small", [f"density={{kind = 'target', {target}}}"])
    block = summary["density_target"]
    assert block["met"] and block["tolerance"] == 0.002 and block["of"] == "interior"
    assert abs(summary["phi_interior"] - block["phi"]) <= 0.002
    assert summary["phi_interior"] == block["reached"] == block["tries"][-1]["phi"]
    assert summary["eta"] == block["tries"][-1]["eta"]
    # the packing kept is the one the chosen eta gives on its own, bit for bit
    again = _run("small", [f"density.eta={summary['eta']!r}"])
    assert again["phi_interior"] == summary["phi_interior"]
    assert again["placed"] == summary["placed"]


def test_the_chosen_eta_goes_with_the_packing_to_its_analyses() -> None:
    target = "density={kind = 'target', phi = 0.80}"
    summary = _run(
        "small", ["domain.width=120", "domain.height=120", target, "outputs.analyses=['density']"]
    )
    assert (
        summary["analyses"]["density"]["eta"] == summary["eta"] == summary["density_target"]["eta"]
    )


def test_results_of_a_sweep_hold_the_target_block() -> None:
    from regopack.experiments.results import _collect

    summary = _run(
        "small", ["domain.width=120", "domain.height=120", "density={kind = 'target', phi = 0.80}"]
    )
    row = _collect(summary, None)
    assert row["density_target.met"] is True and row["density_target.eta"] == summary["eta"]


def test_an_inserter_without_a_density_controller_refuses_a_target(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = ["run", "small", "--set", "insertion={kind = 'rsa'}", "--quiet"]
    argv += ["--set", "density={kind = 'target', phi = 0.5}"]
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        assert main(argv) == 2
    [line] = err.getvalue().splitlines()
    assert "density.kind" in line and "insertion 'rsa' places particles without one" in line


def test_a_target_is_met_in_3d() -> None:
    dims = ["domain.width=30", "domain.height=30", "domain.depth=30", "size.d_max=12"]
    summary = _run("dem3d", [*dims, "density={kind = 'target', phi = 0.40, tolerance = 0.005}"])
    block = summary["density_target"]
    assert block["met"] and abs(summary["phi_interior"] - 0.40) <= 0.005
    assert 0.0 < summary["eta"] < 100.0


def test_a_target_missed_keeps_the_closest_packing_and_warns() -> None:
    scene = "density={kind = 'target', porosity = 0.25, packings = 3}"
    with pytest.warns(DensityTargetWarning, match="not reached within the tolerance in 3"):
        summary = _run("small", ["domain.width=120", "domain.height=120", scene])
    block = summary["density_target"]
    off = [abs(t["phi"] - 0.75) for t in block["tries"]]
    assert not block["met"] and block["packings"] == 3
    assert summary["phi_interior"] == block["tries"][off.index(min(off))]["phi"]


def test_cli_refuses_an_unreachable_target_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    err, out = io.StringIO(), io.StringIO()
    argv = ["run", "small", "--set", "domain.width=100", "--set", "domain.height=100"]
    argv += ["--set", 'density={kind = "target", phi = 0.95}', "--quiet", "--out", "r"]
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        status = main(argv)
    lines = err.getvalue().splitlines()
    assert status == 2 and len(lines) == 1, lines
    assert lines[0].startswith("regopack: error: --set: density.phi = 0.95: phi interior 0.95 ")
    assert "above the densest this scene packs" in lines[0]
    assert not (tmp_path / "r").exists()


def test_cli_run_writes_the_target_block(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    argv = ["run", "small", "--set", "domain.width=120", "--set", "domain.height=120"]
    argv += ["--set", 'density={kind = "target", phi = 0.80}', "--quiet", "--out", "r"]
    with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
        assert main(argv) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["density_target"]["met"] and abs(summary["phi_interior"] - 0.80) <= 0.002


def test_a_steep_fall_is_met_in_few_packings() -> None:
    # all of the fall in the last tenth of the range: plain regula falsi creeps from one end;
    # halving the weight of the end it keeps (the Illinois step) reaches the target quickly
    def probe(ctl: DensityController) -> float:
        return 0.85 - 0.3 * (_eta(ctl) / 100.0) ** 12

    found = TargetController(TargetConfig(phi=0.80, tolerance=0.001, packings=12)).search(probe)
    assert found.met and len(found.tries) == 11  # plain regula falsi: 20 packings


HOWTO = Path(__file__).resolve().parents[3] / "docs" / "how-to" / "target-porosity.md"


@pytest.mark.parametrize("target", ["phi = 0.95", "porosity = 0.6"])
def test_the_howtos_refusals_are_what_the_cli_prints(
    target: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = ["run", "small", "--set", "domain.width=100", "--set", "domain.height=100"]
    argv += ["--set", f'density={{kind = "target", {target}}}', "--quiet"]
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        assert main(argv) == 2
    [line] = err.getvalue().splitlines()
    page = HOWTO.read_text(encoding="utf-8")
    assert line in page.splitlines()
    assert "regopack run small --set 'density={kind = \"target\", porosity = 0.25}'" in page
