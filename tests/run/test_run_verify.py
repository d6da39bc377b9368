"""Runs whose settings may overlap verify their packing; ``run --verify`` fails a violated one."""

from __future__ import annotations

import json

import pytest

from regopack.cli import main
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

TAU = ["count=150", 'insertion.interference="tau"', "insertion.tau=0.9"]


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


def test_the_tau_test_is_verified_and_its_overlaps_reported(registry):
    summary = run_scene(resolve_scene(load_scene("small", TAU), registry)).summary
    checked = summary["verify"]
    assert not checked["ok"] and checked["overlap_pairs"] > 0 and checked["worst_overlap"] > 0


def test_exact_runs_are_verified_only_when_asked(registry):
    scene = resolve_scene(load_scene("small", ["count=60"]), registry)
    assert "verify" not in run_scene(scene).summary
    assert run_scene(scene, verify=True).summary["verify"] == {
        "ok": True,
        "overlap_pairs": 0,
        "worst_overlap": 0.0,
        "outside": 0,
    }


def test_run_verify_exits_1_on_a_violated_packing(tmp_path, capsys):
    sets = [a for s in TAU for a in ("--set", s)]
    assert main(["run", "small", *sets, "--out", str(tmp_path / "a"), "--quiet"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("regopack: warning: the packing is violated")
    assert main(["run", "small", *sets, "--out", str(tmp_path / "b"), "--quiet", "--verify"]) == 1
    summary = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert summary["verify"]["ok"] is False
    ok = ["run", "small", "--set", "count=60", "--out", str(tmp_path / "c"), "--verify"]
    assert main(ok) == 0
