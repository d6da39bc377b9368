"""Benchmark scripts stop on a mistake with one line, before they pack anything."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _refused(script: str, args: list[str]) -> tuple[subprocess.CompletedProcess[str], str]:
    """Run ``benchmarks/script`` on ``args``; it must stop with code 2 and no traceback.

    Returns the run and the last line of its standard error.
    """
    run = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / script), *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    return run, run.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--columns", "0"], "--columns must be 1 or more"),
        (["--size", "nan"], "--size and --ring-width must be positive"),
        (["--count", "-3"], "--count must be 0 or more"),
        (["--scene", "no-such-scene"], "no-such-scene: no such scene file"),
        (["--size", "inf"], "domain.width = inf"),
    ],
)
def test_study_homogeneity_refuses_bad_input_in_one_line(args: list[str], says: str) -> None:
    run, last = _refused("study_homogeneity.py", args)
    assert last.startswith("study_homogeneity.py: error:") and says in last, last
    assert "seed" not in run.stdout  # nothing packed


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--set", "novalue"], "expected key=value"),
        (["--set", "insertion.zone=-1"], "insertion.zone"),
        (["--scene", "no-such-scene"], "no-such-scene"),
    ],
)
def test_study_dem3d_refuses_bad_input_in_one_line(args: list[str], says: str) -> None:
    run, last = _refused("study_dem3d.py", args)
    assert last.startswith("study_dem3d.py: error:") and says in last, last
    assert run.stdout == ""  # nothing packed


@pytest.mark.parametrize("side", ["nan", "-5", "0", "inf"])
def test_bench_sphere_scale_refuses_a_bad_side_in_one_line(side: str) -> None:
    run, last = _refused("bench_sphere_scale.py", [side])
    assert last.startswith("bench_sphere_scale.py: error: side must be a positive length"), last
    assert run.stdout == ""  # nothing packed


def _peers() -> object:
    """``benchmarks/peers_yade.py`` as a module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "peers_yade", ROOT / "benchmarks" / "peers_yade.py"
    )
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_peers_yade_measures_spheres_from_arrays_with_the_package_oracle() -> None:
    import numpy as np

    from regopack.geometry.domain import Box

    peers = _peers()
    box = Box(0.0, 10.0, 0.0, 10.0, 0.0, 10.0)
    apart = peers.sphere_packing([[2, 2, 2], [6, 2, 2]], [1.0, 1.5], box)  # type: ignore[attr-defined]
    m = peers.measure(apart)  # type: ignore[attr-defined]
    solid = 4 / 3 * np.pi * (1.0 + 1.5**3)
    assert m["placed"] == 2 and m["overlaps"] == 0 and m["outside"] == 0
    assert m["phi_domain"] == pytest.approx(solid / 1000.0, rel=1e-9)
    bad = peers.sphere_packing([[2, 2, 2], [4.4, 2, 2], [9.5, 5, 5]], [1.0, 1.5, 1.0], box)  # type: ignore[attr-defined]
    m = peers.measure(bad)  # type: ignore[attr-defined]
    assert m["overlaps"] == 1 and m["outside"] == 1 and m["worst_overlap"] > 0


def test_peers_yade_hands_yade_metres_and_a_gas_of_the_same_radii() -> None:
    import numpy as np

    from regopack.geometry.domain import Box
    from regopack.verification.polyhedra import verify_spheres

    peers = _peers()
    radii = np.random.default_rng(3).uniform(1.0, 6.0, 200)
    cfg = peers.yade_config(radii, Box(-30, 30, -30, 30, -30, 30), 1, ["makeCloud"])  # type: ignore[attr-defined]
    assert cfg["lo"] == pytest.approx([-30e-6] * 3) and cfg["hi"] == pytest.approx([30e-6] * 3)
    assert cfg["radii"] == pytest.approx((radii * 1e-6).tolist(), rel=1e-15)
    assert cfg["psd_sizes"][0] == pytest.approx(2e-6 * radii.min())
    assert cfg["psd_sizes"][-1] == pytest.approx(2e-6 * radii.max())
    assert cfg["psd_cumm"][0] == 0.0 and cfg["psd_cumm"][-1] == 1.0
    assert cfg["r_mean"] * (1 - cfg["r_fuzz"]) == pytest.approx(1e-6 * radii.min())
    assert cfg["r_mean"] * (1 + cfg["r_fuzz"]) == pytest.approx(1e-6 * radii.max())
    cell, centres = np.asarray(cfg["cloud_cell"]), np.asarray(cfg["cloud"])
    assert np.prod(cell) * 0.25 == pytest.approx(np.sum(4 / 3 * np.pi * (radii * 1e-6) ** 3))
    assert np.all((centres >= 0) & (centres < cell))
    assert verify_spheres(centres, radii * 1e-6, [0, 0, 0], cell, periodic=True).ok


def test_peers_yade_runs_makecloud_in_yade_when_installed() -> None:
    import shutil

    import numpy as np

    from regopack.geometry.domain import Box
    from regopack.verification.polyhedra import verify_spheres

    if shutil.which("yade") is None:
        pytest.skip("YADE is not installed (Debian package yade)")
    peers = _peers()
    box = Box(0.0, 30.0, 0.0, 30.0, 0.0, 30.0)
    radii = np.random.default_rng(1).uniform(1.0, 3.0, 50)
    out, reason, _ = peers.run_yade(peers.yade_config(radii, box, 1, ["makeCloud"]), 60.0)  # type: ignore[attr-defined]
    assert out is not None, reason
    row = out["makeCloud"]
    assert row["psd_scaling"] == 1.0 and row["radii"].size > 10
    assert row["radii"].min() >= radii.min() * (1 - 1e-9)  # back in µm
    assert row["radii"].max() <= radii.max() * (1 + 1e-9)
    assert verify_spheres(row["centres"], row["radii"], [0, 0, 0], [30, 30, 30]).ok


def test_peers_yade_refuses_a_box_too_small_in_one_line() -> None:
    run = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "peers_yade.py"), "--side", "5"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert run.returncode == 2, run.stderr
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("peers_yade.py: error:") and "--side" in last, last
    assert "population" not in run.stdout  # nothing packed


def test_peers_yade_says_why_yade_is_skipped(monkeypatch: pytest.MonkeyPatch) -> None:
    import shutil

    peers = _peers()
    monkeypatch.setattr(shutil, "which", lambda name: None)
    out, reason, wall = peers.run_yade({}, 1.0)  # type: ignore[attr-defined]
    assert out is None and wall == 0.0 and "no `yade` on PATH" in reason
    assert peers._cell(None, ".3f") == "–" and peers._cell(0.12345, ".3f") == "0.123"  # type: ignore[attr-defined]


def test_peers_yade_says_when_yade_runs_out_of_time(monkeypatch: pytest.MonkeyPatch) -> None:
    import shutil

    peers = _peers()

    def late(cmd: list[str], **kw: object) -> None:
        raise subprocess.TimeoutExpired(cmd, 2.5)

    monkeypatch.setattr(shutil, "which", lambda name: "/usr/bin/yade")
    monkeypatch.setattr(subprocess, "run", late)
    out, reason, wall = peers.run_yade({"methods": []}, 2.5)  # type: ignore[attr-defined]
    assert out is None and wall == 2.5 and reason == "yade took longer than --timeout 2.5 s"
